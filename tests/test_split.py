"""The split by finger, keyed on resolved folders; the split a run records, and what reads it back:
export's validation fingers (the recorded ones, checked against the data) and ``train --resume``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from procedural import write_dataset

pytest.importorskip("torch")
pytest.importorskip("kornia")

from test_train import tiny_config

from contactcal.infer.bench.dataset import IndexRow, read_datasets
from contactcal.train import loop
from contactcal.train.loop import train
from contactcal.train.split import (
    recorded_split,
    split_by_finger,
    split_record,
    validation_rows,
)


def _held(dirs: list[str | Path], seed: int = 0) -> list[IndexRow]:
    """The validation rows of ``dirs`` at val_fraction 0.25."""
    return split_by_finger(read_datasets(dirs), 0.25, seed)[1]


def _fingers(rows: list[IndexRow]) -> set[tuple[Path, int]]:
    """Each row's finger: (its folder resolved, its number), whatever the key's spelling."""
    return {(r.dataset.resolve(), r.finger) for r in rows}


def _pair(tmp_path: Path) -> tuple[Path, Path]:
    """Two datasets of two fingers, pa and pb."""
    return write_dataset(tmp_path / "pa", fingers=2), write_dataset(tmp_path / "pb", 2, seed=1)


def test_the_split_does_not_depend_on_how_a_folder_is_typed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`--data pa /abs/pb` sorted its fingers as typed (/abs/pb#0 before pa#0): another spelling
    of the same folders held out another finger."""
    monkeypatch.chdir(tmp_path)
    a, b = _pair(tmp_path)
    held = [_held(dirs) for dirs in (["pa", b], [a, "pb"], ["./pa/", "pb"], [a, b])]
    assert all(_fingers(h) == _fingers(held[0]) for h in held)
    keys = split_record([], held[0])["val"]
    assert len(keys) == 1 and keys[0].startswith(f"{tmp_path.resolve()}/p")  # resolved


def test_folders_typed_under_one_parent_split_as_before(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The validation fingers of `--data data/a data/b` as the split keyed on typed folders chose
    them (recorded data/a#10, ...; in string order, #10 before #8): resolving the folders puts
    the same prefix before every key, so existing runs split as before."""
    monkeypatch.chdir(tmp_path)
    write_dataset(tmp_path / "data" / "a", fingers=12)
    write_dataset(tmp_path / "data" / "b", fingers=3, seed=1)
    before = {  # computed by contactcal before the change
        0: ["a#10", "a#11", "a#8", "a#9"],
        1: ["a#1", "a#5", "a#8", "b#0"],
        2: ["a#4", "a#5", "a#7", "b#1"],
    }
    parent = (tmp_path / "data").resolve()
    for seed, held in before.items():
        keys = split_record([], _held(["data/a", "data/b"], seed))["val"]
        assert keys == [f"{parent}/{k}" for k in held], seed


def test_a_recorded_split_is_read_as_the_data_dirs_it_names() -> None:
    """New runs record resolved keys; older ones the folders as typed, each read as the one
    data_dirs entry whose path ends with it; a key naming none or two is refused."""
    path = Path("runs/r1/config.json")
    dirs = ["/w/data/a", "/w/data/b", "/w/other/data/a"]
    old = {"data_dirs": dirs[:2], "split": {"train": ["data/a#0", "../w/data/b#1"], "val": ["b#0"]}}
    assert recorded_split(old, path) == {
        "val": ["/w/data/b#0"],
        "train": ["/w/data/a#0", "/w/data/b#1"],
    }
    new = {"data_dirs": dirs, "split": {"train": ["/w/data/a#0"], "val": ["/w/other/data/a#2"]}}
    assert recorded_split(new, path) == new["split"]
    for key, names in (("data/a#0", "2 (/w/data/a, /w/other/data/a)"), ("c#1", "none")):
        unclear = {"data_dirs": dirs, "split": {"train": [], "val": [key]}}
        said = f"{path}: the split's key '{key}' names {names} of the run's data_dirs"
        with pytest.raises(ValueError, match=re.escape(said) + ".*expected each key to name"):
            recorded_split(unclear, path)
    with pytest.raises(ValueError, match=r"config\.json: expected split and data_dirs"):
        recorded_split({"data_dirs": dirs}, path)


def test_an_older_record_reads_as_its_folders_resolved(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """data_dirs recorded relative (runs before they were resolved) resolve from the working
    folder, as the frames are read; a key folder typed through a symlink, naming no entry, is
    paired with the one entry no key names (two such are refused)."""
    monkeypatch.chdir(tmp_path)
    path = Path("runs/r1/config.json")
    root = tmp_path.resolve()
    old = {"data_dirs": ["data/a", "data/b"], "split": {"train": ["data/a#0"], "val": ["b#1"]}}
    assert recorded_split(old, path) == {"val": [f"{root}/data/b#1"], "train": [f"{root}/data/a#0"]}
    linked = {"data_dirs": ["/w/a", "/w/b"], "split": {"train": ["/w/a#0"], "val": ["ln#1"]}}
    assert recorded_split(linked, path)["val"] == ["/w/b#1"]
    two = {"data_dirs": ["/w/a", "/w/b"], "split": {"train": ["ln2#0"], "val": ["ln#1"]}}
    with pytest.raises(ValueError, match="names none of the run's data_dirs.*through a symlink"):
        recorded_split(two, path)


def test_export_takes_the_validation_fingers_the_run_recorded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run of mixed spellings: the fingers export calibrates and checks on are the recorded
    validation fingers, also from a record of an older run (keys as typed); a record that the
    data contradicts is refused, naming config.json."""
    monkeypatch.chdir(tmp_path)
    b = _pair(tmp_path)[1]
    run = tmp_path / "run"
    summary = train(["pa", b], run, tiny_config(epochs=1), progress=False)
    info = json.loads((run / "config.json").read_text())
    val = validation_rows(run, info, 0.25, 0)
    assert sorted({r.finger_key for r in val}) == info["split"]["val"]
    assert len(val) == summary["val_frames"]
    prefix = f"{tmp_path.resolve()}/"
    typed = {side: [k.removeprefix(prefix) for k in keys] for side, keys in info["split"].items()}
    assert validation_rows(run, {**info, "split": typed}, 0.25, 0) == val
    relative = {**info, "data_dirs": ["pa", "pb"], "split": typed}  # before e0f48ea
    assert [r.finger_key for r in validation_rows(run, relative, 0.25, 0)] == [
        r.finger_key for r in val
    ]
    other = {"val": info["split"]["train"][:1], "train": info["split"]["train"][1:] + typed["val"]}
    said = f"{run / 'config.json'}: the split recomputed from data_dirs (val_fraction 0.25, seed 0)"
    with pytest.raises(ValueError, match=re.escape(said) + ": its validation fingers differ"):
        validation_rows(run, {**info, "split": other}, 0.25, 0)


def test_resume_keeps_the_split_and_refuses_another(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """--resume under other spellings of the run's folders keeps its split (it swapped the
    validation finger mid-run); data that would split otherwise than the record is refused."""
    monkeypatch.chdir(tmp_path)
    a, b = _pair(tmp_path)
    run, cfg = tmp_path / "run", tiny_config(epochs=2)

    class Stop(Exception):
        pass

    def stop(*args: object) -> None:  # after the first epoch's checkpoint
        raise Stop

    monkeypatch.setattr(loop, "plot_curves", stop)
    with pytest.raises(Stop):
        train(["pa", b], run, cfg, progress=False)
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)
    recorded = (run / "config.json").read_text()
    split = json.loads(recorded)["split"]
    other = {"val": split["train"][:1], "train": split["train"][1:] + split["val"]}
    (run / "config.json").write_text(json.dumps({**json.loads(recorded), "split": other}))
    said = f"{run}: the split of this --resume's --data: its validation fingers differ"
    fix = f"pass --data {a.resolve()} {b.resolve()}"
    with pytest.raises(ValueError, match=re.escape(said) + ".*" + re.escape(fix)):
        train([a, "pb"], run, cfg, resume=True, progress=False)
    (run / "config.json").write_text(recorded)
    assert train([a, "pb"], run, cfg, resume=True, progress=False)["epochs_run"] == 1
    again = json.loads((run / "config.json").read_text())["split"]
    assert again == split and again["val"][0].startswith(f"{tmp_path.resolve()}/p")


def test_data_rendered_otherwise_is_refused_by_export_and_resume(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same frames' rows (index.csv) rendered otherwise (the folder's config.json: another
    spp) pass the index digest; the run's render_digest refuses them at export and --resume. A run
    recorded before render_digest (none in its config.json) is not compared."""
    from contactcal.train.export import load_run

    monkeypatch.chdir(tmp_path)
    a, b = _pair(tmp_path)
    (a / "config.json").write_text(json.dumps({"render": {"spp": 16}}))
    run, cfg = tmp_path / "run", tiny_config(epochs=1)
    train([a, b], run, cfg, progress=False)
    load_run(run)  # the data as trained: accepted
    (a / "config.json").write_text(json.dumps({"render": {"spp": 4}}))
    with pytest.raises(ValueError, match=r"config\.json: the run's dataset folders .* rendered "):
        load_run(run)
    (run / "val_bins.csv").unlink()  # killed after its last checkpoint: --resume would finish it
    with pytest.raises(ValueError, match=r"--resume with data rendered otherwise"):
        train([a, b], run, cfg, resume=True, progress=False)
    info = json.loads((run / "config.json").read_text())
    del info["render_digest"]
    (run / "config.json").write_text(json.dumps(info))
    load_run(run)

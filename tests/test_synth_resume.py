"""``contactcal synth`` into an existing folder: damaged files, a changed config, a folder of
other files, the run record of interrupted and resumed runs. The folders are written by hand:
nothing is rendered."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("mitsuba")

from contactcal.infer.cli import main
from contactcal.infer.errors import config_changes
from contactcal.synth.dataset import DatasetConfig, build_dataset
from contactcal.synth.dataset_finger import render_finger
from contactcal.synth.dataset_folder import check_config_matches, check_out_folder
from contactcal.synth.layout import frame_name
from contactcal.synth.run_record import ShardRuns, read_runs
from contactcal.synth.session import RenderConfig
from contactcal.synth.shard_lock import lock_path, shard_lock
from contactcal.synth.variant import choose_variant

CONFIG = DatasetConfig(
    fingers=1, pressures_kpa=(0.0, 6.0), seed=5, render=RenderConfig(width=48, height=36, spp=1)
)
#: The command line of CONFIG (add --out).
ARGV = ["synth", "--fingers", "1", "--pressures", "0,6", "--size", "48x36", "--spp", "1"]
ARGV += ["--seed", "5", "--quiet"]


def _finished(root: Path, config: DatasetConfig = CONFIG) -> Path:
    """``root`` as a finished run of ``config`` leaves it: config.json and every frame record."""
    variant = choose_variant(config.render.variant)
    root.mkdir()
    render = dataclasses.replace(config.render, variant=variant)
    check_config_matches(root, dataclasses.replace(config, render=render))
    _write_frames(root, config, range(config.fingers))
    return root


def _write_frames(root: Path, config: DatasetConfig, fingers: range | list[int]) -> int:
    """Write the missing frame records of ``fingers`` as a render would; returns how many."""
    made = 0
    for f in fingers:
        frames = root / f"finger_{f:04d}" / "frames"
        frames.mkdir(parents=True, exist_ok=True)
        for p in config.pressures_kpa:
            path = frames / f"{frame_name(p)}.json"
            if not path.exists():
                truth = {"finger": f, "pressure_kpa": p, "contact": int(p > 0), "mm_per_px": 0.1}
                path.write_text(json.dumps(truth))
                made += 1
    return made


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    return err


def test_a_damaged_config_json_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = _finished(tmp_path / "ds")
    (root / "config.json").write_text("{\n")
    assert main([*ARGV, "--out", str(root)]) == 2
    err = _one_line(capsys)
    assert f"{root / 'config.json'}: not valid JSON (Expecting property name" in err
    assert "expected the config a `contactcal synth` run wrote; render into a new --out" in err


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("{\n", "not valid JSON (Expecting property name"),
        ("[]", "holds no JSON object"),
        ('{"finger": 1}', "has no pressure_kpa, contact, mm_per_px"),
        (
            '{"finger": 1, "pressure_kpa": 6, "contact": 1, "mm_per_px": 0.1, "colour": 1}',
            "has keys no frame record has (colour)",
        ),
        (
            '{"finger": 1, "pressure_kpa": "6", "contact": 1, "mm_per_px": 0.1}',
            "pressure_kpa is '6', not a number",
        ),
    ],
)
def test_a_damaged_frame_record_is_named_before_any_render(
    tmp_path: Path, text: str, said: str
) -> None:
    """Any shard's frame (index.csv reads them all), before the run renders anything."""
    config = dataclasses.replace(CONFIG, fingers=2)
    root = _finished(tmp_path / "ds", config)
    damaged = root / "finger_0001" / "frames" / "p06.0kpa.json"
    damaged.write_text(text)
    (root / "finger_0000" / "frames" / "p06.0kpa.json").unlink()  # shard 0's frame to render
    with pytest.raises(ValueError) as exc:
        build_dataset(root, config, shard=(0, 2), progress=False)
    msg = str(exc.value)
    assert msg.startswith(f"{damaged}: {said}") and "expected a frame record a `contactcal" in msg
    assert msg.endswith(REMEDY)
    assert not (root / "finger_0000" / "manifest.csv").exists(), "nothing rendered or written"
    with pytest.raises(ValueError, match=re.escape(str(damaged))):
        render_finger(str(root), config, 1)  # the resume of one finger reads it too


#: The end of every refusal of a frame record.
REMEDY = (
    "expected a frame record a `contactcal synth` run wrote; remove it and run the same synth "
    "command, which renders that frame again"
)


@pytest.mark.parametrize(
    ("held", "said"),
    [
        ("a FIFO", "not a regular file (a device, pipe or socket)"),
        ("a folder", "is a folder"),
        ("unreadable", "cannot be read (Permission denied)"),
    ],
)
def test_a_frame_record_that_is_no_file_or_unreadable_says_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch, held: str, said: str
) -> None:
    """A FIFO was refused as "(this one is damaged)", and a permission error was printed as its
    errno text alone, without what to do."""
    from contactcal.infer.files import regular

    root = _finished(tmp_path / "ds")
    record = root / "finger_0000" / "frames" / "p06.0kpa.json"
    record.unlink()
    if held == "a FIFO":
        os.mkfifo(record)
    elif held == "a folder":
        record.mkdir()
    else:
        record.write_text("{}")
        read = regular.read_input_json

        def denied(path: Path, *args: object) -> bytes:
            if path == record:
                raise PermissionError(13, "Permission denied", str(path))
            return read(path, *args)

        monkeypatch.setattr(regular, "read_input_json", denied)
    assert main([*ARGV, "--out", str(root)]) == 2
    err = _one_line(capsys)
    assert err.startswith(f"contactcal: error: {record}: {said}; {REMEDY}"), err
    assert "damaged" not in err and "Errno" not in err


def test_a_changed_config_names_what_changed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = _finished(tmp_path / "ds")
    assert main([*ARGV, "--spp", "4", "--hard-fraction", "0.5", "--out", str(root)]) == 2
    err = _one_line(capsys)
    assert "different config (hard_fraction: 0.25 → 0.5; render.spp: 1 → 4); use a new" in err
    old = {"a": 1, "b": 2, "c": 3, "d": 4, "e": 5, "render": {"f": [0.0, 1.0]}}
    new = {"a": 0, "b": 0, "c": 0, "d": 0, "render": {"f": [0.0] * 20}}
    changes = config_changes(old, new)
    assert changes.startswith("a: 1 → 0; b: 2 → 0; c: 3 → 0; d: 4 → 0; and 2 more")
    assert config_changes({"e": 5}, {"render": {"f": [0.0] * 20}}) == (
        "e: 5 → (none); render.f: (none) → [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0…"
    )


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def test_an_out_of_other_files_or_inside_a_dataset_is_refused(tmp_path: Path) -> None:
    junk = tmp_path / "junk"
    junk.mkdir()
    (junk / "a.txt").write_text("x")
    with pytest.raises(ValueError, match=r"junk: holds other files \(a.txt\) and no config.json"):
        build_dataset(junk, CONFIG, progress=False)
    assert [p.name for p in junk.iterdir()] == ["a.txt"], "nothing written into it"
    killed = tmp_path / "killed"  # killed while staging config.json: taken, as an empty folder
    (killed / f".config.json.{_dead_pid()}.abc123.tmp").mkdir(parents=True)
    (killed / f".config.json.{os.getpid()}.def456.tmp").mkdir()  # another shard writing it
    check_out_folder(killed)
    root = _finished(tmp_path / "ds")
    check_out_folder(root)  # a dataset: resumed
    for inside in (root / "finger_0000", root / "new", root / "finger_0000" / "new"):
        where = re.escape(f"inside the synth dataset {root.resolve()} (its config.json")
        with pytest.raises(ValueError, match=where):
            build_dataset(inside, CONFIG, progress=False)
        assert inside.name == "finger_0000" or not inside.exists()


def test_a_rerun_of_a_finished_shard_keeps_its_run_record(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = _finished(tmp_path / "ds")
    record = root / "run_shard0of1.json"
    record.write_text(json.dumps({"args": {"workers": 2}, "fingers": 1, "frames_rendered": 2}))
    before = record.read_bytes()
    assert main([*ARGV, "--out", str(root)]) == 0
    assert record.read_bytes() == before, "the record of the run that rendered the frames"
    assert "every frame was there; run_shard0of1.json kept" in capsys.readouterr().out
    record.unlink()  # none yet: this run's is written
    assert main([*ARGV, "--out", str(root)]) == 0
    assert json.loads(record.read_text())["frames_rendered"] == 0


def test_run_records_add_up(tmp_path: Path) -> None:
    path = tmp_path / "run_shard0of1.json"
    first = ShardRuns.begin(path, {"run": 1}, 1, (0, 2))
    assert json.loads(path.read_text())["finished"] is None, "on record before the renders"
    assert first.end(2, 2)
    assert not ShardRuns.begin(path, {"run": 2}, 1, (2, 2)).end(0, 2), "a finished shard: kept"
    second = ShardRuns.begin(path, {"run": 3}, 1, (1, 2))  # a resume of a damaged one
    assert second.end(1, 2)
    record = json.loads(path.read_text())
    assert [r["args"] for r in record["earlier_runs"]] == [{"run": 1}]
    assert (record["frames_at_start"], record["frames_rendered"], record["frames_at_end"]) == (
        1,
        1,
        2,
    )
    assert read_runs(path, 2) == ([*record.pop("earlier_runs"), record], True)
    path.write_text("{")
    with pytest.raises(ValueError, match=r"run_shard0of1.json: not valid JSON .*run record"):
        read_runs(path, 2)
    path.write_text(json.dumps({"finished": None}))
    with pytest.raises(ValueError, match=r"run_shard0of1.json: its unfinished run has no frames_"):
        read_runs(path, 2)


def test_interrupted_runs_stay_on_the_record(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each run that rendered frames is on the record, an interrupted one too (its start, no
    end), and their frames add up to the shard's rows in index.csv."""
    root = tmp_path / "ds"
    argv = [*ARGV, "--fingers", "3", "--out", str(root)]
    plans: list[int | None] = [1, 3, None]  # the fingers each run writes; a number: interrupted

    def fake_render(root: Path, config: DatasetConfig, fingers: list[int], *_: object) -> int:
        plan = plans.pop(0)
        made = _write_frames(root, config, fingers[:plan])
        if plan is not None:
            raise KeyboardInterrupt
        return made

    monkeypatch.setattr("contactcal.synth.dataset._render_fingers", fake_render)
    assert main(argv) == 130  # finger 0 written, then interrupted
    assert main(argv) == 130  # fingers 1 and 2 written, interrupted before the run's end
    assert main(argv) == 0  # a resume with nothing left to render
    record = json.loads((root / "run_shard0of1.json").read_text())
    runs = [*record.pop("earlier_runs"), record]
    counts = [(r["frames_at_start"], r["frames_rendered"], r["frames_at_end"]) for r in runs]
    assert counts == [(0, 2, 2), (2, 4, 6), (6, 0, 6)]
    assert [r["finished"] is None for r in runs] == [True, True, False]
    assert all(r["started"] and r["args"]["argv"] == argv for r in runs)
    rows = (root / "index.csv").read_text().splitlines()[1:]
    assert len(rows) == record["frames_at_end"] == sum(r["frames_rendered"] for r in runs)


def test_a_shard_another_run_renders_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A run of a shard that another run holds is refused at once (exit 2, one line naming the
    folder, the shard and the holder's pid); another shard runs alongside; the lock is removed
    at the end, and the file a killed run left blocks nothing."""
    root = _finished(tmp_path / "ds", dataclasses.replace(CONFIG, fingers=2))
    argv = [*ARGV, "--fingers", "2", "--out", str(root)]
    with shard_lock(root, (0, 2)):  # as a run of shard 0/2 holds it
        assert main([*argv, "--shard", "0/2"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1, err
        assert f"--out {root}: shard 0/2 is being rendered by another run (pid {os.getpid()}" in err
        assert not (root / "run_shard0of2.json").exists()  # refused before its record
        assert main([*argv, "--shard", "1/2"]) == 0
        assert (root / "run_shard1of2.json").is_file()
    assert main([*argv, "--shard", "0/2"]) == 0
    lock = lock_path(root, (0, 2))
    assert not lock.exists() and not lock_path(root, (1, 2)).exists()
    lock.write_text("999999999\n")  # a killed run's: nothing holds it
    assert main([*argv, "--shard", "0/2"]) == 0
    assert f"{lock} of an ended run (pid 999999999) taken over" in capsys.readouterr().err
    assert not lock.exists()

"""What ``contactcal train`` does with an ``--out`` that exists: a new run goes only into a new or
empty folder, ``--resume`` continues only a run that holds ``last.pt``; any other folder (a user's
files, a finished run whose last.pt was deleted) is refused before any work, nothing changed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from procedural import write_dataset
from test_outputs import one_line_naming

pytest.importorskip("torch")
pytest.importorskip("kornia")

from contactcal.infer.cli import main

TINY = ["--epochs", "1", "--input-size", "32", "--batch-size", "4", "--base", "4", "--quiet"]


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_train_never_writes_over_a_folder_it_would_not_continue(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d = write_dataset(tmp_path / "d", fingers=3)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    done = tmp_path / "done"  # a finished run whose last.pt was deleted to save space
    done.mkdir()
    (done / "config.json").write_text(json.dumps({"train": {}, "data_dirs": [str(d)]}))
    for name in ("best.pt", "metrics.csv", "curves.png", "val_bins.csv"):
        (done / name).write_bytes(b"the run's")
    (tmp_path / "file").write_text("a file")
    expected = "expected an empty or new folder, or --resume on an unfinished run"
    resume = "nothing to --resume (no last.pt; the folder"
    cases = [
        (
            mine,
            [],
            f"holds notes.txt, which a new run would mix its files with or write over; {expected}",
        ),
        (done, [], "holds best.pt, config.json, curves.png and 2 more, which a new run would mix"),
        (done, ["--resume"], f"{resume} holds best.pt, config.json, curves.png and 2 more)"),
        (tmp_path / "new", ["--resume"], f"{resume} does not exist)"),
        (tmp_path / "file", [], "not a folder; expected a run folder"),
    ]
    before = _snapshot(tmp_path)
    for out, extra, said in cases:
        assert main(["train", "--data", str(d), "--out", str(out), *TINY, *extra]) == 2, said
        err = capsys.readouterr().err
        one_line_naming(err, out)
        assert said in err, (said, err)
    assert _snapshot(tmp_path) == before and not (tmp_path / "new").exists()
    # an empty folder (a killed write's staged temporary aside) takes a new run
    empty = tmp_path / "empty"
    (empty / ".last.pt.999999999.x.tmp").mkdir(parents=True)
    assert main(["train", "--data", str(d), "--out", str(empty), *TINY]) == 0
    assert (empty / "last.pt").is_file() and (empty / "config.json").is_file()

"""What ``contactcal train`` does with an ``--out`` that exists: a new run goes only into a new or
empty folder, ``--resume`` continues only a run that holds ``last.pt``; any other folder (a user's
files, a finished run whose last.pt was deleted) is refused before any work, nothing changed. The
best.pt alone of a run killed in its first epoch takes a new run; a finished run is left as it
is by --resume."""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
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
        (tmp_path / "file" / "run", [], f"{tmp_path / 'file'}: is not a folder; cannot write"),
    ]
    before = _snapshot(tmp_path)
    for out, extra, said in cases:
        assert main(["train", "--data", str(d), "--out", str(out), *TINY, *extra]) == 2, said
        err = capsys.readouterr().err
        one_line_naming(err, out)
        assert err.startswith(f"contactcal: error: --out {out}: ") and said in err, (said, err)
    assert _snapshot(tmp_path) == before and not (tmp_path / "new").exists()
    # an empty folder (a killed write's staged temporary aside) takes a new run
    empty = tmp_path / "empty"
    (empty / ".last.pt.999999999.x.tmp").mkdir(parents=True)
    assert main(["train", "--data", str(d), "--out", str(empty), *TINY]) == 0
    assert (empty / "last.pt").is_file() and (empty / "config.json").is_file()


@pytest.mark.parametrize("resume", [False, True])
def test_train_refuses_an_out_before_it_loads_torch(tmp_path: Path, resume: bool) -> None:
    """The refusal is the argument check's: torch (seconds to import) is not loaded for it."""
    d = write_dataset(tmp_path / "d", fingers=3)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    argv = ["train", "--data", str(d), "--out", str(mine), *TINY, *(["--resume"] * resume)]
    code = (
        "import sys\n"
        "from contactcal.infer.cli import main\n"
        f"status = main({argv!r})\n"
        "print(status, 'torch' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["2", "False"], out
    one_line_naming(out.stderr, mine)
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]


def test_a_lone_best_pt_is_refused_both_ways_and_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Killed after its first best.pt, before its first last.pt, a run leaves best.pt alone; so
    does someone keeping a finished run's checkpoint. Neither --resume nor a new run touches it
    (a new run once removed it, a kept checkpoint too): both say how to go on."""
    from contactcal.train import loop

    d = write_dataset(tmp_path / "d", fingers=3)
    run = tmp_path / "run"
    save = loop.save_checkpoint

    def killed_at_last(path: Path, payload: dict) -> None:
        if Path(path).name == "last.pt":
            raise KeyboardInterrupt
        save(path, payload)

    monkeypatch.setattr(loop, "save_checkpoint", killed_at_last)
    assert main(["train", "--data", str(d), "--out", str(run), *TINY]) == 130
    monkeypatch.undo()
    assert sorted(p.name for p in run.iterdir()) == ["best.pt"]
    capsys.readouterr()
    before = _snapshot(run)
    for resume in (["--resume"], []):
        assert main(["train", "--data", str(d), "--out", str(run), *TINY, *resume]) == 2
        err = capsys.readouterr().err
        one_line_naming(err, run)
        assert "holds only best.pt, with no last.pt to --resume" in err
        assert f"remove {run / 'best.pt'} and start the run again" in err
        assert _snapshot(run) == before


def test_resume_leaves_a_finished_run_as_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A finished run (val_bins.csv written) is not resumed: said so, every file unchanged. A
    run killed after its last last.pt, before the files that follow, is completed. The --data
    that a resume with other data is told to pass is quoted for a shell (a space in a name)."""
    d = write_dataset(tmp_path / "my data", fingers=3)
    run = tmp_path / "run"
    argv = ["train", "--data", str(d), "--out", str(run), *TINY]
    assert main(argv) == 0
    capsys.readouterr()
    before = _snapshot(run)
    stats = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in run.iterdir()}
    assert main([*argv, "--resume"]) == 0
    said = capsys.readouterr().out
    one_line_naming(said, run)
    assert "the run is finished (best epoch 1; it holds val_bins.csv" in said
    assert "nothing to --resume, its files left as they are" in said and _snapshot(run) == before
    assert {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in run.iterdir()} == stats
    # finished or not, --resume with another config is refused (it cannot extend a run)
    assert main([*argv, "--resume", "--epochs", "3"]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, run)
    assert "--resume with a different config (epochs: 1 → 3); expected the run's own" in err
    other = write_dataset(tmp_path / "other", fingers=3, seed=1)  # other data, same config
    assert main(["train", "--data", str(other), "--out", str(run), *TINY, "--resume"]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, run)
    said = f"expected the run's own dataset folders, unchanged: pass --data {shlex.quote(str(d))}"
    assert said in err
    assert _snapshot(run) == before
    recorded = (run / "config.json").read_text()
    for damaged in ({"data_dirs": None}, {"data_dirs": [1]}):  # named, not a traceback
        (run / "config.json").write_text(json.dumps({**json.loads(recorded), **damaged}))
        assert main(["train", "--data", str(other), "--out", str(run), *TINY, "--resume"]) == 2
        err = capsys.readouterr().err
        one_line_naming(err, run / "config.json")
        assert "expected split and data_dirs as `contactcal train` records them" in err
    (run / "config.json").write_text(recorded)
    # killed right after its last epoch's last.pt (a 1-epoch run: config.json not yet written)
    for name in ("config.json", "metrics.csv", "curves.png", "val_bins.csv"):
        (run / name).unlink()
    before_resume = _snapshot(run)  # no config.json to take the saved settings from
    assert main(["train", "--data", str(d), "--out", str(run), "--quiet", "--resume"]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, run)
    assert "(batch_size: 4 → 16; epochs: 1 → 40; input_size: 32 → 256; " in err
    assert "more" not in err and "expected the run's own settings: give them as options" in err
    assert _snapshot(run) == before_resume
    assert main([*argv, "--resume"]) == 0
    after = _snapshot(run)
    assert set(after) == set(before) and after["metrics.csv"] == before["metrics.csv"]
    assert after["val_bins.csv"] == before["val_bins.csv"]


def test_an_out_reached_through_a_linked_folder_is_a_folder_like_any(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An empty run folder inside a linked folder is written into (the files go into the run
    folder, not through a link); an --out that is itself a link is refused before any work."""
    d = write_dataset(tmp_path / "d", fingers=3)
    (tmp_path / "real" / "r").mkdir(parents=True)
    try:
        (tmp_path / "lnk").symlink_to(tmp_path / "real", target_is_directory=True)
    except OSError:
        pytest.skip("no symbolic links here")
    assert main(["train", "--data", str(d), "--out", str(tmp_path / "lnk" / "r"), *TINY]) == 0
    assert (tmp_path / "real" / "r" / "last.pt").is_file()
    capsys.readouterr()
    assert main(["train", "--data", str(d), "--out", str(tmp_path / "lnk"), *TINY]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"contactcal: error: --out {tmp_path / 'lnk'}: ") and "link" in err
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == ["r"]


def test_the_epoch_rows_are_progress_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Standard output holds the run's one summary line: the epoch rows go with the progress
    bars to stderr, so `train ... | head -1` no longer stops a run after its first epoch."""
    d = write_dataset(tmp_path / "d", fingers=3)
    argv = ["train", "--data", str(d), "--out", str(tmp_path / "r"), *TINY[:-1], "--epochs", "2"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert out.count("\n") == 1 and out.startswith(f"{tmp_path / 'r'}: best epoch")
    assert "epoch 1  train_loss=" in err and "epoch 2  train_loss=" in err


@pytest.mark.parametrize("kind", ["folder", "pipe", "dangling link"])
def test_a_resume_refuses_a_config_json_that_is_not_a_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    """A config.json that is a folder, a pipe or a link to nothing was taken for none: a resume
    of a real run said it "was stopped before its config.json ... was written" and asked for
    every setting. A finished run's (an unfinished one's is refused as a file the run replaces:
    the test below)."""
    if kind == "pipe" and not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    d = write_dataset(tmp_path / "d", fingers=3)
    run, config = tmp_path / "run", tmp_path / "run" / "config.json"
    run.mkdir()
    (run / "last.pt").write_bytes(b"")  # never loaded: the config is read first
    (run / "val_bins.csv").write_text("")  # finished
    if kind == "dangling link":
        config.symlink_to(tmp_path / "moved.json")
    else:
        config.mkdir() if kind == "folder" else os.mkfifo(config)
    assert main(["train", "--data", str(d), "--out", str(run), "--quiet", "--resume"]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, config)
    says = {
        "folder": "is a folder",
        "pipe": "not a regular file (a device, pipe or socket)",
        "dangling link": f"a link to {tmp_path / 'moved.json'}, which does not exist",
    }[kind]
    assert f"{config}: {says}; expected the config.json a `contactcal train` run wrote" in err


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("config.json", "dangling link"),
        ("metrics.csv", "link"),
        ("best.pt", "link"),
        ("curves.png", "folder"),
    ],
)
def test_a_resume_refuses_a_run_file_that_is_a_link_or_folder_before_an_epoch(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, kind: str
) -> None:
    """An unfinished run's file that the resume replaces, a link or a folder, was refused only
    when written, after an epoch (last.pt replaced by then); a config.json linked to a missing
    file was moreover taken for none (a run stopped before its config.json was written)."""
    d = write_dataset(tmp_path / "d", fingers=3)
    run, path = tmp_path / "run", tmp_path / "run" / name
    run.mkdir()
    (run / "last.pt").write_bytes(b"")  # never loaded: refused before
    if kind == "folder":
        path.mkdir()
    else:
        target = tmp_path / "elsewhere"
        if kind == "link":
            target.write_text("")
        path.symlink_to(target)
    before = _snapshot(tmp_path)
    assert main(["train", "--data", str(d), "--out", str(run), "--quiet", "--resume"]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, path)
    says = "is a symbolic link" if kind != "folder" else "exists and is not a regular file"
    assert f"--out {run}: {path}: {says}" in err
    assert _snapshot(tmp_path) == before

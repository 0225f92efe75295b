"""Outputs: never replacing inputs, links or devices; all or nothing; no stale temporaries."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from contactcal.infer.cli import main
from contactcal.infer.files.atomic import atomic_path, run_outputs, write_json
from contactcal.infer.files.destination import OutputError
from contactcal.infer.files.temporaries import TEMP_NAME, remove_stale_temporaries
from contactcal.infer.image.write import write_image
from contactcal.infer.pipeline.overlay import overlay_names

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_refuses_an_input(tmp_path: Path) -> None:
    frame = tmp_path / "p00.json"
    frame.write_text("input")
    other_spelling = tmp_path / "sub" / ".." / "p00.json"
    (tmp_path / "sub").mkdir()
    for dest in (frame, other_spelling):
        with pytest.raises(OutputError, match="is an input of this run"):
            with atomic_path(dest, protect=[frame]) as tmp:
                tmp.write_text("output")
    hard = tmp_path / "hard.json"
    os.link(frame, hard)  # another name of the same file
    with pytest.raises(OutputError, match=r"hard\.json: is an input"):
        with run_outputs([frame]) as outs:
            outs.stage(hard)
    assert frame.read_text() == "input"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hard.json", "p00.json", "sub"]


def test_refuses_links_and_non_regular_files(tmp_path: Path) -> None:
    target = tmp_path / "target.json"
    target.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    for dest, why in ((link, "symbolic link"), (fifo, "not a regular file"), (folder, "regular")):
        with pytest.raises(OutputError, match=why) as info:
            write_json(dest, [1])
        assert str(dest) in str(info.value) and "\n" not in str(info.value)
    assert link.is_symlink() and target.read_text() == "keep"
    assert fifo.is_fifo() and folder.is_dir() and list(folder.iterdir()) == []


def test_run_is_all_or_nothing(tmp_path: Path) -> None:
    old = tmp_path / "a.json"
    write_json(old, ["old"])
    before = old.read_bytes()
    new_folder = tmp_path / "new" / "deeper"
    with pytest.raises(RuntimeError, match="midway"):
        with run_outputs() as outs:
            outs.stage(old).write_text("new")
            (outs.stage(new_folder / "b.txt")).write_text("b")
            raise RuntimeError("midway")
    assert old.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]  # no temporaries, no "new"
    with run_outputs() as outs:
        outs.stage(old).write_text("new")
        outs.stage(new_folder / "b.txt").write_text("b")
    assert old.read_text() == "new" and (new_folder / "b.txt").read_text() == "b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "new"]


def test_unwritten_or_twice_staged_output_fails(tmp_path: Path) -> None:
    with pytest.raises(OSError, match="produced no file"):
        with run_outputs() as outs:
            outs.stage(tmp_path / "never.png")
    with pytest.raises(OutputError, match="written twice"):
        with run_outputs() as outs:
            outs.stage(tmp_path / "x.png")
            outs.stage(tmp_path / "." / "x.png")
    assert list(tmp_path.iterdir()) == []


def test_stale_temporaries_of_dead_processes_are_removed(tmp_path: Path) -> None:
    dead, live = _dead_pid(), os.getpid()
    stale_file = tmp_path / f".r.json.{dead}.abc123_x.tmp"
    stale_file.write_bytes(b"")  # what kill -9 leaves
    stale_dir = tmp_path / f".curve.png.{dead}.zz9.tmp"
    stale_dir.mkdir()
    (stale_dir / "curve.png").write_bytes(b"half")
    running = tmp_path / f".r.json.{live}.def456.tmp"
    running.write_bytes(b"")
    unrelated = tmp_path / ".notes.tmp"
    unrelated.write_text("mine")
    write_json(tmp_path / "r.json", [1])
    assert not stale_file.exists() and not stale_dir.exists()
    assert running.exists() and unrelated.exists()
    assert remove_stale_temporaries(tmp_path) == []


def test_temporaries_are_named_with_the_pid(tmp_path: Path) -> None:
    with atomic_path(tmp_path / "r.json") as tmp:
        match = TEMP_NAME.match(tmp.parent.name)
        assert match is not None and int(match["pid"]) == os.getpid()
        assert tmp.parent.name.startswith(".r.json.") and tmp.name == "r.json"
        tmp.write_text("[]")


def test_overlay_names_are_distinct_and_deterministic() -> None:
    files = ["s/p1.jpg", "a/x.jpg", "b/x.jpg", "b/x.png", "c/X.tif", "a/x.jpg"]
    names = overlay_names(files)
    assert names == [
        "p1_overlay.png",
        "a_x_jpg_2_overlay.png",
        "b_x_jpg_overlay.png",
        "x_png_overlay.png",
        "X_tif_overlay.png",
        "a_x_jpg_6_overlay.png",
    ]
    assert len({n.casefold() for n in names}) == len(names)
    assert overlay_names(files) == names
    assert overlay_names(["x.jpg", "x.png"]) == ["x_jpg_overlay.png", "x_png_overlay.png"]


def copy_session(tmp_path: Path, names: tuple[str, ...] = ("p00.0kpa.jpg", "p12.0kpa.jpg")) -> Path:
    """A copy of some example frames (with manifest and rig) in ``tmp_path/s``."""
    s = tmp_path / "s"
    s.mkdir()
    for name in (*names, "rig.json"):
        shutil.copy(EXAMPLE / name, s / name)
    rows = "".join(f"{n},{float(n[1:5])}\n" for n in names)
    (s / "manifest.csv").write_text("file,pressure_kpa\n" + rows)
    return s


def one_line_naming(err: str, path: Path) -> None:
    assert len(err.strip().splitlines()) == 1 and str(path) in err, err


def test_measure_never_replaces_inputs_links_or_devices(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    s = copy_session(tmp_path)
    frames = sorted(s.glob("*.jpg"))
    before = {p: p.read_bytes() for p in s.iterdir()}
    # `--out s/*.jpg`: the shell makes the 0 kPa frame the output; `--out x.png x.png`.
    for argv in ([str(frames[0]), str(frames[1])], [str(frames[1]), str(frames[1])]):
        assert main(["measure", "--method", "classical", "--out", *argv]) == 2
        one_line_naming(capsys.readouterr().err, Path(argv[0]))
    monkeypatch.chdir(tmp_path)
    rig = Path("s/rig.json")  # an input that is no image, named as given (relative)
    assert main(["measure", "--rig", str(rig), "--out", str(rig), str(frames[1])]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, rig)
    assert f"error: --out {rig}: is an input of this run ({rig})" in err, err
    link = tmp_path / "link.json"
    link.symlink_to(s / "manifest.csv")
    fifo = tmp_path / "fifo.json"  # named .json: refused as a pipe, not by its name
    os.mkfifo(fifo)
    for out, why in ((link, "is a symbolic link"), (fifo, "exists and is not a regular file")):
        assert main(["measure", "--method", "classical", "--out", str(out), str(frames[1])]) == 2
        err = capsys.readouterr().err
        one_line_naming(err, out)
        assert f"error: --out {out}: {why}" in err, err
        # a link is refused with measure's other way out; a fifo, no link, without it
        assert ("or --out - for standard output" in err) == (out == link), err
    assert {p: p.read_bytes() for p in s.iterdir()} == before
    assert link.is_symlink() and fifo.is_fifo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo.json", "link.json", "s"]


def test_measure_out_dash_writes_stdout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    frame = str(EXAMPLE / "p12.0kpa.jpg")
    assert (
        main(["measure", "--method", "classical", "--device-id", "D-7", "--out", "-", frame]) == 0
    )
    out = capsys.readouterr()
    rows = json.loads(out.out)
    assert [r["file"] for r in rows] == [frame] and rows[0]["device_id"] == "D-7"
    assert "contact=" in out.err and list(tmp_path.iterdir()) == []


def test_measure_overlays_one_per_input(tmp_path: Path) -> None:
    for folder, suffix in (("a", ".jpg"), ("b", ".jpg"), ("b", ".png")):
        (tmp_path / folder).mkdir(exist_ok=True)
        img = cv2.imread(str(EXAMPLE / "p12.0kpa.jpg"))
        cv2.imwrite(str(tmp_path / folder / f"x{suffix}"), img)
    files = [str(tmp_path / f) for f in ("a/x.jpg", "b/x.jpg", "b/x.png")]
    ov = tmp_path / "ov"
    out = tmp_path / "r.json"
    assert (
        main(["measure", "--method", "classical", "--overlay", str(ov), "--out", str(out), *files])
        == 0
    )
    assert sorted(p.name for p in ov.iterdir()) == [
        "a_x_jpg_overlay.png",
        "b_x_jpg_overlay.png",
        "x_png_overlay.png",
    ]


def test_overlay_rerun_names_the_earlier_overlays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    s = copy_session(tmp_path, ("p00.0kpa.jpg", "p08.0kpa.jpg", "p16.0kpa.jpg"))
    ov = tmp_path / "ov"
    argv = ["measure", "--method", "classical", "--overlay", str(ov), "--out"]
    assert (
        main([*argv, str(tmp_path / "1.json"), str(s / "p08.0kpa.jpg"), str(s / "p16.0kpa.jpg")])
        == 0
    )
    assert "earlier run" not in capsys.readouterr().out
    assert main([*argv, str(tmp_path / "2.json"), str(s / "p08.0kpa.jpg")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith(f"note: {ov} also holds 1 overlay(s) this run did not write")
    assert "(p16.0kpa_overlay.png)" in out[-1]
    assert (ov / "p16.0kpa_overlay.png").exists()  # kept: nothing is deleted


def test_earlier_overlays_note_is_case_blind(tmp_path: Path) -> None:
    from contactcal.infer.pipeline.overlay import earlier_overlays_note

    for name in ("A_overlay.png", "b_overlay.png", "odd\nname_overlay.png"):
        (tmp_path / name).write_bytes(b"png")
    (tmp_path / "dir_overlay.png").mkdir()
    note = earlier_overlays_note([tmp_path / "a_overlay.png", tmp_path / "B_overlay.png"])
    assert note is not None and "holds 1 overlay(s)" in note
    assert "'odd\\nname_overlay.png'" in note and "\n" not in note
    (tmp_path / "odd\nname_overlay.png").unlink()
    assert earlier_overlays_note([tmp_path / "a_overlay.png", tmp_path / "B_overlay.png"]) is None


def test_calibrate_is_all_or_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    s = copy_session(tmp_path, ("p00.0kpa.jpg", "p08.0kpa.jpg", "p16.0kpa.jpg"))
    cal = tmp_path / "cal"
    manifest = str(s / "manifest.csv")
    assert main(["calibrate", manifest, "--method", "classical", "--out", str(cal)]) == 0
    before = {p.name: p.read_bytes() for p in cal.iterdir()}
    argv = ["calibrate", manifest, "--out", str(cal)]  # the U-Net: a different record
    (tmp_path / "file").write_text("a regular file")
    unwritable = tmp_path / "file" / "ov"  # its parent is a regular file (tests run as root)
    assert main([*argv, "--overlay", str(unwritable)]) == 2
    one_line_naming(capsys.readouterr().err, tmp_path / "file")
    assert {p.name: p.read_bytes() for p in cal.iterdir()} == before
    fresh = tmp_path / "fresh"
    assert main([*argv[:-1], str(fresh), "--overlay", str(unwritable)]) == 2
    assert not fresh.exists()

    from contactcal.infer.pipeline import overlay

    calls: list[Path] = []

    def fails_midway(path: Path, image: object) -> Path:
        calls.append(path)
        if len(calls) == 2:
            raise OSError(f"{path}: disk full")
        return write_image(path, image)

    monkeypatch.setattr(overlay, "write_image", fails_midway)
    ov = tmp_path / "ov"
    assert main([*argv, "--overlay", str(ov)]) == 2
    assert len(calls) == 2 and not ov.exists()
    assert {p.name: p.read_bytes() for p in cal.iterdir()} == before
    out = tmp_path / "r.json"
    calls.clear()
    frames = [str(p) for p in sorted(s.glob("*.jpg"))]
    assert main(["measure", "--overlay", str(ov), "--out", str(out), *frames]) == 2
    assert not out.exists() and not ov.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cal", "file", "s"]


def test_a_full_disk_names_the_output_folder(tmp_path: Path) -> None:
    """A write that finds no room raises errno 28 without a file name: the error then names the
    folder the run was writing into, and the run leaves nothing there."""
    import errno

    def full(path: Path) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    out = tmp_path / "out"
    with pytest.raises(OSError) as caught:
        with run_outputs() as outs:
            full(outs.stage(out / "a.json"))
    assert caught.value.errno == errno.ENOSPC and "[Errno" not in str(caught.value)
    assert str(caught.value) == (
        f"{out}: No space left on device while writing this run's outputs there"
    )
    assert not out.exists()
    with pytest.raises(OSError, match=r"^\[Errno 2\]"):  # another error is left as it is
        with run_outputs() as outs:
            outs.stage(out / "b.json")
            raise FileNotFoundError(errno.ENOENT, "No such file or directory")

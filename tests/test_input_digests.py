"""The sha256 digests a record keeps (``calibration.json``, ``evaluation.json`` ``inputs``) are of
the content the run parsed and measured: a file replaced after the run read it is recorded as it
was measured, never as it was read again afterwards; and a run opens each frame once (every
step uses the content read)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from test_outputs import EXAMPLE, copy_session

from contactcal.infer.cli import main
from contactcal.infer.image import read
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL
from contactcal.infer.pipeline import manifest

NAMES = ("p00.0kpa.jpg", "p04.0kpa.jpg", "p08.0kpa.jpg", "p12.0kpa.jpg", "p16.0kpa.jpg")


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


_OPENS: list[Counter[str]] = []  # the counter of the test counting (empty: none counts)


def _count_open(event: str, args: tuple[Any, ...]) -> None:
    """Audit hook: every ``open`` of a named file by Python (``Path.read_bytes``, ``open``, a
    JPEG header's read), counted by file name while a test counts."""
    if event == "open" and _OPENS and isinstance(args[0], str | os.PathLike):
        _OPENS[-1][Path(args[0]).name] += 1


sys.addaudithook(_count_open)  # an audit hook stays for the process: it counts only in _OPENS


@contextmanager
def _counting() -> Iterator[Counter[str]]:
    """How many times each file (by name) is opened in the block (a block within it counts
    apart: the test's own reads and writes are left out so)."""
    _OPENS.append(Counter())
    try:
        yield _OPENS[-1]
    finally:
        _OPENS.pop()


def _replaced_after_reading(
    monkeypatch: pytest.MonkeyPatch, names: set[str]
) -> dict[str, list[bytes]]:
    """Every read of a frame (``read_file_bytes``) or of the manifest (``read_rows``) named in
    ``names`` replaces that file right after it (other bytes, still a valid file): a digest
    taken by reading it again differs from the one of the content read. Returns each file's
    content as each read got it."""
    got: dict[str, list[bytes]] = {}

    def replacing(original: Callable[..., Any]) -> Callable[..., Any]:
        def wrapped(path: Path, *args: Any) -> Any:
            p = Path(path)
            with _counting():
                before = p.read_bytes()
            out = original(path, *args)
            if p.name in names:
                got.setdefault(p.name, []).append(before)
                with _counting():  # after a JPEG's end marker, or a blank CSV line
                    p.write_bytes(before + b"\n")
            return out

        return wrapped

    monkeypatch.setattr(read, "read_file_bytes", replacing(read.read_file_bytes))
    monkeypatch.setattr(manifest, "read_rows", replacing(manifest.read_rows))
    return got


@pytest.mark.parametrize("method", ["unet", "classical"])
def test_calibration_records_the_digests_of_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, method: str
) -> None:
    s = copy_session(tmp_path, NAMES)
    got = _replaced_after_reading(monkeypatch, {*NAMES, "manifest.csv"})
    out = tmp_path / "out"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", method, "--out", str(out)]
    with _counting() as opened:
        assert main(argv) == 0
    inputs = json.loads((out / "calibration.json").read_text(encoding="utf-8"))["inputs"]
    # each file read once (the reference too: its decode for the method is the one measured,
    # and the U-Net's choice of decode takes its size from that content)
    assert {name: len(reads) for name, reads in got.items()} == dict.fromkeys(got, 1)
    assert opened[NAMES[0]] == 1
    assert inputs["manifest"]["sha256"] == _sha(got["manifest.csv"][0])
    assert {e["file"]: e["sha256"] for e in inputs["frames"]} == {
        name: _sha(got[name][0]) for name in NAMES
    }


def test_classical_overlays_record_the_model_drawing_the_unet_outlines(tmp_path: Path) -> None:
    """``--method classical --overlay DIR --model M``: the overlays draw M's outlines, so the
    record names M with the sha256 of the content loaded (it was in ``argv`` only), read once."""
    s = copy_session(tmp_path, NAMES[:3])
    model = tmp_path / "m.onnx"
    shutil.copy(DEFAULT_MODEL, model)
    out, overlays = tmp_path / "out", tmp_path / "ov"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical", "--model", str(model)]
    with _counting() as opened:
        assert main([*argv, "--overlay", str(overlays), "--out", str(out)]) == 0
    assert opened["m.onnx"] == 1
    extra = json.loads((out / "calibration.json").read_text(encoding="utf-8"))["extra"]
    unet = extra["overlay_methods"]["unet"]
    assert (unet["model"], unet["model_sha256"]) == (str(model.resolve()), _sha(model.read_bytes()))


def _labelled_session(tmp_path: Path) -> tuple[Path, Path]:
    """A copy of some example frames and their label masks: (manifest, masks folder)."""
    s = copy_session(tmp_path, NAMES)
    (s / "masks").mkdir()
    for name in NAMES:
        stem = Path(name).stem
        shutil.copy(EXAMPLE / "masks" / f"{stem}.png", s / "masks" / f"{stem}.png")
    return s / "manifest.csv", s / "masks"


def test_evaluation_opens_each_frame_once_and_records_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    manifest_csv, masks = _labelled_session(tmp_path)
    got = _replaced_after_reading(monkeypatch, {*NAMES, "manifest.csv"})  # the reference too
    out = tmp_path / "out"
    argv = ["evaluate", str(manifest_csv), "--labels", str(masks), "--method", "both"]
    with _counting() as opened:
        assert main([*argv, "--out", str(out)]) == 0
    # the labels' checks (the reference's window ring, each frame's size), both methods'
    # measurements and the record all use the one content read
    assert {name: opened[name] for name in NAMES} == dict.fromkeys(NAMES, 1)
    inputs = json.loads((out / "evaluation.json").read_text(encoding="utf-8"))["inputs"]
    assert inputs["manifest"]["sha256"] == _sha(got["manifest.csv"][0])
    assert inputs["reference"]["sha256"] == _sha(got[NAMES[0]][0])
    recorded = {e["file"]: e["sha256"] for e in inputs["frames"]}
    assert recorded == {n: _sha(got[n][0]) for n in NAMES}


def test_demo_opens_each_frame_once_and_its_methods_record_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``demo`` measures one content with both methods: each frame (and the manifest) is read
    once, though replaced after that read; both records name that content's sha256, and the
    montage is drawn on it (it was read once per method and again for the montage, which
    refused the frame replaced in between, and records could name two contents silently)."""
    s = copy_session(tmp_path, NAMES)
    got = _replaced_after_reading(monkeypatch, {*NAMES, "manifest.csv"})
    out = tmp_path / "demo"
    with _counting() as opened:
        assert main(["demo", "--manifest", str(s / "manifest.csv"), "--out", str(out)]) == 0
    assert {name: opened[name] for name in (*NAMES, "manifest.csv")} == dict.fromkeys(
        (*NAMES, "manifest.csv"), 1
    )
    assert (out / "overlay_montage.png").stat().st_size > 0
    for method in METHODS:
        record = json.loads((out / method / "calibration.json").read_text(encoding="utf-8"))
        inputs = record["inputs"]
        assert inputs["manifest"]["sha256"] == _sha(got["manifest.csv"][0])
        recorded = {e["file"]: e["sha256"] for e in inputs["frames"]}
        assert recorded == {n: _sha(got[n][0]) for n in NAMES}, method


def _overlay_run(command: str, s: Path, out: Path) -> list[str]:
    """The command line of ``command`` drawing overlays of session ``s`` into ``out``."""
    manifest_csv = str(s / "manifest.csv")
    if command == "measure":
        frames = [str(s / n) for n in NAMES[1:]]
        ref = ["--reference", str(s / NAMES[0])]
        return [
            "measure",
            *frames,
            *ref,
            "--overlay",
            str(out / "ov"),
            "--out",
            str(out / "r.json"),
        ]
    if command == "calibrate":
        return ["calibrate", manifest_csv, "--overlay", str(out / "ov"), "--out", str(out / "cal")]
    return ["demo", "--manifest", manifest_csv, "--out", str(out / "demo")]


@pytest.mark.parametrize("command", ["measure", "calibrate"])
def test_overlays_open_each_frame_once_and_draw_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, command: str
) -> None:
    """``--overlay`` measures one content with both methods and draws on it: each frame (and
    ``measure``'s reference) is read once, though replaced after that read, and ``calibrate``'s
    record names that content's sha256 (each frame was read for the measurement, again for the
    other method's outlines and again to draw on, and the frame replaced in between stopped the
    run)."""
    s = copy_session(tmp_path, NAMES)
    out = tmp_path / "out"
    out.mkdir()
    got = _replaced_after_reading(monkeypatch, set(NAMES))  # each read gets other content
    with _counting() as opened:
        assert main(_overlay_run(command, s, out)) == 0
    assert {name: opened[name] for name in NAMES} == dict.fromkeys(NAMES, 1)
    drawn = NAMES if command == "calibrate" else NAMES[1:]
    assert len(list((out / "ov").glob("*_overlay.png"))) == len(drawn)
    if command == "calibrate":
        inputs = json.loads((out / "cal" / "calibration.json").read_text(encoding="utf-8"))
        recorded = {e["file"]: e["sha256"] for e in inputs["inputs"]["frames"]}
        assert recorded == {n: _sha(got[n][0]) for n in NAMES}


def test_measure_without_overlay_reads_each_frame_as_it_is_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without ``--overlay`` nothing is held: each frame is read when it is measured (after
    the frame before it was decoded), not all read up front."""
    s = copy_session(tmp_path, NAMES)
    events: list[str] = []

    def logged(original: Callable[..., Any], what: str) -> Callable[..., Any]:
        def wrapped(first: Any, *args: Any, **kwargs: Any) -> Any:
            events.append(f"{what} {Path(getattr(first, 'path', first)).name}")
            return original(first, *args, **kwargs)

        return wrapped

    monkeypatch.setattr(read, "read_file_bytes", logged(read.read_file_bytes, "read"))
    monkeypatch.setattr(read.ImageFile, "decode", logged(read.ImageFile.decode, "decode"))
    argv = ["measure", *(str(s / n) for n in NAMES[1:]), "--reference", str(s / NAMES[0])]
    assert main([*argv, "--method", "classical", "--out", str(tmp_path / "r.json")]) == 0
    frames = [e for e in events if e.split()[1] in NAMES[1:]]
    assert frames == [f"{what} {n}" for n in NAMES[1:] for what in ("read", "decode")], events


@pytest.mark.parametrize("command", ["measure", "calibrate", "demo"])
def test_overlays_of_unchanged_frames_are_drawn(tmp_path: Path, command: str) -> None:
    s = copy_session(tmp_path, NAMES)
    out = tmp_path / "out"
    out.mkdir()
    assert main(_overlay_run(command, s, out)) == 0
    assert sorted(out.rglob("*overlay*.png"))


@pytest.mark.parametrize("command", ["calibrate", "evaluate"])
def test_mm_per_px_reads_the_manifest_once(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    command: str,
) -> None:
    """``--mm-per-px`` against the scale of the ``rig.json`` beside the manifest compares them
    at the frames' width: the manifest read for it is the run's one read, passed on (two reads
    could see two versions of it)."""
    manifest_csv, masks = _labelled_session(tmp_path)
    got = _replaced_after_reading(monkeypatch, {"manifest.csv"})
    out = tmp_path / "out"
    argv = [command, str(manifest_csv), "--method", "classical", "--mm-per-px", "0.2"]
    argv += ["--labels", str(masks)] if command == "evaluate" else []
    assert main([*argv, "--out", str(out)]) == 0
    assert "note: --mm-per-px 0.2 used in place of the scale of" in capsys.readouterr().out
    assert len(got["manifest.csv"]) == 1
    record = json.loads((out / f"{command[:-1]}ion.json").read_text(encoding="utf-8"))
    assert record["inputs"]["manifest"]["sha256"] == _sha(got["manifest.csv"][0])


def test_measure_overlay_tells_a_copy_of_the_reference_from_the_contents_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``measure --overlay --reference X COPY``: the note that COPY is the reference's bytes
    (the change gate cannot show contact there) is of the contents measured, so each file is
    still read once (both were read again to compare them)."""
    s = copy_session(tmp_path, ("p12.0kpa.jpg",))  # in contact: only the gate says no contact
    shutil.copy(s / "p12.0kpa.jpg", s / "copy.jpg")
    argv = ["measure", str(s / "copy.jpg"), "--reference", str(s / "p12.0kpa.jpg")]
    argv += ["--overlay", str(tmp_path / "ov"), "--out", str(tmp_path / "r.json")]
    with _counting() as opened:
        assert main(argv) == 0
    assert (opened["copy.jpg"], opened["p12.0kpa.jpg"]) == (1, 1), opened
    assert f"warning: {s / 'copy.jpg'}: this file is the reference frame itself (same bytes)" in (
        capsys.readouterr().err
    )

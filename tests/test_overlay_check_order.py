"""A run that holds its frames' contents (``measure --overlay``, ``calibrate --overlay``,
``demo``) refuses what a run without ``--overlay`` refuses before reading a frame, first: the
manifest's sweep in bar, an unusable ``--model``, a boundary offset measured for another model,
and ``measure``'s ``--reference`` before the frames. Reading every frame first let a damaged
frame hide those errors (and each was reported only after all the frames were read)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from test_outputs import copy_session

from contactcal.infer.cli import main

NAMES = ("p00.0kpa.jpg", "p04.0kpa.jpg", "p08.0kpa.jpg", "p12.0kpa.jpg")
DAMAGED = b"not an image"


def _first_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """The one error line ``argv`` exits 2 with."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


def _in_bar(s: Path) -> Path:
    """Session ``s``'s manifest with its pressures in bar (0.12 at the top): refused."""
    rows = "".join(f"{n},{float(n[1:5]) / 100:g}\n" for n in NAMES)
    (s / "manifest.csv").write_text("file,pressure_kpa\n" + rows)
    return s / "manifest.csv"


@pytest.mark.parametrize("overlay", [False, True])
def test_calibrate_refuses_a_sweep_in_bar_before_a_damaged_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], overlay: bool
) -> None:
    s = copy_session(tmp_path, NAMES)
    manifest = _in_bar(s)
    (s / NAMES[2]).write_bytes(DAMAGED)
    argv = ["calibrate", str(manifest), "--out", str(tmp_path / "cal")]
    argv += ["--overlay", str(tmp_path / "ov")] if overlay else []
    err = _first_error(argv, capsys)
    assert f"{manifest}: the highest pressure_kpa is 0.12" in err, err


def test_demo_refuses_a_sweep_in_bar_before_a_damaged_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    s = copy_session(tmp_path, NAMES)
    manifest = _in_bar(s)
    (s / NAMES[2]).write_bytes(DAMAGED)
    err = _first_error(["demo", "--manifest", str(manifest), "--out", str(tmp_path / "d")], capsys)
    assert f"{manifest}: the highest pressure_kpa is 0.12" in err, err


@pytest.mark.parametrize("overlay", [False, True])
def test_calibrate_refuses_an_unusable_model_before_a_damaged_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], overlay: bool
) -> None:
    s = copy_session(tmp_path, NAMES)
    (s / NAMES[2]).write_bytes(DAMAGED)
    model = tmp_path / "m.onnx"
    model.write_bytes(b"not a model")
    argv = ["calibrate", str(s / "manifest.csv"), "--model", str(model)]
    argv += ["--out", str(tmp_path / "cal")]
    argv += ["--overlay", str(tmp_path / "ov")] if overlay else []
    err = _first_error(argv, capsys)
    assert f"{model}: not a loadable ONNX model" in err, err


@pytest.mark.parametrize("overlay", [False, True])
def test_measure_refuses_a_damaged_reference_before_a_damaged_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], overlay: bool
) -> None:
    s = copy_session(tmp_path, NAMES)
    (s / NAMES[0]).write_bytes(DAMAGED)
    (s / NAMES[1]).write_bytes(DAMAGED)
    argv = ["measure", *(str(s / n) for n in NAMES[1:]), "--reference", str(s / NAMES[0])]
    argv += ["--out", str(tmp_path / "r.json")]
    argv += ["--overlay", str(tmp_path / "ov")] if overlay else []
    err = _first_error(argv, capsys)
    assert f"{s / NAMES[0]}: not a JPEG file" in err, err


@pytest.mark.parametrize("overlay", [False, True])
def test_calibrate_refuses_a_stale_boundary_offset_before_a_damaged_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], overlay: bool
) -> None:
    s = copy_session(tmp_path, NAMES)
    (s / NAMES[2]).write_bytes(DAMAGED)
    rig = json.loads((s / "rig.json").read_text())
    stale = {"boundary_offset_mm": 0.2, "boundary_offset_model_sha256": "a" * 64}
    (s / "rig.json").write_text(json.dumps(rig | stale))
    argv = ["calibrate", str(s / "manifest.csv"), "--out", str(tmp_path / "cal")]
    argv += ["--overlay", str(tmp_path / "ov")] if overlay else []
    err = _first_error(argv, capsys)
    assert f"{s / 'rig.json'}: its boundary offset was measured for the model" in err, err

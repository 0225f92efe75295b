"""One run's measuring options, built once from the command line and passed whole."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from contactcal.infer.cli import build_parser
from contactcal.infer.pipeline.args import measure_options, read_rig
from contactcal.infer.pipeline.options import MeasureOptions

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def _args(*argv: str) -> argparse.Namespace:
    return build_parser(argv[0]).parse_args(list(argv))


def test_defaults_are_the_command_lines() -> None:
    args = _args("calibrate", str(EXAMPLE / "manifest.csv"), "--out", "x")
    got = measure_options(args, read_rig(args))  # no rig.json named or looked for
    assert got == MeasureOptions()


def test_every_option_reaches_the_config(tmp_path: Path) -> None:
    args = _args(
        "calibrate",
        str(EXAMPLE / "manifest.csv"),
        "--out",
        "x",
        "--threads",
        "2",
        "--no-change-gate",
        "--bit-depth",
        "12",
        "--mm-per-px",
        "0.02",
        "--overlay",
        str(tmp_path / "ov"),
        "--model",
        "m.onnx",
    )
    got = measure_options(args, read_rig(args))
    assert (got.threads, got.change_gate, got.bit_depth, got.outline) == (2, False, 12, True)
    assert got.scale is not None and got.scale.mm_per_px == pytest.approx(0.02)
    assert got.boundary is None and str(got.model) == "m.onnx"


def test_the_rig_json_beside_the_manifest_gives_scale_and_offset(tmp_path: Path) -> None:
    rig = tmp_path / "rig.json"
    rig.write_text(
        json.dumps(
            {"mm_per_px": 0.03, "image_width_px": 400, "boundary_offset_mm": 0.1, **_digest()}
        )
    )
    args = _args("evaluate", str(tmp_path / "manifest.csv"), "--labels", "l", "--out", "x")
    got = measure_options(args, read_rig(args, rig))
    assert got.scale is not None and got.scale.mm_per_px == pytest.approx(0.03)
    assert got.boundary is not None and got.boundary.mm == pytest.approx(0.1)
    assert (got.threads, got.outline) == (1, False)  # evaluate has neither option


def _rig_json(path: Path, mm_per_px: float, width: int, **offset: object) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"mm_per_px": mm_per_px, "image_width_px": width, **offset}))
    return path


def test_an_option_setting_aside_the_rig_json_beside_the_manifest_is_said(tmp_path: Path) -> None:
    """``--rig`` leaves the ``rig.json`` beside the manifest unread, ``--mm-per-px`` replaces its
    scale: one note names both sources and values, none where they state the same."""
    from contactcal.infer.pipeline.rig_note import rig_note

    beside = _rig_json(tmp_path / "s" / "rig.json", 0.05, 400)
    manifest = str(tmp_path / "s" / "manifest.csv")

    def note(*option: str, width: int | None = None) -> str | None:
        args = _args("calibrate", manifest, "--out", "x", *option)

        def width_px() -> int:
            assert width is not None, "the frames' width is read only for --mm-per-px"
            return width

        read = read_rig(args, beside)
        return rig_note(args, measure_options(args, read), beside, read, width_px)

    other = _rig_json(tmp_path / "other.json", 0.06, 400)
    assert note("--rig", str(other)) == (
        f"note: --rig {other} used (0.06 mm/px at 400 px wide); {beside} beside the manifest "
        "(0.05 mm/px at 400 px wide) was not read"
    )
    same = _rig_json(tmp_path / "same.json", 0.1, 200)  # the same scale at every width
    assert note("--rig", str(same)) is None
    assert note("--rig", str(tmp_path / "s" / ".." / "s" / "rig.json")) is None  # that file
    assert note() is None
    offset = _rig_json(tmp_path / "offset.json", 0.1, 200, boundary_offset_mm=0.1, **_digest())
    assert f"(0.1 mm/px at 200 px wide, boundary offset +0.100 mm); {beside}" in str(
        note("--rig", str(offset))
    )
    assert "(0.05 mm/px at 400 px wide, boundary offset none) was not read" in str(
        note("--rig", str(offset))
    )
    beside.write_text("[1, 2]")  # not read, so not refused: said
    assert f"{beside} beside the manifest (not a valid rig config) was not read" in str(
        note("--rig", str(other))
    )
    _rig_json(beside, 0.05, 400)
    assert note("--mm-per-px", "0.07", width=400) == (
        f"note: --mm-per-px 0.07 used in place of the scale of {beside} (0.05 mm/px at 400 px wide)"
    )
    assert note("--mm-per-px", "0.1", width=200) is None  # the rig's scale at the frames' width
    assert note("--mm-per-px", "0.05", width=200) is not None  # its number, at another width
    _rig_json(beside, 0.05, 400, boundary_offset_mm=0.1, **_digest())
    assert str(note("--mm-per-px", "0.07", width=400)).endswith(
        "(0.05 mm/px at 400 px wide); its boundary offset still applies"
    )
    beside.write_text(json.dumps({"boundary_offset_mm": 0.1, **_digest()}))
    assert note("--mm-per-px", "0.07") is None  # no scale replaced: only its offset, applied
    beside.unlink()
    assert note("--rig", str(other)) is None and note("--mm-per-px", "0.07") is None


def test_calibrate_says_and_records_the_rig_json_its_rig_option_left_unread(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from contactcal.infer.cli import main

    session = tmp_path / "s"
    frames = sorted(EXAMPLE.glob("p*.jpg"))[::4]
    session.mkdir()
    rows = "".join(f"{f},{float(f.stem[1:5]):g}\n" for f in frames)
    (session / "manifest.csv").write_text("file,pressure_kpa\n" + rows)
    beside = _rig_json(session / "rig.json", 0.05, 400)
    other = _rig_json(tmp_path / "other.json", 0.06, 400)
    argv = ["calibrate", str(session / "manifest.csv"), "--rig", str(other), "--method"]
    assert main([*argv, "classical", "--out", str(tmp_path / "c")]) == 0
    expected = (
        f"note: --rig {other} used (0.06 mm/px at 400 px wide); {beside} beside the manifest "
        "(0.05 mm/px at 400 px wide) was not read"
    )
    assert capsys.readouterr().out.splitlines().count(expected) == 1
    record = json.loads((tmp_path / "c" / "calibration.json").read_text())
    assert record["extra"]["rig_note"] == expected and record["extra"]["mm_per_px"] == 0.06


def test_threads_reach_onnxruntime() -> None:
    """``calibrate --threads`` sets onnxruntime's threads too (it was 1 whatever was asked)."""
    method = MeasureOptions(threads=2).method("unet")
    opts = method.segmenter.ort_session.get_session_options()
    assert opts.intra_op_num_threads == 2
    assert MeasureOptions().method("unet").segmenter.ort_session.get_session_options() is not None


def test_outline_override_and_bad_name() -> None:
    assert MeasureOptions().method("classical", outline=True).name == "classical"
    with pytest.raises(ValueError, match="unknown method"):
        MeasureOptions().method("nope")


def _digest() -> dict[str, str]:
    return {"boundary_offset_model_sha256": "0" * 64}  # checked only when applied

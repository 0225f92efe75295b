"""One run's measuring options, built once from the command line and passed whole."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from contactcal.infer.cli import build_parser
from contactcal.infer.pipeline.args import measure_options
from contactcal.infer.pipeline.options import MeasureOptions

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def _args(*argv: str) -> argparse.Namespace:
    return build_parser(argv[0]).parse_args(list(argv))


def test_defaults_are_the_command_lines() -> None:
    args = _args("calibrate", str(EXAMPLE / "manifest.csv"), "--out", "x")
    got = measure_options(args)  # no rig.json named or looked for
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
    got = measure_options(args)
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
    got = measure_options(args, rig)
    assert got.scale is not None and got.scale.mm_per_px == pytest.approx(0.03)
    assert got.boundary is not None and got.boundary.mm == pytest.approx(0.1)
    assert (got.threads, got.outline) == (1, False)  # evaluate has neither option


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

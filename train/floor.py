"""Set an exported model's dark floor (metadata ``preprocess.norm_floor_percentile`` only).

The floor ``F``, a low percentile of the crop, is subtracted before the division by the bright
level ``P`` (``u = (g − F) / (P − F)``; :mod:`contactcal.infer.methods.unet.prepare`), which
makes the input invariant to a camera's black level and contrast. The weights are not touched:
whether a model trained without a floor takes it is for validation renders to say (``contactcal
bench --data VALIDATION --model NEW.onnx --robustness``), never the benchmark's held-out sets.

A new floor changes every network input, so the entries calibrated on the old inputs are kept
but stale: the interval, and the change gate (``min_change``, in network input units: the floor
scales the frame-reference difference by ``P / (P − F)``) when the model has one. The summary's
``stale`` says so and what to rerun (:func:`contactcal.train.restate.stale`).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.parser import Parser
from contactcal.train.restate import (
    check_paths,
    load_proto,
    metadata_of,
    run_restating,
    save_restated,
    stale,
)


def floor_model(
    model: str | os.PathLike[str], percentile: float, out: str | os.PathLike[str]
) -> dict[str, Any]:
    """Write ``model`` with ``norm_floor_percentile = percentile`` to ``out``.

    Args:
        model: an exported ``.onnx`` model.
        percentile: the floor's percentile, % (0 = no floor; below the bright percentile).
        out: the new ``.onnx`` file; must not be ``model`` (inputs are never overwritten).

    Returns:
        ``{"norm_floor_percentile": new, "before": old, "stale": …}``: ``stale`` names the
        calibrated entries the change left stale and what to rerun, None when the floor is
        unchanged.

    Raises:
        ValueError: bad output name, or a percentile outside ``[0, norm_percentile)`` (the
            message names ``--percentile``).
    """

    from contactcal.infer.methods.unet.spec import read_spec

    src, dst = check_paths(model, out)
    proto = load_proto(src)
    spec = read_spec(metadata_of(proto), src)
    try:
        pre = dataclasses.replace(spec.preprocess, norm_floor_percentile=percentile)
    except ValueError as exc:
        raise ValueError(f"--percentile {percentile:g}: {exc}") from None
    new = dataclasses.replace(spec, preprocess=pre)
    save_restated(proto, {"preprocess": new.to_metadata()["preprocess"]}, new, dst)
    before = spec.preprocess.norm_floor_percentile
    calibrated = ["interval", *(["min_change"] if spec.min_change > 0.0 else [])]
    again = stale(calibrated if percentile != before else [], dst)
    return {"norm_floor_percentile": percentile, "before": before, "stale": again}


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m contactcal.train.floor MODEL --percentile F --out NEW.onnx``."""
    ap = Parser(
        prog="python -m contactcal.train.floor",
        description="Set an exported model's dark floor (metadata only).",
    )
    ap.add_argument("model", type=Path, help="exported .onnx model")
    ap.add_argument("--percentile", type=float, required=True, help="floor percentile, %%")
    ap.add_argument("--out", type=Path, required=True, help="new .onnx file")
    a = ap.parse_args(argv)
    return run_restating(lambda: floor_model(a.model, a.percentile, a.out), a.out)


if __name__ == "__main__":
    raise SystemExit(main())

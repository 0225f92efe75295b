"""Set an exported model's dark floor (metadata ``preprocess.norm_floor_percentile`` only).

The floor ``F``, a low percentile of the crop, is subtracted before the division by the bright
level ``P`` (``u = (g − F) / (P − F)``; :mod:`contactcal.infer.methods.unet.prepare`), which
makes the input invariant to a camera's black level and contrast. The weights are not touched:
whether a model trained without a floor takes it is for validation renders to say (``contactcal
bench --data VALIDATION --model NEW.onnx --robustness``), never the benchmark's held-out sets.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from collections.abc import Sequence
from typing import Any

from contactcal.train.restate import (
    check_paths,
    load_proto,
    metadata_of,
    run_restating,
    save_restated,
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
        ``{"norm_floor_percentile": new, "before": old}``.

    Raises:
        ValueError: bad output name, or a percentile outside ``[0, norm_percentile)``.
    """

    from contactcal.infer.methods.unet.spec import read_spec

    src, dst = check_paths(model, out)
    proto = load_proto(src)
    spec = read_spec(metadata_of(proto), src)
    pre = dataclasses.replace(spec.preprocess, norm_floor_percentile=percentile)
    new = dataclasses.replace(spec, preprocess=pre)
    save_restated(proto, {"preprocess": new.to_metadata()["preprocess"]}, new, dst)
    return {"norm_floor_percentile": percentile, "before": spec.preprocess.norm_floor_percentile}


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m contactcal.train.floor MODEL --percentile F --out NEW.onnx``."""
    ap = argparse.ArgumentParser(
        prog="python -m contactcal.train.floor",
        description="Set an exported model's dark floor (metadata only).",
    )
    ap.add_argument("model", help="exported .onnx model")
    ap.add_argument("--percentile", type=float, required=True, help="floor percentile, %%")
    ap.add_argument("--out", required=True, help="new .onnx file")
    a = ap.parse_args(argv)
    return run_restating(lambda: floor_model(a.model, a.percentile, a.out), a.out)


if __name__ == "__main__":
    raise SystemExit(main())

"""How the contact region's shape changes a model's area error (``docs/training.md``, "A convex
contact region").

Every frame of the datasets goes through the deployed runner (each session's lowest-pressure frame
as reference, large frames shrunk as deployment shrinks them), with the model's region set to
``largest``; the kept region is then measured as it is and as each candidate shape made from it:
its convex hull (``convex``, the spec's ``region``), the hull within the looser band p >=
``threshold_low`` of the model's interval, within p >= 0.2, a morphological closing by 8 and 16
network px (holes filled), and a least-squares ellipse through its outline. Printed: per pressure
bin, the median |relative area error| and the mean signed one over frames with true contact.

    .venv/bin/python docs/scripts/region_scores.py models/contact_unet.onnx \
        --data data/val_v3
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.bench.dataset import read_index
from contactcal.infer.methods.unet.postprocess import Segmentation, convex_region
from contactcal.infer.methods.unet.runner import OnnxSegmenter
from contactcal.train.sessions import session_inputs

#: Pressure bins (kPa, lower bound inclusive), as the bench's 3-5 and ≥ 5 kPa columns.
BINS = ((3.0, 5.0), (5.0, float("inf")))


def closed(keep: np.ndarray, radius: int) -> np.ndarray:
    """``keep`` closed by a disk of ``radius`` px, holes filled."""
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    pad = 2 * radius
    c = cv2.morphologyEx(np.pad(keep.astype(np.uint8), pad), cv2.MORPH_CLOSE, k)[pad:-pad, pad:-pad]
    contours, _ = cv2.findContours(c, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    out = np.zeros(keep.shape, np.uint8)
    cv2.drawContours(out, contours, -1, 1, -1)
    return out.astype(bool) | keep


def ellipse_px(keep: np.ndarray) -> float:
    """Area (px) of the least-squares ellipse through the region's outline."""
    contours, _ = cv2.findContours(keep.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    c = max(contours, key=cv2.contourArea)
    if len(c) < 5:
        return float(keep.sum())
    _, (a, b), _ = cv2.fitEllipse(c)
    return float(np.pi * a * b / 4.0)


def shapes(low: float) -> dict[str, Callable[[Segmentation], float]]:
    """Each candidate's area in network px from a ``largest`` segmentation."""
    return {
        "largest": lambda s: float(s.mask_net.sum()),
        "convex": lambda s: float(convex_region(s.mask_net).sum()),
        "convex, p>=low": lambda s: float(
            ((convex_region(s.mask_net) & (s.prob >= low)) | s.mask_net).sum()
        ),
        "convex, p>=0.2": lambda s: float(
            ((convex_region(s.mask_net) & (s.prob >= 0.2)) | s.mask_net).sum()
        ),
        "closed 8": lambda s: float(closed(s.mask_net, 8).sum()),
        "closed 16": lambda s: float(closed(s.mask_net, 16).sum()),
        "ellipse": lambda s: ellipse_px(s.mask_net),
    }


def errors(model: Path, data: list[Path]) -> tuple[list[str], np.ndarray]:
    """``(names, (N, 1 + len(names)))``: pressure (kPa) and each shape's relative area error of
    every frame with true contact; -1 where the model calls no contact."""
    runner = OnnxSegmenter(model)
    runner.spec = dataclasses.replace(runner.spec, region="largest")
    if runner.spec.interval is None:
        raise ValueError(f"{model}: the model states no interval (threshold_low)")
    fns = shapes(runner.spec.interval.threshold_low)
    rows = []
    for d in data:
        for sess in session_inputs(read_index(d), runner.spec.preprocess).values():
            for r in sess.rows:
                if not r.contact:
                    continue
                seg = runner.segment(sess.frame(r.frame), sess.reference)
                px = seg.box.scale(seg.prob.shape[0]) ** 2 * sess.shrink**2  # input px per net px
                errs = [
                    f(seg) * px / r.area_px - 1.0 if seg.contact else -1.0 for f in fns.values()
                ]
                rows.append([r.pressure_kpa, *errs])
    return list(fns), np.array(rows, float).reshape(-1, 1 + len(fns))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", type=Path, help="exported .onnx model")
    ap.add_argument("--data", type=Path, nargs="+", required=True, help="dataset folder(s)")
    args = ap.parse_args()
    try:
        names, a = errors(args.model, args.data)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}")
        return 2
    print(f"{args.model}: {', '.join(map(str, args.data))}, {len(a)} frames in contact")
    for lo, hi in BINS:
        b = a[(a[:, 0] >= lo) & (a[:, 0] < hi)]
        print(f"  {lo:g}-{hi:g} kPa, {len(b)} frames: median |error| (mean signed)")
        for i, name in enumerate(names, start=1):
            if not len(b):
                print(f"    {name:16s} –")
                continue
            med, mean = 100 * np.median(np.abs(b[:, i])), 100 * np.mean(b[:, i])
            print(f"    {name:16s} {med:6.2f} % ({mean:+.1f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

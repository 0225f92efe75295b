"""Does a boundary offset measured on a few labelled frames carry over to other sessions?

Simulates what ``docs/evaluate.md`` ("Boundary offset") asks of a lab: label N frames of its rig,
let ``contactcal evaluate`` measure the U-Net's boundary offset on them, put it in the rig config,
calibrate other sessions. Every frame of every dataset is measured once through
``measure_files`` (the session's lowest-pressure frame as reference, the dataset's own pixel
scale); per frame in contact the offset that would give the true area is
:func:`~contactcal.infer.pipeline.boundary.fit_offset`'s. Then, ``--draws`` times, N frames in
contact are drawn (seeded) from the ``--fit`` datasets, their median offset is applied
(:func:`~contactcal.infer.pipeline.boundary.apply_offset`) to every frame of each ``--apply``
dataset, and its median |area error| at ≥ 5 kPa is taken. Printed per apply dataset: without
offset, and with it (median and 5-95 % over the draws), plus the pooled-offset row (all fit
frames). The fit and apply datasets must not share sessions.

    .venv/bin/python docs/scripts/offset_transfer.py --fit data/cc7800_hr data/cc7900_hr \\
        --apply data/cc8000_hr data/cc8100_hr --labelled 10 --draws 200
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.methods.registry import make_method
from contactcal.infer.pipeline.boundary import apply_offset, fit_offset
from contactcal.infer.pipeline.measure import measure_files
from contactcal.infer.pipeline.scale import PixelScale

#: Columns of a measured frame: pressure kPa, true area px, area px, perimeter px, mm/px.
P, TRUE, AREA, PERIM, MMPX = range(5)


def measure_dataset(folder: Path, model: Path | None) -> np.ndarray:
    """``(F, 5)`` per frame of ``folder`` (see the column constants); no contact: area 0."""
    method = make_method("unet", model)
    out = []
    for rows in sessions_of(read_index(folder)).values():
        scale = PixelScale(rows[0].mm_per_px, None)
        for row, m in zip(
            rows,
            measure_files([r.frame for r in rows], method, rows[0].frame, scale),
            strict=True,
        ):
            r = m.result
            perim = r.perimeter_px if r.contact and r.perimeter_px else 0.0
            out.append((row.pressure_kpa, row.area_px, r.area_px, perim, row.mm_per_px))
    return np.array(out, dtype=float)


def offsets_mm(f: np.ndarray) -> np.ndarray:
    """Per frame in contact (truth and U-Net): the offset that gives the true area, mm."""
    ok = (f[:, TRUE] > 0) & (f[:, AREA] > 0) & (f[:, PERIM] > 0)
    d = [fit_offset(a, p, t) for a, p, t in f[ok][:, [AREA, PERIM, TRUE]]]
    return np.asarray(d) * f[ok][:, MMPX]


def error_at(f: np.ndarray, d_mm: float) -> float:
    """Median |relative area error| (%) at ≥ 5 kPa with the boundary moved ``d_mm``."""
    from contactcal.infer.methods.base import AreaResult

    sel = f[(f[:, P] >= 5) & (f[:, TRUE] > 0)]
    errs = []
    for row in sel:
        res = AreaResult(row[AREA] > 0, row[AREA], "", None, perimeter_px=row[PERIM] or None)
        area = apply_offset(res, d_mm / row[MMPX], d_mm).area_px if d_mm else row[AREA]
        errs.append(abs(area - row[TRUE]) / row[TRUE])
    return 100 * float(np.median(errs))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, nargs="+", required=True, help="the 'labelled' datasets")
    ap.add_argument("--apply", type=Path, nargs="+", required=True, help="datasets to correct")
    ap.add_argument("--model", type=Path, help="ONNX model (default: shipped)")
    ap.add_argument("--labelled", type=int, default=10, help="frames a lab labels (default 10)")
    ap.add_argument("--draws", type=int, default=200, help="draws of those frames (default 200)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    fit = np.concatenate([measure_dataset(d, args.model) for d in args.fit])
    pool = offsets_mm(fit)
    rng = np.random.default_rng(args.seed)
    picks = [
        float(np.median(rng.choice(pool, args.labelled, replace=False))) for _ in range(args.draws)
    ]
    lo, hi = np.percentile(picks, (5, 95))
    print(
        f"fit: {', '.join(d.name for d in args.fit)}: {pool.size} frames in contact; offset "
        f"pooled {np.median(pool):+.3f} mm; from {args.labelled} frames {np.median(picks):+.3f} "
        f"mm (5-95 %: {lo:+.3f} … {hi:+.3f}, {args.draws} draws)"
    )
    print(
        "| dataset | ≥ 5 kPa without | with the pooled offset "
        "| with N labelled frames: median (5-95 %) |"
    )
    print("|---|---|---|---|")
    for d in args.apply:
        f = measure_dataset(d, args.model)
        errs = [error_at(f, x) for x in picks]
        q = np.percentile(errs, (5, 50, 95))
        print(
            f"| {d.name} | {error_at(f, 0.0):.2f} % | {error_at(f, float(np.median(pool))):.2f} % "
            f"| {q[1]:.2f} % ({q[0]:.2f}-{q[2]:.2f}) |"
        )


if __name__ == "__main__":
    main()

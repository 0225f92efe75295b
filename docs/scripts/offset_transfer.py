"""Does a boundary offset measured on a few labelled frames carry over to other sessions?

Simulates what ``docs/evaluate.md`` ("Boundary offset") asks of a lab: label N frames of its rig,
let ``contactcal evaluate`` measure the U-Net's boundary offset on them, put it in the rig config,
calibrate other sessions. Every frame of every dataset is measured once through
``measure_files`` (the session's lowest-pressure frame as reference, the dataset's own pixel
scale); per frame in contact the offset that would give the true area is
:func:`~contactcal.infer.pipeline.boundary.fit_offset`'s. Then, ``--draws`` times, N frames in
contact are drawn (seeded) from the ``--fit`` datasets, and the offset ``contactcal evaluate``
would give from them (their median, or none when its 90 % interval includes 0:
:func:`~contactcal.infer.evaluate.offset.resolved_offset`) is applied
(:func:`~contactcal.infer.pipeline.boundary.apply_offset`) to every frame of each ``--apply``
dataset, and its median |area error| at ≥ 5 kPa is taken. Printed per apply dataset: without
offset, with the pooled offset (all fit frames), and with the drawn ones (median and 5-95 % over
the draws); and the share of its frames in contact whose stated 90 % interval holds the true
area, without and with the pooled offset. The fit and apply datasets must not share sessions.

    .venv/bin/python docs/scripts/offset_transfer.py --fit data/cc7800_hr data/cc7900_hr \\
        --apply data/cc8000_hr data/cc8100_hr --labelled 10 --draws 200
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.evaluate.offset import resolved_offset
from contactcal.infer.methods.base import AreaResult
from contactcal.infer.methods.registry import make_method
from contactcal.infer.pipeline.boundary import apply_offset, fit_offset
from contactcal.infer.pipeline.measure import measure_files
from contactcal.infer.pipeline.scale import PixelScale

#: Columns of a measured frame: pressure kPa, true area px, area px, perimeter px, mm/px, the
#: stated interval's ends px, and the session's index in its dataset.
P, TRUE, AREA, PERIM, MMPX, LO, HI, SESSION = range(8)


def measure_dataset(folder: Path, model: Path | None) -> np.ndarray:
    """``(F, 8)`` per frame of ``folder`` (see the column constants); no contact: area 0."""
    method = make_method("unet", model)
    out = []
    for k, rows in enumerate(sessions_of(read_index(folder)).values()):
        scale = PixelScale(rows[0].mm_per_px, None)
        for row, m in zip(
            rows,
            measure_files([r.frame for r in rows], method, rows[0].frame, scale),
            strict=True,
        ):
            r = m.result
            perim = r.perimeter_px if r.contact and r.perimeter_px else 0.0
            lo, hi = r.area_interval_px or (np.nan, np.nan)
            out.append((row.pressure_kpa, row.area_px, r.area_px, perim, row.mm_per_px, lo, hi, k))
    return np.array(out, dtype=float)


def session_spread(f: np.ndarray) -> str:
    """The sessions' own median offsets (sessions with >= 5 frames in contact): range and SD."""
    meds = [
        np.median(d)
        for k in np.unique(f[:, SESSION])
        if (d := offsets_mm(f[f[:, SESSION] == k])).size >= 5
    ]
    return (
        f"{len(meds)} sessions' medians {min(meds):+.3f} … {max(meds):+.3f} mm, "
        f"SD {np.std(meds):.3f} mm"
    )


def offsets_mm(f: np.ndarray) -> np.ndarray:
    """Per frame in contact (truth and U-Net): the offset that gives the true area, mm."""
    ok = (f[:, TRUE] > 0) & (f[:, AREA] > 0) & (f[:, PERIM] > 0)
    d = [fit_offset(a, p, t) for a, p, t in f[ok][:, [AREA, PERIM, TRUE]]]
    return np.asarray(d) * f[ok][:, MMPX]


def _moved(row: np.ndarray, d_mm: float) -> AreaResult:
    """One measured frame as a result, its boundary moved ``d_mm`` (0: as measured)."""
    res = AreaResult(
        row[AREA] > 0, row[AREA], "", None, None, (row[LO], row[HI]), row[PERIM] or None
    )
    return apply_offset(res, d_mm / row[MMPX], d_mm) if d_mm else res


def error_at(f: np.ndarray, d_mm: float) -> float:
    """Median |relative area error| (%) at ≥ 5 kPa with the boundary moved ``d_mm``."""
    sel = f[(f[:, P] >= 5) & (f[:, TRUE] > 0)]
    errs = [abs(_moved(row, d_mm).area_px - row[TRUE]) / row[TRUE] for row in sel]
    return 100 * float(np.median(errs))


def coverage_at(f: np.ndarray, d_mm: float) -> float:
    """Share (%) of the frames in contact whose stated interval holds the true area."""
    sel = f[f[:, TRUE] > 0]
    ivs = [_moved(row, d_mm).area_interval_px for row in sel]
    return 100 * float(
        np.mean([lo <= t <= hi for (lo, hi), t in zip(ivs, sel[:, TRUE], strict=True)])
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, nargs="+", required=True, help="the 'labelled' datasets")
    ap.add_argument("--apply", type=Path, nargs="+", required=True, help="datasets to correct")
    ap.add_argument("--model", type=Path, help="ONNX model (default: shipped)")
    ap.add_argument("--labelled", type=int, default=10, help="frames a lab labels (default 10)")
    ap.add_argument("--draws", type=int, default=200, help="draws of those frames (default 200)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    fits = [measure_dataset(d, args.model) for d in args.fit]
    for d, f in zip(args.fit, fits, strict=True):
        print(f"{d.name}: {session_spread(f)}")
    fit = np.concatenate(fits)
    pool = offsets_mm(fit)
    rng = np.random.default_rng(args.seed)
    picks = [
        resolved_offset(rng.choice(pool, args.labelled, replace=False)) for _ in range(args.draws)
    ]
    lo, hi = np.percentile(picks, (5, 95))
    print(
        f"fit: {', '.join(d.name for d in args.fit)}: {pool.size} frames in contact; offset "
        f"pooled {np.median(pool):+.3f} mm; from {args.labelled} frames {np.median(picks):+.3f} "
        f"mm (5-95 %: {lo:+.3f} … {hi:+.3f}, {args.draws} draws; resolved, i.e. its interval "
        f"excludes 0, in {sum(x != 0.0 for x in picks)})"
    )
    print(
        "| dataset | ≥ 5 kPa without | with the pooled offset "
        "| with N labelled frames: median (5-95 %) | interval coverage without / with |"
    )
    print("|---|---|---|---|---|")
    for d in args.apply:
        f = measure_dataset(d, args.model)
        errs = [error_at(f, x) for x in picks]
        q = np.percentile(errs, (5, 50, 95))
        pooled = float(np.median(pool))
        cov = f"{coverage_at(f, 0.0):.1f} / {coverage_at(f, pooled):.1f} %"
        print(
            f"| {d.name} | {error_at(f, 0.0):.2f} % | {error_at(f, pooled):.2f} % "
            f"| {q[1]:.2f} % ({q[0]:.2f}-{q[2]:.2f}) | {cov} |"
        )


if __name__ == "__main__":
    main()

"""``evaluation.png``: signed relative area error vs pressure, and a Bland-Altman plot.

matplotlib is imported inside :func:`plot_evaluation` only (object API with the Agg canvas, never
pyplot's global backend). Both panels show the frames labelled with contact only (a relative
error needs a label area > 0).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from contactcal.infer.bench.scoring import ScoredFrame

#: %, largest |error| drawn on a linear axis; beyond it the axis is symmetric-log, linear within
#: ±:data:`SYMLOG_LINEAR_PCT` (the U-Net's few per cent stay readable beside a 480 % miss).
SYMLOG_ABOVE_PCT = 30.0
SYMLOG_LINEAR_PCT = 5.0
SYMLOG_TICKS_PCT = (-1000, -100, -20, -5, -2, 0, 2, 5, 20, 100, 1000, 10000)


def bland_altman(frames: Sequence[ScoredFrame]) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Mean and difference of method and label areas, the mean bias and its 1.96 sd half-width.

    Args:
        frames: one method's frames labelled with contact (>= 1).

    Returns:
        ``(mean, diff, bias, half_width)``: ``(N,)`` arrays of ``(method + label) / 2`` and
        ``method − label`` in px, the mean difference (px) and ``1.96 ×`` its sd (px; 0 for N=1).
    """
    a = np.array([f.area_px for f in frames], dtype=np.float64)
    t = np.array([f.true_area_px for f in frames], dtype=np.float64)
    diff = a - t
    sd = float(np.std(diff, ddof=1)) if diff.size > 1 else 0.0
    return (a + t) / 2.0, diff, float(diff.mean()), 1.96 * sd


def plot_evaluation(path: str | os.PathLike[str], scored: Sequence[ScoredFrame]) -> None:
    """Draw the two panels per method into the PNG ``path`` (written as given: stage it)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.4), dpi=110)
    FigureCanvasAgg(fig)
    err_ax, ba_ax = fig.subplots(1, 2)
    err_ax.axhline(0.0, color="black", lw=0.8)
    worst = 0.0  # %, the largest |error| drawn
    for i, method in enumerate(sorted({s.method for s in scored})):
        fs = [s for s in scored if s.method == method and s.true_contact]
        if not fs:
            continue
        colour = f"C{i}"
        errors = [100.0 * f.rel_error for f in fs]
        worst = max(worst, *(abs(e) for e in errors))
        # markers only: a line would join a loading pass's top to the unloading pass's frames
        err_ax.plot([f.pressure_kpa for f in fs], errors, ls="", color=colour, marker="o", ms=4)
        err_ax.plot([], [], ls="", color=colour, marker="o", ms=4, label=method)
        mean, diff, bias, half = bland_altman(fs)
        ba_ax.scatter(mean, diff, color=colour, s=16, label=f"{method}: bias {bias:+.0f} px")
        ba_ax.axhline(bias, color=colour, lw=1.2)
        for y in (bias - half, bias + half):
            ba_ax.axhline(y, color=colour, lw=0.9, ls="--")
    err_ax.set_xlabel("pressure (kPa)")
    err_ax.set_ylabel("(method − label) / label area (%)")
    err_ax.set_title("Signed relative area error")
    if worst > SYMLOG_ABOVE_PCT:  # one method's outliers would flatten the other's errors
        err_ax.set_yscale("symlog", linthresh=SYMLOG_LINEAR_PCT, linscale=2.0)
        ticks = [t for t in SYMLOG_TICKS_PCT if abs(t) <= 2.0 * worst]
        err_ax.set_yticks(ticks, [f"{t:g}" for t in ticks])
        err_ax.set_title(f"Signed relative area error (log beyond ±{SYMLOG_LINEAR_PCT:g} %)")
    ba_ax.set_xlabel("(method + label) / 2 area (px)")
    ba_ax.set_ylabel("method − label area (px)")
    ba_ax.set_title("Bland-Altman: bias (solid), ±1.96 sd (dashed)")
    for ax in (err_ax, ba_ax):
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.fspath(path), format="png")

"""Run outputs: ``metrics.csv``, ``val_bins.csv`` and the learning-curve plot ``curves.png``.

matplotlib is imported inside :func:`plot_curves` only, with its object API and the Agg canvas
(``Figure`` + ``FigureCanvasAgg``; pyplot's global backend is never touched).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from typing import Any

from contactcal.infer.files.atomic import atomic_open, atomic_path
from contactcal.train.metrics import SUMMARY_KEYS

#: Columns of metrics.csv (one row per epoch; "" where undefined).
METRIC_COLUMNS = ("epoch", "train_loss", "val_loss", "lr", *SUMMARY_KEYS, "seconds")


def write_csv(
    path: str | os.PathLike[str], rows: Sequence[dict[str, Any]], columns: Sequence[str]
) -> None:
    """Write rows atomically; None becomes "" (never NaN); floats with 6 significant digits."""
    with atomic_open(path, "w") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for row in rows:
            vals = [row.get(c) for c in columns]
            w.writerow(
                ["" if v is None else (f"{v:.6g}" if isinstance(v, float) else v) for v in vals]
            )


def _series(history: Sequence[dict[str, Any]], key: str) -> tuple[list[int], list[float]]:
    """``(epochs, values)`` of one metrics column, skipping epochs where it is undefined."""
    pts = [(int(r["epoch"]), float(r[key])) for r in history if r.get(key) is not None]
    return [p[0] for p in pts], [p[1] for p in pts]


def plot_curves(
    path: str | os.PathLike[str], history: Sequence[dict[str, Any]], best_epoch: int = -1
) -> None:
    """Losses (left) and validation metrics (right) against epoch; ``best_epoch`` marked.

    Args:
        path: PNG file (written atomically).
        history: metrics.csv rows.
        best_epoch: 1-based epoch of ``best.pt`` (a dashed line on both axes); < 1: none.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    fig = Figure(figsize=(10, 4), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    ax_loss, ax_val = fig.subplots(1, 2)
    for key in ("train_loss", "val_loss"):
        ax_loss.plot(*_series(history, key), marker=".", label=key)
    ax_loss.set(xlabel="epoch", ylabel="loss (BCE + soft Dice)", title="loss", yscale="log")
    for key in ("val_iou", "val_iou_contact", "rel_area_err_ge5", "rel_area_err_3to5"):
        ax_val.plot(*_series(history, key), marker=".", label=key)
    ax_val.set(
        xlabel="epoch", ylabel="IoU / relative area error", title="validation", ylim=(0, 1.05)
    )
    for ax in (ax_loss, ax_val):
        if best_epoch >= 1:
            ax.axvline(
                best_epoch, color="black", ls="--", lw=1, label=f"best.pt (epoch {best_epoch})"
            )
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")

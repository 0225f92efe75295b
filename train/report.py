"""Run outputs: ``metrics.csv``, ``val_bins.csv`` and the learning-curve plot ``curves.png``."""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from typing import Any

from contactcal.infer.atomic import atomic_open, atomic_path

#: Columns of metrics.csv (one row per epoch; "" where undefined).
METRIC_COLUMNS = (
    "epoch",
    "train_loss",
    "val_loss",
    "lr",
    "val_iou",
    "val_iou_contact",
    "rel_area_err_ge5",
    "rel_area_err_3to5",
    "no_contact_acc",
    "contact_recall",
    "seconds",
)


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


def plot_curves(path: str | os.PathLike[str], history: Sequence[dict[str, Any]]) -> None:
    """Losses (left) and validation IoU / relative area error (right) against epoch."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def series(key: str) -> tuple[list[int], list[float]]:
        pts = [(int(r["epoch"]), float(r[key])) for r in history if r.get(key) is not None]
        return [p[0] for p in pts], [p[1] for p in pts]

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for key in ("train_loss", "val_loss"):
        ax0.plot(*series(key), marker=".", label=key)
    ax0.set(xlabel="epoch", ylabel="BCE + Dice", title="loss", yscale="log")
    for key in ("val_iou", "val_iou_contact", "rel_area_err_ge5", "rel_area_err_3to5"):
        ax1.plot(*series(key), marker=".", label=key)
    ax1.set(xlabel="epoch", title="validation", ylim=(0, 1.05))
    for ax in (ax0, ax1):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100)
    plt.close(fig)

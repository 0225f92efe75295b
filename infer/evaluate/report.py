"""The short table ``contactcal evaluate`` prints: per method and pressure bin."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:6.2f} %"


def _iou(x: float | None) -> str:
    return "–" if x is None else f"{x:.3f}"


def _count(rate: float | None, n: int) -> str:
    """``"k/n"``: how many of ``n`` frames ``rate`` stands for; "–" without frames."""
    return "–" if rate is None or n == 0 else f"{round(rate * n)}/{n}"


def format_table(bins: Sequence[dict[str, Any]], onset: dict[str, Any]) -> str:
    """Rows of ``bin_table`` (frames; of the frames labelled in contact, how many the method
    found; of those labelled without, how many it left without; median |rel error|, median
    IoU) and the onset errors.

    Args:
        bins: ``bin_table`` rows (``method``, ``bin_kpa``, ``frames``, ``contact_frames``,
            ``contact_recall``, ``no_contact_frames``, ``no_contact_accuracy``,
            ``median_abs_rel_error``, ``median_iou``).
        onset: :func:`~contactcal.infer.evaluate.score.onset_summary`'s result.
    """
    lines = [
        f"{'method':>10s} {'bin kPa':>8s} {'frames':>6s} {'contact found':>13s} "
        f"{'no contact kept':>15s} {'med |rel err|':>13s} med IoU"
    ]
    for r in bins:
        found = _count(r["contact_recall"], r["contact_frames"])
        kept = _count(r["no_contact_accuracy"], r["no_contact_frames"])
        lines.append(
            f"{r['method']:>10s} {r['bin_kpa']:>8s} {r['frames']:6d} {found:>13s} {kept:>15s} "
            f"{_pct(r['median_abs_rel_error']):>13s} {_iou(r['median_iou'])}"
        )
    truth = onset["labels_onset_kpa"]
    if truth is None:
        lines.append(onset["note"])
        return "\n".join(lines)
    for m, o in onset["methods"].items():
        est = "none" if o["onset_kpa"] is None else f"{o['onset_kpa']:.2f} kPa"
        err = "" if o["error_kpa"] is None else f" (error {o['error_kpa']:+.2f} kPa)"
        lines.append(f"onset {m}: {est}{err}; from the labels {truth:.2f} kPa")
    if onset["note"]:
        lines.append(f"note: {onset['note']}")
    return "\n".join(lines)

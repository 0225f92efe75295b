"""Scoring a method against known truth, per frame and per pressure bin.

One home for the per-frame record and the pressure-bin table used by ``contactcal bench`` and by
validation during training (so a model is selected on the numbers the benchmark reports).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.infer.calibration.rings import frame_revisions
from contactcal.infer.methods.base import AreaResult

#: Pressure bins of every table, kPa, ``[lo, hi)``; the last bin includes 20 kPa.
PRESSURE_BINS: tuple[tuple[float, float], ...] = (
    (0.0, 3.0),
    (3.0, 5.0),
    (5.0, 10.0),
    (10.0, 20.0001),
)
#: The bins of ``contactcal evaluate``: a rig's sessions may go past 20 kPa (or log 20.001), and a
#: labelled frame is never left out of the table, so the last bin is open.
OPEN_BINS: tuple[tuple[float, float], ...] = (*PRESSURE_BINS[:-1], (10.0, math.inf))


def covering_bins(
    pressures_kpa: Sequence[float], bins: Sequence[tuple[float, float]]
) -> tuple[tuple[float, float], ...]:
    """``bins``, with the last one opened (its end +inf, shown as ``">=lo"``) when a pressure
    lies at or above its end, so that a table leaves no frame out (a dataset past 20 kPa).

    Args:
        pressures_kpa: the frames' pressures, kPa.
        bins: ascending ``[lo, hi)`` bins, kPa.
    """
    out = tuple(bins)
    if out and any(p >= out[-1][1] for p in pressures_kpa):
        out = (*out[:-1], (out[-1][0], math.inf))
    return out


#: Suffix of the rows that score the U-Net's probability mass instead of its pixel count.
SOFT_SUFFIX = " (soft area)"
#: Suffix of the rows that score a method's frames after the session rule of ``calibrate``
#: (:mod:`~contactcal.infer.calibration.rings`): what a calibration reports, per frame.
SESSION_SUFFIX = " (session rule)"


@dataclass(frozen=True)
class ScoredFrame:
    """A method's outcome on one frame whose truth is known. Areas in input pixels."""

    method: str  # e.g. "unet", "classical", "unet (soft area)"
    session: str  # session key (frames of one session share a reference)
    frame: str  # frame file
    pressure_kpa: float  # kPa
    true_area_px: float  # px, exact mask area (0 without contact)
    area_px: float  # px, the method's area (0.0 when it reports no contact)
    contact: bool  # the method reports contact
    iou: float | None = None  # against the mask, where computed
    mm_per_px: float | None = None  # mm/px, for errors in mm²
    onset_kpa: float | None = None  # kPa, the session's true onset
    hard: bool = False  # the session was drawn from the hard ranges
    area_interval_px: tuple[float, float] | None = None  # px, the stated interval; None: none
    reference: bool = False  # the session's reference frame, measured against itself (bench)

    @property
    def true_contact(self) -> bool:
        """Truth: the mask is not empty."""
        return self.true_area_px > 0

    @property
    def rel_error(self) -> float:
        """Signed relative area error ``(area - true) / true`` (contact frames only)."""
        if not self.true_contact:
            raise ValueError(f"{self.frame}: relative error is undefined without true contact")
        return (self.area_px - self.true_area_px) / self.true_area_px

    @property
    def covered(self) -> bool | None:
        """The stated interval contains the true area (None without an interval)."""
        if self.area_interval_px is None:
            return None
        lower, upper = self.area_interval_px
        return lower <= self.true_area_px <= upper


def not_references(frames: Sequence[ScoredFrame]) -> list[ScoredFrame]:
    """The frames a table scores: all but the sessions' reference frames (each measured against
    itself; ``bench`` keeps them for the onset and in its records, marked ``reference``)."""
    return [f for f in frames if not f.reference]


def session_revised(frames: Sequence[ScoredFrame]) -> np.ndarray:
    """``(N,) bool``: the frames (one method, one pass, any pressure order) that ``calibrate``'s
    session rule sets to no contact (:func:`~contactcal.infer.calibration.rings.frame_revisions`,
    both its parts); all False for a method that states no interval."""
    ring, below = frame_revisions(
        [f.pressure_kpa for f in frames],
        [f.area_px for f in frames],
        [f.contact for f in frames],
        [f.area_interval_px for f in frames],
    )
    return ring | below


def median_or_none(values: Sequence[float]) -> float | None:
    """Median, or None for no values."""
    return float(statistics.median(values)) if values else None


def _fraction(flags: Sequence[bool]) -> float | None:
    return sum(flags) / len(flags) if flags else None


def outline_iou(result: AreaResult, truth: np.ndarray) -> float | None:
    """IoU of the method's outline (filled) with a truth mask that has contact (a hand label
    in ``evaluate``, a render's exact mask in ``bench``).

    Args:
        result: the method's outcome; ``contour`` in input pixels (None without contact).
        truth: ``(H, W)`` bool label mask, not empty.

    Returns:
        The IoU in [0, 1]; None when the method reports contact without an outline.
    """
    pred = np.zeros(truth.shape, dtype=np.uint8)
    if result.contact:
        if result.contour is None:
            return None
        cv2.drawContours(pred, [result.contour.astype(np.int32)], -1, 1, thickness=-1)
    inter = np.logical_and(pred > 0, truth).sum()
    union = np.logical_or(pred > 0, truth).sum()
    return float(inter / union)


def bin_row(frames: Sequence[ScoredFrame]) -> dict[str, float | int | None]:
    """Error summary of some frames (one method): None where a quantity has no frames.

    Keys: ``frames``, ``contact_frames``, ``median_abs_rel_error``, ``mean_rel_error``,
    ``sd_rel_error``, ``median_abs_error_mm2``, ``median_iou``, ``contact_recall``,
    ``no_contact_frames``, ``no_contact_accuracy``.
    """
    cont = [f for f in frames if f.true_contact]
    none = [f for f in frames if not f.true_contact]
    rel = [f.rel_error for f in cont]
    mm2 = [abs(f.area_px - f.true_area_px) * f.mm_per_px**2 for f in cont if f.mm_per_px]
    ious = [f.iou for f in cont if f.iou is not None]
    return {
        "frames": len(frames),
        "contact_frames": len(cont),
        "median_abs_rel_error": median_or_none([abs(x) for x in rel]),
        "mean_rel_error": float(np.mean(rel)) if rel else None,
        "sd_rel_error": float(np.std(rel)) if rel else None,
        "median_abs_error_mm2": median_or_none(mm2),
        "median_iou": median_or_none(ious),
        "contact_recall": _fraction([f.contact for f in cont]),
        "no_contact_frames": len(none),
        "no_contact_accuracy": _fraction([not f.contact for f in none]),
    }


def coverage_row(frames: Sequence[ScoredFrame]) -> dict[str, float | int | None]:
    """Coverage of the stated interval over some frames (one method that states one).

    Keys: ``frames`` (with an interval), ``coverage`` (all of them), ``contact_frames``,
    ``contact_coverage`` (frames with true contact), ``median_rel_width`` (interval width over
    the true area, true-contact frames); None where a quantity has no frames.
    """
    stated = [f for f in frames if f.area_interval_px is not None]
    cont = [f for f in stated if f.true_contact]
    widths = [(f.area_interval_px[1] - f.area_interval_px[0]) / f.true_area_px for f in cont]
    return {
        "frames": len(stated),
        "coverage": _fraction([bool(f.covered) for f in stated]),
        "contact_frames": len(cont),
        "contact_coverage": _fraction([bool(f.covered) for f in cont]),
        "median_rel_width": median_or_none(widths),
    }


def bin_label(lo: float, hi: float) -> str:
    """``"5-10"`` for the bin ``[5, 10)`` kPa (20.0001 shows as 20), ``">=10"`` for an open one."""
    return f">={lo:g}" if math.isinf(hi) else f"{lo:g}-{hi:.0f}"


def bin_table(
    frames: Sequence[ScoredFrame], bins: Sequence[tuple[float, float]] = PRESSURE_BINS
) -> list[dict[str, object]]:
    """Per method and pressure bin: :func:`bin_row` plus ``method`` and ``bin_kpa``.

    Every (method, bin) pair gets a row, empty bins included (their values are None).
    """
    rows: list[dict[str, object]] = []
    for method in sorted({f.method for f in frames}):
        for lo, hi in bins:
            sel = [f for f in frames if f.method == method and lo <= f.pressure_kpa < hi]
            rows.append({"method": method, "bin_kpa": bin_label(lo, hi), **bin_row(sel)})
    return rows

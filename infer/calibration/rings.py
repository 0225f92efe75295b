"""The inner ring before contact: a region that shrinks as the pressure rises is not contact.

The paper's photographs (``../shared/reference``, Figure 10) show the LGP's reflection on the
inflating membrane as an inner luminous ring *before* any contact: it "decreased its size from 1
to 2 kPa because the membrane was inflated, while remaining detached from the finger", and grows
again once contact starts, hugging the ridge region. A per-frame segmenter can take the disc
inside that ring for contact (the U-Net does on the procedural cross-check generator,
``docs/evaluate.md``); one frame alone cannot always tell the two apart, a session can: the true
contact area never decreases as the pressure rises (the skin is pressed further), while the
pre-contact ring's disc does.

Rule (a step is one pressure of one phase; frames of a step are pooled as in
:mod:`~contactcal.infer.calibration.steps`): a step in contact whose stated area interval lies
wholly above the stated interval of the next step in contact (the next higher pressure) is
revised to "no contact". Both intervals are the method's own calibrated ~90 % intervals, so a
revision needs a decrease the method's uncertainty cannot explain; no threshold is tuned here.
Methods that state no interval (the classical routine) are never revised. The calibration's
onset rule (:func:`~contactcal.infer.calibration.onset.onset_index`) then drops any lone contact
left below the revised steps, as it drops any isolated false contact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike

from contactcal.infer.calibration.onset import onset_index
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.steps import pool

#: The note of a frame revised as a ring (``{area}``, ``{upper}``, ``{next_kpa}`` filled in, px).
RING_NOTE = (
    "no contact (session rule): its region ({area:.0f} px) is larger than the next step's "
    "(at most {upper:.0f} px at {next_kpa:g} kPa) beyond both stated intervals; contact area "
    "only grows with pressure, so this is the inner ring before contact"
)
#: The note of a contact left below the session's contact range (``{area}`` filled in, px).
BELOW_NOTE = (
    "no contact (session rule): its region ({area:.0f} px) lies below the session's contact "
    "range (most frames between it and the range are not in contact), so the fit counts it as 0"
)


def shrinking_steps(
    pressures_kpa: ArrayLike, lower: ArrayLike, upper: ArrayLike, contact: ArrayLike
) -> np.ndarray:
    """Which steps the rule revises to "no contact".

    Args:
        pressures_kpa: ``(N,)`` step pressures, kPa, distinct, any order.
        lower: ``(N,)`` lower ends of the steps' stated area intervals (any area unit; NaN
            where the step states none).
        upper: ``(N,)`` upper ends, same unit (NaN where none).
        contact: ``(N,)`` bool, the step is in contact.

    Returns:
        ``(N,) bool``, in the input order: in contact, with an interval, and its ``lower`` is
        above the ``upper`` of the next step in contact at a higher pressure (which must state
        an interval too).

    Raises:
        ValueError: arrays of different lengths, or repeated or non-finite pressures.
    """
    p = np.asarray(pressures_kpa, dtype=np.float64)
    lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    c = np.asarray(contact, dtype=bool)
    if not (p.ndim == 1 and p.shape == lo.shape == hi.shape == c.shape):
        raise ValueError(
            "shrinking_steps: expected 1-D arrays of one length, got shapes "
            f"{p.shape}, {lo.shape}, {hi.shape}, {c.shape}"
        )
    if not np.all(np.isfinite(p)) or np.unique(p).size != p.size:
        raise ValueError("shrinking_steps: pressures must be finite and distinct")
    order = np.argsort(p)
    out = np.zeros(p.size, dtype=bool)
    in_contact = [int(i) for i in order if c[i]]
    for i, j in pairwise(in_contact):
        out[i] = bool(lo[i] > hi[j])  # False when either is NaN
    return out


def session_revisions(
    pressures_kpa: ArrayLike, lower: ArrayLike, upper: ArrayLike, contact: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """The whole session rule: shrinking steps, then contacts left below the contact range.

    Arguments as :func:`shrinking_steps`.

    Returns:
        ``(ring, below)``, ``(N,) bool`` each, input order: the steps :func:`shrinking_steps`
        revises, and the steps still in contact below the contact range that the calibration's
        onset rule (:func:`~contactcal.infer.calibration.onset.onset_index`) finds after that
        (the fit sets their area to 0). A step in neither keeps its flag.
    """
    ring = shrinking_steps(pressures_kpa, lower, upper, contact)
    c = np.asarray(contact, dtype=bool) & ~ring
    order = np.argsort(np.asarray(pressures_kpa, dtype=np.float64))
    s = onset_index(c[order])
    below = np.zeros_like(c)
    below[order[: order.size if s is None else s]] = True
    return ring, below & c


def step_interval(
    contacts: Sequence[bool], intervals: Sequence[tuple[float, float] | None]
) -> tuple[float, float]:
    """A step's stated interval from its frames: the medians of the lower and of the upper ends
    over its frames in contact that state one; ``(nan, nan)`` when none does."""
    ivs = [v for c, v in zip(contacts, intervals, strict=True) if c and v is not None]
    if not ivs:
        return float("nan"), float("nan")
    return float(np.median([v[0] for v in ivs])), float(np.median([v[1] for v in ivs]))


def revise_points(points: Sequence[CalibrationPoint]) -> list[CalibrationPoint]:
    """The session's points with the rule applied, per phase (same order as given).

    Only a session whose method states intervals is revised (the classical routine's points
    come back unchanged; its fit still drops contacts below the range, silently as before). A
    revised frame gets ``contact`` False, area 0 (px and mm²), the interval ``(0, its upper
    end)`` and the note :data:`RING_NOTE` or :data:`BELOW_NOTE`; the others are unchanged.
    The rule works in px (every point has ``area_px``, and a px interval where it has one).

    Args:
        points: one session's per-frame measurements, any order.

    Returns:
        The points, revised where the rule says so.
    """
    out = list(points)
    if all(r.area_interval_px is None for r in points):
        return out
    for phase in dict.fromkeys(r.phase for r in points):
        levels = sorted({r.pressure_kpa for r in points if r.phase == phase})
        steps = [
            [k for k, r in enumerate(points) if r.phase == phase and r.pressure_kpa == p]
            for p in levels
        ]
        ivs = [
            step_interval([points[k].contact for k in s], [points[k].area_interval_px for k in s])
            for s in steps
        ]
        ivs = np.asarray(ivs).reshape(-1, 2)
        contact = [
            pool([points[k].area_px for k in s], [points[k].contact for k in s])[1] for s in steps
        ]
        ring, below = session_revisions(levels, ivs[:, 0], ivs[:, 1], contact)
        in_contact = [i for i, c in enumerate(contact) if c]
        for i in np.flatnonzero(ring | below):
            j = in_contact[in_contact.index(int(i)) + 1] if ring[i] else i  # next in contact
            for k in steps[i]:
                a = points[k].area_px
                note = (
                    RING_NOTE.format(area=a, upper=ivs[j, 1], next_kpa=levels[j])
                    if ring[i]
                    else BELOW_NOTE.format(area=a)
                )
                if points[k].contact:
                    out[k] = _revised(points[k], note)
    return out


def _revised(r: CalibrationPoint, note: str) -> CalibrationPoint:
    """The point as "no contact" with the rule's note (kept beside any note it had)."""
    iv_px = None if r.area_interval_px is None else (0.0, r.area_interval_px[1])
    iv_mm2 = None if r.area_interval_mm2 is None else (0.0, r.area_interval_mm2[1])
    return replace(
        r,
        contact=False,
        area_px=0.0,
        area_mm2=None if r.area_mm2 is None else 0.0,
        note="; ".join(n for n in (r.note, note) if n),
        area_interval_px=iv_px,
        area_interval_mm2=iv_mm2,
    )

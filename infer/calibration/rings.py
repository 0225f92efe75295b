"""The inner ring before contact: a region that shrinks as the pressure rises is not contact.

The paper's photographs (``../shared/reference``, Figure 10) show the LGP's reflection on the
inflating membrane as an inner luminous ring *before* any contact: it "decreased its size from 1
to 2 kPa because the membrane was inflated, while remaining detached from the finger", and grows
again once contact starts, hugging the ridge region. A per-frame segmenter can take the disc
inside that ring for contact (the U-Net does on the procedural cross-check generator,
``docs/crosscheck.md``, ``models/MODEL_CARD.md``); one frame alone cannot always tell the two
apart, a session can: the true contact area never decreases as the pressure rises (the skin is
pressed further), while the pre-contact ring's disc does.

Rule (a step is one pressure of one phase; its frames pooled: in contact by majority, as in
:mod:`~contactcal.infer.calibration.steps`; its area and interval ends the medians over its frames
in contact):

1. a step in contact whose stated area interval lies wholly above the stated interval of the
   next step in contact (the next higher pressure), after which the area grows again (a later
   step in contact is larger than that interval), is revised to "no contact". Both intervals
   are the method's own calibrated ~90 % intervals, so a revision needs a decrease the method's
   uncertainty cannot explain; no threshold is tuned here. The regrowth condition keeps a
   method that loses the contact at high pressure (areas falling to the end) from wiping the
   curve below;
2. the run of contact steps just below a revised step whose median areas do not increase
   towards it is revised too: a slowly shrinking ring (less than the intervals' width per step)
   ends in a drop at its last step only;
3. a ring lies below the contact range: revisions of steps 1-2 at or above the start of the
   contact range that the calibration's onset rule
   (:func:`~contactcal.infer.calibration.onset.onset_index`) finds with all of them applied
   are undone. A lone under-segmented step within the growing curve (a drop the next steps
   grow out of again), with more contact steps below the revised ones than revised and
   no-contact steps down to the first contact, thus leaves the correct step below it in
   contact, as measured, instead of turning it into a 0 inside the curve. Closer to the onset
   (a drop at the second or third contact step) the areas alone cannot tell it from a ring,
   and it is revised as one;
4. contacts left below the contact range that the calibration's onset rule
   (:func:`~contactcal.infer.calibration.onset.onset_index`) finds after that are revised (the
   fit counts them as 0 anyway; the record then says so).

Methods that state no interval (the classical routine) are never revised.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from contactcal.infer.calibration.onset import onset_index
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.steps import pool

#: The note of a frame revised by steps 1-2 (``{area}`` filled in, px).
RING_NOTE = (
    "no contact (session rule): its region ({area:.0f} px) belongs to a run of steps that ends "
    "larger than the next step in contact beyond both stated intervals; contact area only grows "
    "with pressure, so this is not the contact (before contact: the membrane's inner ring)"
)
#: The note of a contact revised by step 4 (``{area}`` filled in, px).
BELOW_NOTE = (
    "no contact (session rule): its region ({area:.0f} px) lies below the session's contact "
    "range (at least as many frames between them are not in contact), so the fit counts it as 0"
)
#: The note of a contact revised by step 4 in a session without any contact range.
NO_RANGE_NOTE = (
    "no contact (session rule): the session has no contact range (at least as many frames above "
    "it are not in contact), so the fit counts it as 0"
)


def _check(p: np.ndarray, *arrays: np.ndarray) -> None:
    """Raise ``ValueError`` unless every array is 1-D of ``p``'s length and ``p`` is finite and
    distinct."""
    if not (p.ndim == 1 and all(a.shape == p.shape for a in arrays)):
        raise ValueError(
            "shrinking_steps: expected 1-D arrays of one length, got shapes "
            + ", ".join(str(a.shape) for a in (p, *arrays))
        )
    if not np.all(np.isfinite(p)) or np.unique(p).size != p.size:
        raise ValueError("shrinking_steps: pressures must be finite and distinct")


def shrinking_steps(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    lower: ArrayLike,
    upper: ArrayLike,
    contact: ArrayLike,
) -> np.ndarray:
    """Steps 1-2 of the rule: which steps are revised to "no contact".

    Args:
        pressures_kpa: ``(N,)`` step pressures, kPa, distinct, any order.
        areas: ``(N,)`` step areas (median of its frames in contact; NaN without), any unit.
        lower: ``(N,)`` lower ends of the steps' stated area intervals, same unit (NaN where
            the step states none).
        upper: ``(N,)`` upper ends, same unit (NaN where none).
        contact: ``(N,)`` bool, the step is in contact.

    Returns:
        ``(N,) bool`` in the input order (the last two contact steps are never revised by
        step 1: it needs a regrowth after the drop).

    Raises:
        ValueError: arrays of different lengths, or repeated or non-finite pressures.
    """
    p = np.asarray(pressures_kpa, dtype=np.float64)
    a = np.asarray(areas, dtype=np.float64)
    lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    c = np.asarray(contact, dtype=bool)
    _check(p, a, lo, hi, c)
    out = np.zeros(p.size, dtype=bool)
    steps = [int(i) for i in np.argsort(p) if c[i]]  # the contact steps, ascending pressure
    for n in range(len(steps) - 2):  # step 1
        i, j, later = steps[n], steps[n + 1], steps[n + 2 :]
        regrows = bool(np.max(a[later]) > hi[j])
        out[i] = bool(lo[i] > hi[j]) and regrows  # False when either bound is NaN
    for k in range(len(steps) - 1, 0, -1):  # step 2, downwards so that a run extends
        i, below = steps[k], steps[k - 1]
        out[below] |= bool(out[i] and a[below] >= a[i])
    return out


def session_revisions(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    lower: ArrayLike,
    upper: ArrayLike,
    contact: ArrayLike,
) -> tuple[np.ndarray, np.ndarray]:
    """The whole rule on one pass's steps.

    Arguments as :func:`shrinking_steps`.

    Returns:
        ``(ring, below)``, ``(N,) bool`` each, input order: the steps :func:`shrinking_steps`
        revises that lie below the contact range, as
        :func:`~contactcal.infer.calibration.onset.onset_index` finds it with all of them
        revised (all of them when it finds none), and the steps still in contact below that
        range (all of them when there is none). A step in neither keeps its flag.
    """
    ring = shrinking_steps(pressures_kpa, areas, lower, upper, contact)
    touch = np.asarray(contact, dtype=bool)
    order = np.argsort(np.asarray(pressures_kpa, dtype=np.float64))
    s = onset_index((touch & ~ring)[order])
    if s is not None:  # a ring lies below the contact range: a drop inside it is not one
        ring[order[s:]] = False  # contact again at or above s: the onset stays s
    c = touch & ~ring
    below = np.zeros_like(c)
    below[order[: order.size if s is None else s]] = True
    return ring, below & c


def frame_revisions(
    pressures_kpa: Sequence[float],
    areas: Sequence[float],
    contacts: Sequence[bool],
    intervals: Sequence[tuple[float, float] | None],
) -> tuple[np.ndarray, np.ndarray]:
    """The rule on one pass's frames: frames at one pressure are pooled into a step (in
    contact by majority; its area the median over its frames in contact, its interval by
    :func:`step_interval`).

    Args:
        pressures_kpa: ``(N,)`` frame pressures, kPa (repeats form a step).
        areas: ``(N,)`` frame areas (any unit; 0 without contact).
        contacts: ``(N,)`` per frame, in contact.
        intervals: per frame, its stated area interval (same unit) or None.

    Returns:
        ``(ring, below)``, ``(N,) bool`` each: the frames in contact that
        :func:`session_revisions` revises, by its two parts; all False when no frame states an
        interval.
    """
    n = len(pressures_kpa)
    if all(v is None for v in intervals):
        return np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    p = np.asarray(pressures_kpa, dtype=np.float64)
    levels, step_of = np.unique(p, return_inverse=True)
    rows = []
    for k in range(levels.size):
        at = np.flatnonzero(step_of == k)
        contact = pool([areas[i] for i in at], [contacts[i] for i in at])[1]
        touching = [areas[i] for i in at if contacts[i]]  # the areas the intervals describe
        area = float(np.median(touching)) if touching else float("nan")
        lo, hi = step_interval([contacts[i] for i in at], [intervals[i] for i in at])
        rows.append((area, lo, hi, contact))
    a, lo, hi, c = (np.asarray(col) for col in zip(*rows, strict=True))
    ring, below = session_revisions(levels, a, lo, hi, c.astype(bool))
    mine = np.asarray(contacts, dtype=bool)
    return ring[step_of] & mine, below[step_of] & mine


def step_interval(
    contacts: Sequence[bool], intervals: Sequence[tuple[float, float] | None]
) -> tuple[float, float]:
    """A step's stated interval from its frames.

    Args:
        contacts: per frame of the step, in contact.
        intervals: per frame, its stated ``(lower, upper)`` area interval or None.

    Returns:
        The medians of the lower and of the upper ends over the frames in contact that state
        one; ``(nan, nan)`` when none does.
    """
    ivs = [v for c, v in zip(contacts, intervals, strict=True) if c and v is not None]
    if not ivs:
        return float("nan"), float("nan")
    return float(np.median([v[0] for v in ivs])), float(np.median([v[1] for v in ivs]))


def revise_points(points: Sequence[CalibrationPoint]) -> list[CalibrationPoint]:
    """The session's points with the rule applied, per phase (same order as given).

    Only a session whose method states intervals is revised (the classical routine's points
    come back unchanged; its fit still drops contacts below the range, silently as before). A
    revised frame gets ``contact`` False, area 0 (px and mm²), the interval ``(0, its upper
    end)`` and the note :data:`RING_NOTE`, :data:`BELOW_NOTE` or :data:`NO_RANGE_NOTE`; the
    others are unchanged. The rule works in px.

    Args:
        points: one session's per-frame measurements, any order.

    Returns:
        The points, revised where the rule says so.
    """
    out = list(points)
    for phase in dict.fromkeys(r.phase for r in points):
        idx = [k for k, r in enumerate(points) if r.phase == phase]
        mine = [points[k] for k in idx]
        ring, below = frame_revisions(
            [r.pressure_kpa for r in mine],
            [r.area_px for r in mine],
            [r.contact for r in mine],
            [r.area_interval_px for r in mine],
        )
        has_range = bool(np.any(np.asarray([r.contact for r in mine]) & ~(ring | below)))
        for k, r, is_ring, is_below in zip(idx, mine, ring, below, strict=True):
            if is_ring:
                out[k] = _revised(r, RING_NOTE.format(area=r.area_px))
            elif is_below:
                note = BELOW_NOTE if has_range else NO_RANGE_NOTE
                out[k] = _revised(r, note.format(area=r.area_px))
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

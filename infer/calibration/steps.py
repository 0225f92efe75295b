"""Pressure steps: the frames of one phase at one pressure, aggregated by their median area.

A rig records several settled frames per pressure step; the step's area is the MEDIAN of its
frames' areas (robust to one bad frame), with its spread (min-max and interquartile range) and
frame count. The step is in contact when at least half of its frames are. The median hides a
frame that disagrees with its step (a slipped finger, an unsettled pressure, a mislabelled
file), so :func:`frames_off_their_step` names such frames for the run to say.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from contactcal.infer.calibration.curve import MM2
from contactcal.infer.calibration.phases import PHASES
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.errors import few


def pool(
    areas: Sequence[float] | np.ndarray, contacts: Sequence[bool] | np.ndarray
) -> tuple[float, bool]:
    """One step's area and contact from its frames: the median area, and in contact when at
    least half of the frames are (the rule of this module, for steps, resamples and labels)."""
    c = np.asarray(contacts, dtype=bool)
    return float(np.median(areas)), 2 * int(c.sum()) >= c.size


#: Fewest frames of a step for one of them to be named off it: with two, the median is their
#: midpoint, both depart from it alike and which one is off cannot be told (the table's min-max
#: column shows the pair's disagreement; record a third frame to have it named).
STEP_OUTLIER_MIN_FRAMES = 3
#: Share of its step's median area a frame must depart from it by to be named. Above the U-Net's
#: ordinary scatter (on the example session its stated 90 % intervals are about ±5 % of the area
#: from 6 kPa up, its band ±1-3 %) and below what a frame of a pressure two steps away does
#: mid-curve (10-20 % at 6-10 kPa). Lower names ordinary scatter; higher hides more bad frames.
#: Near saturation (the top steps differ by ~1 % per kPa) an unsettled frame departs less than
#: this and goes unnamed.
STEP_OUTLIER_SHARE = 0.10
#: The least departure named, in mm²: near the onset a step's areas are a few mm², where
#: a share of the median is a few dozen pixels and a frame just below the model's
#: smallest contact region reads "no contact" beside one just above it. 5 mm² is about twice the
#: shipped U-Net's smallest contact region on the example rig (77.7 network px on its 290-px ring
#: crop: 177 px, 2.8 mm²). Higher hides a frame without contact in the first contact steps (the
#: example's reads 20 mm²); lower names the onset's ordinary flips.
STEP_OUTLIER_FLOOR_MM2 = 5.0
#: The same floor for a curve in px (no pixel scale): 5 mm² at the example rig's 0.126 mm/px is
#: 320 px on its frames, 400 px wide; frames of another width see the same membrane at another
#: pixel scale (mm/px inversely with the width), so the floor scales with the square of the
#: width, (width / 400)² (~13 400 px at 2592 px wide, whatever the height).
STEP_OUTLIER_FLOOR_PX = 320.0  # px, on frames STEP_OUTLIER_FLOOR_WIDTH_PX wide
STEP_OUTLIER_FLOOR_WIDTH_PX = 400  # px


def step_outlier_floor(unit: str, width_px: int) -> float:
    """The least departure :func:`frames_off_their_step` names, in ``unit`` (mm² or px).

    Args:
        unit: the curve's area unit (:data:`~contactcal.infer.calibration.curve.MM2` or ``PX``).
        width_px: the frames' width, px (scales the px floor by its square).

    Returns:
        :data:`STEP_OUTLIER_FLOOR_MM2` in mm², else :data:`STEP_OUTLIER_FLOOR_PX` scaled by
        ``(width_px / STEP_OUTLIER_FLOOR_WIDTH_PX)²``.
    """
    if unit == MM2:
        return STEP_OUTLIER_FLOOR_MM2
    return STEP_OUTLIER_FLOOR_PX * (width_px / STEP_OUTLIER_FLOOR_WIDTH_PX) ** 2


@dataclass(frozen=True)
class OffStep:
    """A frame whose area departs from its step's median beyond its tolerance
    (:func:`frames_off_their_step`); recorded as ``extra.frames_off_their_step``.

    Attributes:
        file: the frame, as the record names it.
        phase: ``"loading"`` or ``"unloading"``.
        pressure_kpa: the step's pressure, kPa.
        area: the frame's area (curve unit; 0 without contact).
        contact: the frame's contact flag.
        step_median: the step's median area (curve unit).
        tolerance: the departure this frame was allowed (curve unit).
    """

    file: str
    phase: str
    pressure_kpa: float
    area: float
    contact: bool
    step_median: float
    tolerance: float


@dataclass(frozen=True, eq=False)
class Step:
    """One pressure step of one phase.

    Attributes:
        phase: ``"loading"`` or ``"unloading"``.
        step: 0-based index within the phase (ascending pressure).
        pressure_kpa: the step's pressure, kPa.
        areas: ``(n,)`` float64 frame areas (the curve's unit), n >= 1.
        contacts: ``(n,)`` bool per frame.
        intervals: per frame, its stated area interval (curve unit) or None.
        files: per frame, its file as the record names it.
    """

    phase: str
    step: int
    pressure_kpa: float
    areas: np.ndarray
    contacts: np.ndarray
    intervals: tuple[tuple[float, float] | None, ...]
    files: tuple[str, ...]

    @property
    def n(self) -> int:
        """Number of frames."""
        return int(self.areas.size)

    @property
    def median(self) -> float:
        """Median frame area (curve unit)."""
        return pool(self.areas, self.contacts)[0]

    @property
    def contact(self) -> bool:
        """True when at least half of the frames are in contact."""
        return pool(self.areas, self.contacts)[1]

    def spread(self) -> dict[str, float]:
        """``min``, ``q25``, ``q75``, ``max`` of the frame areas (curve unit)."""
        q = np.quantile(self.areas, [0.0, 0.25, 0.75, 1.0])
        return {"min": float(q[0]), "q25": float(q[1]), "q75": float(q[2]), "max": float(q[3])}


def group_steps(points: Sequence[CalibrationPoint], unit: str) -> dict[str, list[Step]]:
    """The points grouped into steps by phase and pressure, each phase's steps by pressure.

    Args:
        points: per-frame measurements, any order.
        unit: the curve's area unit (``"mm²"`` needs every point's ``area_mm2``).

    Returns:
        ``{phase: [Step, ...]}`` for the phases present (loading first).

    Raises:
        ValueError: a point without an area in ``unit``.
    """
    out: dict[str, list[Step]] = {}
    for phase in PHASES:
        mine = [r for r in points if r.phase == phase]
        levels = sorted({r.pressure_kpa for r in mine})
        steps = []
        for i, level in enumerate(levels):
            at = [r for r in mine if r.pressure_kpa == level]
            areas = [r.area(unit) for r in at]
            if any(a is None for a in areas):
                raise ValueError(f"{at[0].file}: no area in {unit} (no pixel scale?)")
            steps.append(
                Step(
                    phase,
                    i,
                    float(level),
                    np.asarray(areas, dtype=np.float64),
                    np.asarray([bool(r.contact) for r in at]),
                    tuple(r.interval(unit) for r in at),
                    tuple(r.file for r in at),
                )
            )
        if steps:
            out[phase] = steps
    return out


def frames_off_their_step(steps: Sequence[Step], floor: float) -> list[OffStep]:
    """The frames whose area departs from their step's median by more than their tolerance.

    Only steps of at least :data:`STEP_OUTLIER_MIN_FRAMES` frames are looked at. A frame's
    tolerance is the largest of :data:`STEP_OUTLIER_SHARE` of the median, ``floor``
    (:func:`step_outlier_floor`) and, when the frame states an area interval and agrees with the
    step on contact, the interval's side towards the median (the frame's own stated uncertainty:
    a frame whose interval holds the median is never named). A frame whose contact flag differs
    from its step's (no contact in a step in contact, or the reverse) gets no interval term: its
    interval bounds a region it did not call contact. No division: a step at 0 is safe.

    Args:
        steps: steps of any phases, e.g. every phase's of a fit.
        floor: the least departure named, in the steps' area unit (:func:`step_outlier_floor`).

    Returns:
        The frames named, in the steps' order and each step's frame order.
    """
    out = []
    for s in steps:
        if s.n < STEP_OUTLIER_MIN_FRAMES:
            continue
        m, agree = s.median, s.contact
        frames = zip(s.files, s.areas.tolist(), s.contacts.tolist(), s.intervals, strict=True)
        for file, a, c, iv in frames:
            stated = 0.0 if iv is None or c != agree else (a - iv[0] if a > m else iv[1] - a)
            tolerance = max(STEP_OUTLIER_SHARE * m, floor, stated)
            if abs(a - m) > tolerance:
                out.append(OffStep(file, s.phase, s.pressure_kpa, a, bool(c), m, tolerance))
    return out


def off_step_warning(off: Sequence[OffStep], unit: str, floor: float, listed: int) -> str:
    """The printed warning for :func:`frames_off_their_step`'s frames (at least one, areas and
    ``floor`` in ``unit``), naming the first ``listed``."""
    shown = few([_off_step_line(o, unit) for o in off], listed, "; ")
    those = "that frame" if len(off) == 1 else f"those {len(off)} frames"
    share = f"{100 * STEP_OUTLIER_SHARE:g} %"
    least = f"{floor:g} {unit}" if unit == MM2 else f"{floor:.0f} {unit}"
    return (
        f"warning: {shown}; look at {those} (a slipped finger, an unsettled pressure or a "
        f"mislabelled file): beyond {share} of the step's median, {least} and the frame's own "
        "stated interval (the record's extra.frames_off_their_step)"
    )


def _off_step_line(o: OffStep, unit: str) -> str:
    """One frame of :func:`off_step_warning`: what it reads against its step's median."""
    reads = f"{o.area:.1f} {unit}" if o.contact else "no contact"
    if o.step_median == 0.0:
        how = " (no contact)"
    elif o.contact:
        how = f" ({100.0 * (o.area - o.step_median) / o.step_median:+.0f} %)"
    else:
        how = ""
    return (
        f"step {o.pressure_kpa:g} kPa ({o.phase}): {o.file} reads {reads} against the step's "
        f"median {o.step_median:.1f} {unit}{how}"
    )

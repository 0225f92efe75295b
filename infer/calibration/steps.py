"""Pressure steps: the frames of one phase at one pressure, aggregated by their median area.

A rig records several settled frames per pressure step; the step's area is the MEDIAN of its
frames' areas (robust to one bad frame), with its spread (min-max and interquartile range) and
frame count. The step is in contact when at least half of its frames are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from contactcal.infer.calibration.phases import PHASES
from contactcal.infer.calibration.points import CalibrationPoint


def pool(
    areas: Sequence[float] | np.ndarray, contacts: Sequence[bool] | np.ndarray
) -> tuple[float, bool]:
    """One step's area and contact from its frames: the median area, and in contact when at
    least half of the frames are (the rule of this module, for steps, resamples and labels)."""
    c = np.asarray(contacts, dtype=bool)
    return float(np.median(areas)), 2 * int(c.sum()) >= c.size


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
    """

    phase: str
    step: int
    pressure_kpa: float
    areas: np.ndarray
    contacts: np.ndarray
    intervals: tuple[tuple[float, float] | None, ...]

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
                )
            )
        if steps:
            out[phase] = steps
    return out

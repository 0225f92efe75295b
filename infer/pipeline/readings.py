"""Gauge readings → pressure steps: readings closer than a tolerance are one step.

A manifest written from a pressure logger gives each frame the gauge's reading (5.02, 4.98,
5.01 kPa for three frames of the 5 kPa step), not the step's setpoint. Read as exact values,
every frame would be a step of its own: no repeats are pooled, the leave-one-step-out error
keeps each frame's near-twins in the fit, and the passes are no longer rising then falling.
:func:`step_pressures` gives each reading its step's pressure instead. A manifest of setpoints
(exact, repeated values at least the tolerance apart) comes back unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: kPa. Readings less than this above a step's lowest reading belong to that step: a gauge's
#: jitter at a held pressure (hundredths of a kPa) is well inside it, and no calibration steps
#: its setpoints this finely (the finest used here are 0.25-0.5 kPa apart). A sweep stepped more
#: finely needs ``--step-tolerance-kpa`` below its step (0: every distinct value is a step).
DEFAULT_STEP_TOLERANCE_KPA = 0.1
#: kPa: readings exactly one tolerance apart (0.1-kPa setpoints at tolerance 0.1) stay two steps
#: whatever the rounding of their difference (``0.3 - 0.2 < 0.1`` in floating point).
_ROUNDING_KPA = 1e-9


def step_pressures(readings_kpa: Sequence[float], tolerance_kpa: float) -> list[float]:
    """Each reading's step pressure, in the given order.

    The readings sorted, a step starts at its lowest reading and takes every further reading
    less than ``tolerance_kpa`` above that one; its pressure is the median of its readings.

    Args:
        readings_kpa: ``(N,)`` gauge readings, kPa, any order.
        tolerance_kpa: the step width, kPa, >= 0; 0 keeps every distinct reading a step.

    Returns:
        ``N`` step pressures, kPa (equal to the reading where its step holds one value).

    Raises:
        ValueError: a negative or non-finite tolerance.
    """
    if not (np.isfinite(tolerance_kpa) and tolerance_kpa >= 0.0):
        raise ValueError(
            f"step tolerance {tolerance_kpa!r} kPa: expected a finite value >= 0 (0: every "
            "distinct pressure is a step)"
        )
    p = np.asarray(readings_kpa, dtype=np.float64)
    out = p.copy()
    if tolerance_kpa == 0.0 or p.size == 0:
        return out.tolist()
    order = np.argsort(p, kind="stable")
    start = 0
    for k in range(1, p.size + 1):
        if k < p.size and p[order[k]] - p[order[start]] < tolerance_kpa - _ROUNDING_KPA:
            continue
        members = order[start:k]
        if np.ptp(p[members]) > 0.0:
            out[members] = float(np.median(p[members]))
        start = k
    return out.tolist()

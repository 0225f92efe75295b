"""Hysteresis of a session: the unloading pass against the loading pass."""

from __future__ import annotations

from typing import Any

import numpy as np

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.steps import Step


def hysteresis(
    loading: tuple[list[Step], Curve], unloading: tuple[list[Step], Curve]
) -> dict[str, Any]:
    """Area difference unloading − loading at the pressures both passes have, and the onsets.

    The differences are of the step medians (measured, not fitted), in the curves' unit.

    Args:
        loading: the loading pass's steps and curve.
        unloading: the unloading pass's steps and curve.

    Returns:
        ``{"pressures_kpa": [...], "difference": [...], "max_abs_difference",
        "max_abs_at_kpa", "mean_difference", "onset_kpa": {"loading", "unloading"},
        "onset_shift_kpa"}``; the difference fields are None without a common pressure, the
        shift None when a pass has no onset.
    """
    up = {s.pressure_kpa: s.median for s in loading[0]}
    down = {s.pressure_kpa: s.median for s in unloading[0]}
    common = sorted(set(up) & set(down))
    diff = np.asarray([down[q] - up[q] for q in common], dtype=np.float64)
    on_up, on_down = loading[1].onset_kpa, unloading[1].onset_kpa
    k = int(np.argmax(np.abs(diff))) if diff.size else None
    return {
        "pressures_kpa": common,
        "difference": diff.tolist(),
        "max_abs_difference": None if k is None else float(abs(diff[k])),
        "max_abs_at_kpa": None if k is None else common[k],
        "mean_difference": float(diff.mean()) if diff.size else None,
        "onset_kpa": {"loading": on_up, "unloading": on_down},
        "onset_shift_kpa": None if on_up is None or on_down is None else on_down - on_up,
    }

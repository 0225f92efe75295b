"""Hysteresis of a session: the unloading pass against the loading pass."""

from __future__ import annotations

from typing import Any

import numpy as np

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.steps import Step

#: kPa: an unloading step is compared with the loading step nearest in pressure if they are at
#: most this far apart. Logged step pressures scatter by a few 0.01 kPa around the set point
#: (a video's steps are the median of the controller's log), while set points are >= 0.5 kPa
#: apart on the rig; a quarter kPa matches the same set point and never its neighbour.
MATCH_TOLERANCE_KPA = 0.25


def hysteresis(
    loading: tuple[list[Step], Curve], unloading: tuple[list[Step], Curve]
) -> dict[str, Any]:
    """Area difference unloading − loading at the pressures both passes have, and the onsets.

    The differences are of the step medians (measured, not fitted), in the curves' unit. Each
    unloading step is paired with the loading step nearest in pressure within
    :data:`MATCH_TOLERANCE_KPA` (reported at the loading step's pressure).

    Args:
        loading: the loading pass's steps and curve.
        unloading: the unloading pass's steps and curve.

    Returns:
        ``{"pressures_kpa": [...], "difference": [...], "max_abs_difference",
        "max_abs_at_kpa", "mean_difference", "onset_kpa": {"loading", "unloading"},
        "onset_bracket_kpa": {"loading", "unloading"}, "onset_shift_kpa",
        "onset_shift_range_kpa"}``; the difference fields are None without a common pressure,
        the shift None when a pass has no onset. A pass's onset is only known to lie in its
        bracket ``(lo, hi]`` (the curve's ``onset_bracket_kpa``), so the shift is only known
        to lie in ``(down_lo - up_hi, down_hi - up_lo)``: that range, or None when a pass has
        no onset or is in contact from its lowest pressure (no ``lo``).
    """
    up = {s.pressure_kpa: s.median for s in loading[0]}
    pairs: dict[float, float] = {}
    for s in unloading[0]:
        q = min(up, key=lambda p: abs(p - s.pressure_kpa))
        if abs(q - s.pressure_kpa) <= MATCH_TOLERANCE_KPA and q not in pairs:
            pairs[q] = s.median - up[q]
    common = sorted(pairs)
    diff = np.asarray([pairs[q] for q in common], dtype=np.float64)
    on_up, on_down = loading[1].onset_kpa, unloading[1].onset_kpa
    b_up, b_down = loading[1].onset_bracket_kpa, unloading[1].onset_bracket_kpa
    k = int(np.argmax(np.abs(diff))) if diff.size else None
    return {
        "pressures_kpa": common,
        "matched_within_kpa": MATCH_TOLERANCE_KPA,
        "difference": diff.tolist(),
        "max_abs_difference": None if k is None else float(abs(diff[k])),
        "max_abs_at_kpa": None if k is None else common[k],
        "mean_difference": float(diff.mean()) if diff.size else None,
        "onset_kpa": {"loading": on_up, "unloading": on_down},
        "onset_bracket_kpa": {"loading": _listed(b_up), "unloading": _listed(b_down)},
        "onset_shift_kpa": None if on_up is None or on_down is None else on_down - on_up,
        "onset_shift_range_kpa": _shift_range(b_up, b_down),
    }


def _listed(bracket: tuple[float | None, float] | None) -> list[float | None] | None:
    """A bracket as the record holds it (a list), or None."""
    return None if bracket is None else list(bracket)


def _shift_range(
    up: tuple[float | None, float] | None, down: tuple[float | None, float] | None
) -> list[float] | None:
    """``[down_lo - up_hi, down_hi - up_lo]``, kPa: the onset shift's range given both passes'
    brackets; None unless both have a lower end (a frame without contact below contact)."""
    if up is None or down is None or up[0] is None or down[0] is None:
        return None
    return [down[0] - up[1], down[1] - up[0]]

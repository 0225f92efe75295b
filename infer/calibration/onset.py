"""Contact onset from per-frame contact flags: the contact range and its refined start (numpy).

The onset always lies in its bracket ``(lo, hi]``: ``lo`` the highest pressure without contact
below the contact range, ``hi`` the lowest pressure of the contact range (`onset_bracket`).
How it was placed there is one of the ``*_RULE`` strings (recorded and printed).
"""

from __future__ import annotations

import numpy as np

#: The zero-area crossing of the line through the first two contact steps, inside the bracket.
EXTRAPOLATED_RULE = "extrapolated to zero area from the first two contact steps"
#: The parametric form's fitted onset, inside the bracket.
FITTED_RULE = "the parametric fit's onset"
#: The fit put the onset at or below ``lo``, where the frame shows no contact.
MIDPOINT_BELOW_RULE = (
    "midpoint of the bracket: the fit put the onset at or below the highest pressure without "
    "contact"
)
#: Fewer than two contact steps (or no rising area between them) to extrapolate from.
MIDPOINT_NO_SLOPE_RULE = "midpoint of the bracket: no rising contact steps to extrapolate from"
#: The first contact step's fitted area is 0: contact starts there.
AT_FIRST_RULE = "the first pressure in contact (its fitted area is 0)"
#: Contact from the lowest pressure: no frame without contact below it.
LOWEST_RULE = "the lowest pressure, already in contact (not calibrated below it)"
#: The parametric form's fitted onset with contact from the lowest pressure (within one step
#: below it, >= 0 kPa).
FITTED_BELOW_LOWEST_RULE = (
    "the parametric fit's onset, at most one step below the lowest pressure, already in "
    "contact (not calibrated below it)"
)
#: Rules that say the onset is only known to lie in its bracket (printed as warnings).
MIDPOINT_RULES = (MIDPOINT_BELOW_RULE, MIDPOINT_NO_SLOPE_RULE)


def onset_index(contact_sorted: np.ndarray) -> int | None:
    """Index of the first frame of the contact range, or None (see `curve.estimate_onset`).

    Minimises ``#contact[:s] + #~contact[s:]`` over ``s`` in ``0..N``; ties -> the highest
    ``s < N`` (``N``, i.e. None, only when it is strictly best).
    """
    c = np.asarray(contact_sorted, dtype=bool)
    n = c.size
    hits_below = np.concatenate([[0], np.cumsum(c)])  # contacts in [0, s)
    misses_above = (n - np.arange(n + 1)) - (c.sum() - hits_below)  # misses in [s, n)
    errors = hits_below + misses_above
    best = np.flatnonzero(errors == errors.min())
    best = best[best < n]
    return int(best.max()) if best.size else None


def onset_bracket(p: np.ndarray, s: int) -> tuple[float | None, float]:
    """``(lo, hi)``, kPa: the pressure below the contact range starting at ``s`` (None when
    ``s == 0``: no frame without contact below it) and the range's first pressure."""
    return (float(p[s - 1]) if s > 0 else None), float(p[s])


def refine_onset(p: np.ndarray, fit: np.ndarray, idx: np.ndarray) -> tuple[float, str]:
    """Onset pressure (kPa) from the fit between the first two contact frames, and its rule.

    Args:
        p: ``(N,)`` sorted pressures, kPa.
        fit: ``(N,)`` fitted areas (0 below the contact range).
        idx: indices of the contact frames in the contact range, ascending (``idx[0] = s``).

    Returns:
        ``(onset, rule)``: the zero-area crossing of the line through the first two contact
        frames when it lies strictly inside ``(p[s-1], p[s]]``, else the midpoint of that
        bracket (an onset at or below ``p[s-1]`` would contradict its frame's "no contact");
        ``p[s]`` when ``s == 0`` or the fit is 0 there. ``rule`` is one of the ``*_RULE``
        strings.
    """
    s = int(idx[0])
    hi = float(p[s])
    if s == 0:
        return hi, LOWEST_RULE
    lo = float(p[s - 1])
    f0 = float(fit[s])
    if f0 <= 0:
        return hi, AT_FIRST_RULE
    if idx.size >= 2:
        s1 = int(idx[1])
        slope = (float(fit[s1]) - f0) / (float(p[s1]) - hi)
        if slope > 0:
            crossing = hi - f0 / slope  # < hi, as f0 > 0
            if crossing > lo:
                return crossing, EXTRAPOLATED_RULE
            return 0.5 * (lo + hi), MIDPOINT_BELOW_RULE
    return 0.5 * (lo + hi), MIDPOINT_NO_SLOPE_RULE

"""Contact onset from per-frame contact flags: the contact range and its refined start (numpy)."""

from __future__ import annotations

import numpy as np


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


def refine_onset(p: np.ndarray, fit: np.ndarray, idx: np.ndarray) -> float:
    """Onset pressure (kPa) from the fit between the first two contact frames.

    Args:
        p: ``(N,)`` sorted pressures, kPa.
        fit: ``(N,)`` fitted areas (0 below the contact range).
        idx: indices of the contact frames in the contact range, ascending (``idx[0] = s``).

    Returns:
        The zero-area crossing of the line through the first two contact frames, clamped to
        ``[p[s-1], p[s]]``; ``p[s]`` when ``s == 0``; the midpoint without a usable slope.
    """
    s = int(idx[0])
    hi = float(p[s])
    if s == 0:
        return hi
    lo = float(p[s - 1])
    f0 = float(fit[s])
    if f0 <= 0:
        return hi
    if idx.size >= 2:
        s1 = int(idx[1])
        slope = (float(fit[s1]) - f0) / (float(p[s1]) - hi)
        if slope > 0:
            return float(np.clip(hi - f0 / slope, lo, hi))
    return 0.5 * (lo + hi)

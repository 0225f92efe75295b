"""Input validation and contact-onset helpers for `contactcal.infer.curve` (pure numpy)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def prepare_points(
    pressures_kpa: ArrayLike, areas: ArrayLike, contact: ArrayLike | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate the per-frame points and sort them by pressure.

    Args:
        pressures_kpa: ``(N,)`` pressures, kPa, finite and distinct, N >= 2.
        areas: ``(N,)`` areas, finite and >= 0.
        contact: ``(N,)`` bool, or None for ``areas > 0``.

    Returns:
        ``(p, a, c)``: float64, float64, bool arrays of shape ``(N,)``, sorted by pressure.

    Raises:
        ValueError: what was expected and what was got.
    """
    p = np.asarray(pressures_kpa, dtype=np.float64).reshape(-1)
    a = np.asarray(areas, dtype=np.float64).reshape(-1)
    if contact is None:
        c = a > 0
    else:
        c_raw = np.asarray(contact).reshape(-1)
        if c_raw.dtype != np.bool_ and not np.all(np.isin(c_raw, (0, 1))):
            raise ValueError(f"contact: expected booleans, got values {np.unique(c_raw)[:5]}")
        c = c_raw.astype(bool)
    if not (p.size == a.size == c.size):
        raise ValueError(
            f"expected one pressure, area and contact flag per frame, got lengths {p.size}, "
            f"{a.size}, {c.size}"
        )
    if p.size < 2:
        raise ValueError(f"a calibration needs >= 2 pressure steps, got {p.size}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"pressures must be finite (kPa), got {p[~np.isfinite(p)][:5]}")
    bad = ~np.isfinite(a) | (a < 0)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"areas must be finite and >= 0, got {a[i]} at pressure {p[i]} kPa "
            f"({int(bad.sum())} bad value(s))"
        )
    order = np.argsort(p, kind="stable")
    p, a, c = p[order], a[order], c[order]
    dup = np.flatnonzero(np.diff(p) == 0)
    if dup.size:
        raise ValueError(
            f"duplicate pressure {p[dup[0]]} kPa: expected one frame per pressure step"
        )
    return p, a, c


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

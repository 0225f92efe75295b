"""Monotone regression primitives (pure numpy): pool-adjacent-violators and a running median.

Used by `contactcal.infer.calibration.fit` to fit the contact-area-vs-pressure curve.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def isotonic_fit(x: ArrayLike, y: ArrayLike, w: ArrayLike | None = None) -> np.ndarray:
    """Weighted least-squares non-decreasing fit of ``y`` against ``x`` (pool adjacent violators).

    Minimises ``sum(w * (f - y)**2)`` subject to ``f`` non-decreasing in ``x``. Points with equal
    ``x`` are first pooled into their weighted mean (so they share one fitted value).

    Args:
        x: ``(N,)`` float, the ordering variable (e.g. pressure, kPa); any order.
        y: ``(N,)`` float, values to fit (any unit).
        w: ``(N,)`` float weights > 0, or None for unit weights.

    Returns:
        ``(N,)`` float64 fitted values, aligned with the input order (``f[i]`` belongs to
        ``x[i]``). Every value lies within ``[min(y), max(y)]``.

    Raises:
        ValueError: mismatched lengths, empty input, non-finite values, or weights <= 0.
    """
    xa = np.asarray(x, dtype=np.float64).reshape(-1)
    ya = np.asarray(y, dtype=np.float64).reshape(-1)
    wa = np.ones_like(ya) if w is None else np.asarray(w, dtype=np.float64).reshape(-1)
    if not (xa.size == ya.size == wa.size):
        raise ValueError(
            f"isotonic_fit: x, y and w must have the same length, got {xa.size}, {ya.size}, "
            f"{wa.size}"
        )
    if xa.size == 0:
        raise ValueError("isotonic_fit: expected at least one point, got none")
    for name, arr in (("x", xa), ("y", ya), ("w", wa)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"isotonic_fit: {name} must be finite, got NaN or inf")
    if np.any(wa <= 0):
        raise ValueError("isotonic_fit: weights must be > 0")

    # Pool ties in x, then run PAVA over the unique x values (already sorted by np.unique).
    ux, inverse = np.unique(xa, return_inverse=True)
    gw = np.bincount(inverse, weights=wa, minlength=ux.size)
    gy = np.bincount(inverse, weights=wa * ya, minlength=ux.size) / gw
    fitted = _pava(gy, gw)
    # Clip guards against round-off pushing a pooled mean a hair outside the data range.
    return np.clip(fitted[inverse], ya.min(), ya.max())


def _pava(y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Pool adjacent violators on already-ordered ``(M,)`` values ``y`` with weights ``w``."""
    means: list[float] = []
    weights: list[float] = []
    counts: list[int] = []
    for yi, wi in zip(y.tolist(), w.tolist(), strict=True):
        means.append(yi)
        weights.append(wi)
        counts.append(1)
        # Merge backwards while the last block violates monotonicity.
        while len(means) > 1 and means[-2] > means[-1]:
            m1, w1, c1 = means.pop(), weights.pop(), counts.pop()
            wt = weights[-1] + w1
            means[-1] = (means[-1] * weights[-1] + m1 * w1) / wt
            weights[-1] = wt
            counts[-1] += c1
    return np.repeat(np.asarray(means, dtype=np.float64), counts)


def despike(y: ArrayLike, window: int = 3) -> np.ndarray:
    """Replace isolated outliers by a running median, worst point first; monotone data unchanged
    but for the last value's end rule below.

    The median of a monotone window is its middle value, so on monotone data every interior
    point already equals its window median and nothing changes (no bias on a genuine curve). An
    isolated spike or dip differs from its window median and is replaced by it. Points are
    fixed one at a time, the largest deviation first (interior points win ties), and the
    medians recomputed: a plain one-pass running median would also lift the right neighbour
    of a spike (``median(spike, y[i+1], y[i+2]) = y[i+2]``), a sequential one does not.

    Windows shrink symmetrically near the ends. End rules: the first value's target is
    ``min(y0, median(y0, y1, 3 y1 - 2 y2))`` (a high first value is lowered to the trend, a
    low one is kept: it is the start of the curve); the last value's target is Tukey's
    ``median(y[-1], y[-2], 3 y[-2] - 2 y[-3])`` (a last value below the previous one, or more
    than twice the previous step above it, is pulled back to the trend). That end rule also
    lowers a genuine last value of a monotone curve whose last step is more than twice the one
    before (steps in samples, not kPa): on a plateau where steps are noise, e.g. +0.2 then
    +0.6 mm² gives -0.2 mm², so an area measured at the top step can read as above the
    calibrated maximum.

    Args:
        y: ``(N,)`` float values, ordered by the independent variable (e.g. pressure).
        window: odd window length in samples, >= 1 (1 returns a copy).

    Returns:
        ``(N,)`` float64 values, each within ``[min(y), max(y)]``.
    """
    out = np.array(y, dtype=np.float64).reshape(-1)
    if window < 1 or window % 2 == 0:
        raise ValueError(f"despike: window must be an odd integer >= 1, got {window}")
    n = out.size
    if window == 1 or n < 3:
        return out
    h = min(window // 2, (n - 1) // 2)
    tol = 1e-12 * max(1.0, float(np.max(np.abs(out))))
    for _ in range(4 * n):  # a bound; in practice a few fixes per outlier
        target = out.copy()
        target[h : n - h] = np.median(np.lib.stride_tricks.sliding_window_view(out, 2 * h + 1), 1)
        for k in range(1, h):  # shrinking windows near the ends
            target[k] = np.median(out[: 2 * k + 1])
            target[n - 1 - k] = np.median(out[n - 2 * k - 1 :])
        target[0] = min(out[0], np.median([out[0], out[1], 3.0 * out[1] - 2.0 * out[2]]))
        target[-1] = np.median([out[-1], out[-2], 3.0 * out[-2] - 2.0 * out[-3]])
        dev = np.abs(out - target)
        dev[[0, -1]] *= 1.0 - 1e-9  # ties: fix an interior point before an end point
        i = int(np.argmax(dev))
        if dev[i] <= tol:
            break
        out[i] = target[i]
    return out

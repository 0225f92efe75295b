"""Percentiles of a frame's pixels, equal to ``np.percentile``'s (method ``"linear"``), cheaply.

``np.percentile`` partitions a copy of the array and, on its first call in a process, imports
``numpy.ma`` (~20 ms here, paid by every ``measure`` and ``calibrate``); per call it costs
~0.8 ms on a 324×243 uint8 frame. :func:`percentiles` gives the same numbers, bit for bit
(``tests/test_percentile.py`` compares them), from a 256-bin histogram for ``uint8`` images
(~0.1 ms) and from one ``np.partition`` otherwise: the order statistics around the virtual
index ``(n - 1) q / 100``, interpolated as numpy's ``_lerp`` does.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def _lerp(a: np.generic, b: np.generic, t: float) -> float:
    """numpy's linear interpolation between order statistics ``a <= b`` (same rounding).

    As ``np.percentile`` with a Python-float percentile: the arithmetic stays in the array's
    dtype where it is a float (float32 frames interpolate in float32), an integer one goes to
    float64; from ``t = 0.5`` on, numpy interpolates back from ``b``.
    """
    diff = b - a  # in the array's dtype: b >= a, so no unsigned wrap-around
    if t >= 0.5:
        return float(b - diff * (1.0 - t))
    return float(a + diff * t)


def _indices(n: int, qs: Sequence[float]) -> list[tuple[int, int, float]]:
    """Per percentile: the lower and upper order statistic and the weight of the upper one."""
    out = []
    for q in qs:
        if not 0.0 <= q <= 100.0:
            raise ValueError(f"percentile must be in [0, 100], got {q}")
        virtual = (n - 1) * (q / 100.0)
        lo = math.floor(virtual)
        if virtual >= n - 1:  # q = 100 (or rounding at it): the maximum
            out.append((n - 1, n - 1, 0.0))
        else:
            out.append((lo, lo + 1, virtual - lo))
    return out


def percentiles(values: np.ndarray, qs: Sequence[float]) -> tuple[float, ...]:
    """The ``qs``-th percentiles of all elements, as ``np.percentile(values, q)`` gives them
    for each Python-float ``q`` (numpy's weak promotion: a float32 array's in float32).

    Args:
        values: any shape; ``uint8`` (a frame: histogram path) or any real dtype.
        qs: percentiles, each in [0, 100] (e.g. ``(99.5, 50.0)``: a bright level and the
            median, which for integer images equals ``np.median``).

    Returns:
        One float per percentile; NaN when a float array holds a NaN (as numpy).

    Raises:
        ValueError: empty ``values`` or a percentile outside [0, 100].
    """
    flat = values.ravel()
    n = flat.size
    if n == 0:
        raise ValueError("percentiles of an empty array: expected at least one value")
    where = _indices(n, qs)
    if flat.dtype == np.uint8:
        below = np.cumsum(np.bincount(flat, minlength=256))  # below[v]: count of values <= v
        ranks = np.array([k for lo, hi, _ in where for k in (lo, hi)])
        stats = np.searchsorted(below, ranks, side="right").astype(np.uint8)
        pairs = stats.reshape(-1, 2)
        return tuple(_lerp(a, b, t) for (a, b), (_, _, t) in zip(pairs, where, strict=True))
    kth = sorted({k for lo, hi, _ in where for k in (lo, hi)} | {n - 1})
    part = np.partition(flat, kth)
    if np.issubdtype(part.dtype, np.inexact) and np.isnan(part[n - 1]):
        return tuple(math.nan for _ in qs)  # NaN sorts last; numpy's answer is NaN
    return tuple(_lerp(part[lo], part[hi], t) for lo, hi, t in where)

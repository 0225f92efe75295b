"""Lookups on a piecewise-linear, non-decreasing curve ``y(x)`` (pure numpy): the lowest
``x`` reaching a value and, just above it, the end of a flat segment at that value. The curve's
inverse (:mod:`~contactcal.infer.calibration.curve`) and its band's edges
(:mod:`~contactcal.infer.calibration.band`) invert through them."""

from __future__ import annotations

import numpy as np


def lowest_reaching(x: np.ndarray, y: np.ndarray, a: float) -> float:
    """Lowest ``x`` at which the piecewise-linear, non-decreasing ``y(x)`` reaches ``a``.

    Args:
        x: ``(N,)`` increasing abscissae (kPa).
        y: ``(N,)`` non-decreasing values.
        a: target; ``x[0]`` when ``a <= y[0]``, ``x[-1]`` when ``a > y[-1]`` (callers warn).
    """
    if a <= y[0]:
        return float(x[0])
    if a > y[-1]:
        return float(x[-1])
    k = int(np.searchsorted(y, a, side="left"))  # y[k-1] < a <= y[k]
    t = (a - y[k - 1]) / (y[k] - y[k - 1])
    return float(x[k - 1] + t * (x[k] - x[k - 1]))


def highest_at(x: np.ndarray, y: np.ndarray, a: float) -> float:
    """Where `lowest_reaching` goes just above ``a``: the highest ``x`` at which ``y`` equals
    ``a`` (the end of a flat segment at ``a``), else ``lowest_reaching(x, y, a)``.

    Args:
        x: ``(N,)`` increasing abscissae (kPa).
        y: ``(N,)`` non-decreasing values.
        a: target.
    """
    at = np.flatnonzero(y == a)
    return float(x[at[-1]]) if at.size else lowest_reaching(x, y, a)

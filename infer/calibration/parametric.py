"""Physics-informed parametric curve: onset plus saturating growth (numpy least squares).

Form (Hill type, exponent 1): ``A(p) = A_max · x / (K + x)`` with ``x = p − p0`` for ``p > p0``
and ``A = 0`` below the onset ``p0``. As the mechanics model (``docs/mechanics.md``), the area
grows from the onset and saturates towards the pad size ``A_max``; ``K`` (kPa) is the pressure
above the onset at which half of it is reached. Its inverse is analytic and smooth:
``p = p0 + K · A / (A_max − A)``. On the example session's exact areas this form fits with an
RMS residual of 0.65 mm² (the exponential ``A_max (1 − exp(−x/s))``: 1.4 mm²), and it follows
the sub-linear, saturating trend of the reference fingertip data
(``shared/reference/fingertip_contact_area.csv``).

The fit is a least-squares fit by variable projection: for given ``(p0, K)`` the best ``A_max``
is linear (closed form), so only ``(p0, K)`` are searched, on a grid refined around its best cell
(deterministic, no scipy).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Grid points per parameter and zoom rounds of the search (cost ∝ points² × rounds). Each round
#: halves the window around the best point (a slow zoom follows the diagonal valley of p0 and
#: K); the final cell is 2^-rounds / points of the initial range (~1e-6 of it).
_GRID = 32
_ROUNDS = 14


@dataclass(frozen=True)
class Saturating:
    """``A(p) = a_max · (p − p0) / (k + p − p0)`` above ``p0``, 0 below.

    Attributes:
        p0_kpa: onset, kPa.
        k_kpa: half-saturation pressure above the onset, kPa, > 0.
        a_max: saturation area (the curve's area unit), > 0.
    """

    p0_kpa: float
    k_kpa: float
    a_max: float

    def area(self, p_kpa: np.ndarray | float) -> np.ndarray:
        """Area at ``p_kpa`` (any shape), same shape, float64; 0 at and below the onset."""
        x = np.maximum(np.asarray(p_kpa, dtype=np.float64) - self.p0_kpa, 0.0)
        return self.a_max * x / (self.k_kpa + x)

    def pressure(self, area: float) -> float:
        """The pressure (kPa) at which the area reaches ``area``, ``0 <= area < a_max``."""
        return self.p0_kpa + self.k_kpa * area / (self.a_max - area)


def _profile(p: np.ndarray, y: np.ndarray, p0: np.ndarray, k: np.ndarray) -> tuple:
    """Best ``a_max`` and the residual sum of squares for every ``(p0, k)`` pair (broadcast)."""
    x = np.maximum(p[None, None, :] - p0[:, None, None], 0.0)
    g = x / (k[None, :, None] + x)
    gg = np.einsum("ijn,ijn->ij", g, g)
    gy = np.einsum("ijn,n->ij", g, y)
    a = np.where(gg > 0, gy / np.where(gg > 0, gg, 1.0), 0.0)
    rss = np.einsum("n,n->", y, y) - np.where(a > 0, a * gy, 0.0)
    return a, rss


def fit_saturating(
    pressures_kpa: np.ndarray, areas: np.ndarray, p0_bounds: tuple[float, float]
) -> Saturating | None:
    """Least-squares fit of the saturating form to contact points.

    Args:
        pressures_kpa: ``(M,)`` pressures of the contact points, kPa, M >= 3.
        areas: ``(M,)`` areas there (> 0 for a useful fit).
        p0_bounds: ``(lo, hi)`` range of the onset, kPa, ``hi <= min(pressures_kpa)``.

    Returns:
        The fitted :class:`Saturating`, or None when fewer than 3 points or no positive fit.
    """
    p = np.asarray(pressures_kpa, dtype=np.float64)
    y = np.asarray(areas, dtype=np.float64)
    if p.size < 3 or not np.any(y > 0):
        return None
    lo, hi = float(p0_bounds[0]), float(p0_bounds[1])
    span = max(float(p.max() - p.min()), 1e-6)
    top = max(lo, hi - 1e-9 * span)  # the onset stays below the first contact point
    p0_lo, p0_hi = lo, top
    logk_lo, logk_hi = np.log(span * 1e-3), np.log(span * 1e2)
    best = (np.inf, p0_hi, float(np.exp(logk_lo)), 0.0)
    for _ in range(_ROUNDS):
        p0 = np.linspace(p0_lo, p0_hi, _GRID) if p0_hi > p0_lo else np.array([p0_hi])
        logk = np.linspace(logk_lo, logk_hi, _GRID)
        a, rss = _profile(p, y, p0, np.exp(logk))
        rss = np.where(a > 0, rss, np.inf)
        i, j = np.unravel_index(int(np.argmin(rss)), rss.shape)
        if rss[i, j] < best[0]:
            best = (float(rss[i, j]), float(p0[i]), float(np.exp(logk[j])), float(a[i, j]))
        dp = (p0_hi - p0_lo) / 4
        dk = (logk_hi - logk_lo) / 4
        p0_lo, p0_hi = max(lo, best[1] - dp), min(top, best[1] + dp)
        logk_lo, logk_hi = np.log(best[2]) - dk, np.log(best[2]) + dk
    if not np.isfinite(best[0]) or best[3] <= 0:
        return None
    return Saturating(best[1], best[2], best[3])

"""The curve's uncertainty band by bootstrap over pressure steps (seeded numpy Generator).

Each resample rebuilds every step's median area and contact flag, then refits the curve with
the session's chosen model; the band is the pointwise 5th-95th percentile (:data:`BAND_LEVEL`,
90 %) of the refitted curves on a pressure grid, widened where needed to contain the fit itself
(a percentile band of a biased estimator may miss it; the band never excludes the curve).

How a step is resampled (each frame's own uncertainty, best source first):

- a frame with a stated interval (the method's 90 % interval): a split-normal draw around its
  area, each side's sigma = that side's half-width / 1.645, clipped at 0;
- a step of several frames: its frames resampled with replacement (the median and the contact
  majority recomputed) — the step's spread;
- a single frame without interval in the contact range: the fitted area plus a residual drawn
  from the contact steps' centred residuals (median − fit) — the steps' scatter about the fit.

Steps below the contact range keep their frames. So the band shows the measurement noise
propagated through the fit; a bias shared by all frames (the method's systematic error) is
not in it.

Where the contact starts is known only to lie in the onset's bracket (between the highest
pressure without contact and the lowest in contact); the resamples keep most contact flags,
so they would not show that. The band therefore also holds every non-decreasing curve that is
0 up to the bracket's low end and reaches the upper edge at its high end (`_cover_bracket`):
an area below the first contact step's maps to the whole bracket, however the fit placed
the onset inside it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from contactcal.infer.calibration.band import Band
from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.steps import Step, pool

#: Coverage level of the band (5th to 95th percentile).
BAND_LEVEL = 0.9
_Z90 = 1.6448536269514722  # standard-normal 95th percentile: 90 % interval = ±1.645 sigma
#: Points of the band's pressure grid besides the steps (resolution of the band's inverse).
_GRID_POINTS = 121
#: Fraction of the onset's bracket between its ends and the grid points just inside them.
_BRACKET_EDGE = 1e-6

Refit = Callable[[np.ndarray, np.ndarray, np.ndarray], "Curve | None"]


def band_grid(curve: Curve) -> np.ndarray:
    """``(G,)`` pressures (kPa): an even grid over the calibrated range, the steps, the onset,
    and points just inside the onset's bracket (where `_cover_bracket` steps the edges)."""
    p = curve.pressures_kpa
    extra = [] if curve.onset_kpa is None else [curve.onset_kpa]
    bracket = curve.onset_bracket_kpa
    if bracket is not None and bracket[0] is not None:
        eps = _BRACKET_EDGE * (bracket[1] - bracket[0])
        extra += [bracket[0] + eps, bracket[1] - eps]
    grid = np.union1d(np.linspace(p[0], p[-1], _GRID_POINTS), [*p, *extra])
    return grid[(grid >= min(p[0], *extra)) & (grid <= p[-1])]


def _cover_bracket(
    grid: np.ndarray, lo: np.ndarray, hi: np.ndarray, curve: Curve
) -> tuple[np.ndarray, np.ndarray]:
    """The edges widened over the onset's bracket ``(b0, b1]``: the lower edge 0 below ``b1``,
    the upper edge at least its value at ``b1`` above ``b0`` (unchanged without a bracket or
    without a pressure without contact below the contact range)."""
    bracket = curve.onset_bracket_kpa
    if bracket is None or bracket[0] is None:
        return lo, hi
    b0, b1 = bracket
    top = float(np.interp(b1, grid, hi))
    lo = np.where(grid < b1, 0.0, lo)
    hi = np.where((grid > b0) & (grid <= b1), np.maximum(hi, top), hi)
    return lo, hi


def _draw_frames(step: Step, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One resample of a step's frames: areas (with interval draws) and contact flags."""
    pick = rng.integers(0, step.n, step.n) if step.n >= 2 else np.zeros(1, dtype=np.int64)
    areas = step.areas[pick].copy()
    z = rng.standard_normal(pick.size)
    for k, i in enumerate(pick.tolist()):
        iv = step.intervals[i]
        if iv is not None:
            side = iv[1] - areas[k] if z[k] > 0 else areas[k] - iv[0]
            areas[k] = max(0.0, areas[k] + z[k] * max(side, 0.0) / _Z90)
    return areas, step.contacts[pick]


def _residuals(steps: Sequence[Step], curve: Curve) -> np.ndarray:
    """Centred residuals (median − fit) of the steps in contact where the fit is > 0."""
    r = [
        s.median - curve.area_at(s.pressure_kpa)
        for s in steps
        if s.contact and curve.area_at(s.pressure_kpa) > 0
    ]
    out = np.asarray(r, dtype=np.float64)
    return out - out.mean() if out.size else out


def bootstrap_band(
    steps: Sequence[Step], curve: Curve, refit: Refit, n_resamples: int, seed: int
) -> Band:
    """The curve's band at :data:`BAND_LEVEL` (see the module docstring for the resampling).

    Args:
        steps: the phase's steps (ascending pressure), those the curve was fitted to.
        curve: the fitted curve (the band contains it).
        refit: ``(pressures, medians, contacts) -> Curve | None``, the same model as ``curve``.
        n_resamples: bootstrap resamples (>= 20).
        seed: seed of the ``numpy.random.Generator``.

    Returns:
        The :class:`Band` on `band_grid` (``n_resamples``: those whose refit gave a curve).
    """
    rng = np.random.default_rng(seed)
    grid = band_grid(curve)
    p = np.asarray([s.pressure_kpa for s in steps])
    resid = _residuals(steps, curve)
    in_range = np.asarray([s.contact and curve.area_at(s.pressure_kpa) > 0 for s in steps])
    fitted = np.asarray([curve.area_at(q) for q in p])
    curves = []
    for _ in range(n_resamples):
        med = np.empty(p.size)
        con = np.empty(p.size, dtype=bool)
        for j, s in enumerate(steps):
            areas, contacts = _draw_frames(s, rng)
            if s.n == 1 and s.intervals[0] is None and in_range[j] and resid.size:
                areas = np.array([max(0.0, fitted[j] + resid[rng.integers(resid.size)])])
            med[j], con[j] = pool(areas, contacts)
        again = refit(p, med, con)
        if again is not None and again.has_contact:
            curves.append([again.area_at(q) for q in grid])
    fit = np.asarray([curve.area_at(q) for q in grid])
    lo = hi = fit
    if len(curves) >= 2:
        tail = (1 - BAND_LEVEL) / 2
        lo, hi = np.quantile(np.asarray(curves), [tail, 1 - tail], axis=0)
        lo = np.maximum.accumulate(np.minimum(lo, fit))
        hi = np.maximum.accumulate(np.maximum(hi, fit))
    lo, hi = _cover_bracket(grid, lo, hi, curve)
    return Band(grid, lo, hi, BAND_LEVEL, len(curves), seed)

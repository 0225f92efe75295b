"""A curve's uncertainty band: lower and upper area vs pressure, and its inverse (numpy).

Made by :func:`contactcal.infer.calibration.bootstrap.bootstrap_band`; stored in
``calibration.json`` under each phase's ``band``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contactcal.infer.calibration.piecewise import highest_at, lowest_reaching


@dataclass(frozen=True, eq=False)
class Band:
    """Pointwise band of the fitted area at ``level`` (e.g. 0.9: 5th to 95th percentile).

    Attributes:
        pressures_kpa: ``(G,)`` strictly increasing grid, kPa.
        lo: ``(G,)`` non-decreasing lower edge (area unit of the curve), >= 0.
        hi: ``(G,)`` non-decreasing upper edge, ``>= lo``.
        level: the band's coverage level, in (0, 1).
        n_resamples: bootstrap resamples the band was made from (those that gave a curve).
        seed: seed of the resampling generator.
    """

    pressures_kpa: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    level: float
    n_resamples: int
    seed: int

    def __post_init__(self) -> None:
        arrays = [
            np.array(a, dtype=np.float64).reshape(-1)
            for a in (self.pressures_kpa, self.lo, self.hi)
        ]
        x, lo, hi = arrays
        if not (x.size == lo.size == hi.size >= 2):
            raise ValueError(
                f"Band: expected equal lengths >= 2, got {x.size}, {lo.size}, {hi.size}"
            )
        if not all(np.all(np.isfinite(a)) for a in arrays):
            raise ValueError("Band: pressures and edges must be finite")
        if np.any(np.diff(x) <= 0) or np.any(np.diff(lo) < 0) or np.any(np.diff(hi) < 0):
            raise ValueError("Band: pressures must increase and edges must not decrease")
        if np.any(lo < 0) or np.any(hi < lo):
            raise ValueError("Band: expected 0 <= lo <= hi")
        if not (0 < float(self.level) < 1) or not math.isfinite(self.level):
            raise ValueError(f"Band: level must be in (0, 1), got {self.level}")
        for name, a in zip(("pressures_kpa", "lo", "hi"), arrays, strict=True):
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    def at(self, p_kpa: float) -> tuple[float, float]:
        """``(lo, hi)`` area at ``p_kpa`` (linear between grid points, held beyond its ends)."""
        x = self.pressures_kpa
        return float(np.interp(p_kpa, x, self.lo)), float(np.interp(p_kpa, x, self.hi))

    def pressure_bounds(self, area: float, above: bool = False) -> tuple[float, float, str | None]:
        """``(p_lo, p_hi, warning)``: pressures (kPa) where the upper / lower edge reach ``area``.

        ``area == 0`` gives where each edge leaves 0 (the band of the onset). An end the band
        does not reach within its grid is clamped to the grid's top pressure, and the warning
        says so; otherwise the warning is None. ``above``: the bounds just above ``area``
        (where an edge holds ``area`` over a pressure range, the range's end, where the edge
        rises again; :func:`~contactcal.infer.calibration.piecewise.highest_at`).
        """
        x = self.pressures_kpa
        # area 0: where each edge leaves 0 (its onset), not the grid's first pressure
        target = max(area, 1e-12 * max(float(self.hi[-1]), 1.0))
        reach = highest_at if above else lowest_reaching
        p_lo = reach(x, self.hi, target)
        p_hi = reach(x, self.lo, target)
        notes = []
        for edge, top in (("upper", self.hi[-1]), ("lower", self.lo[-1])):
            if area > top:
                notes.append(
                    f"the band's {edge} edge ({top:.4g}) stays below {area:.4g}; its bound is "
                    f"clamped to {x[-1]:.4g} kPa"
                )
        return p_lo, p_hi, "; ".join(notes) or None

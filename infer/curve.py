"""Contact area vs pressure: robust monotone fit, contact onset, and the inverse for the controller.

Pure numpy. Pipeline (`fit_monotone`): sort by pressure -> find the contact range from the
per-frame contact flags (`estimate_onset` rule) -> isolated outliers among the contact
frames' areas replaced by a running median (`despike`) -> isotonic (PAVA) fit -> area forced
to 0 below the onset -> `Curve`, which evaluates the fit (`Curve.area_at`) and inverts it
(`Curve.pressure_for_area`, `Curve.inverse_table`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from contactcal.infer.isotonic import despike, isotonic_fit
from contactcal.infer.onset import onset_index, prepare_points, refine_onset

__all__ = [
    "Curve",
    "CurveConfig",
    "despike",
    "estimate_onset",
    "fit_monotone",
    "isotonic_fit",
]


@dataclass(frozen=True)
class CurveConfig:
    """Settings of the area-vs-pressure fit."""

    # frames, odd >= 1: running-median width before PAVA. 3 removes isolated outliers; 5 also
    # pairs of them, but flattens genuine knees sharper than the window. 1 disables.
    median_window: int = 3
    # area unit (mm² or px) per inverse-table row; None = a 1-2-5 step giving <= table_max_rows
    # rows. Finer only makes the table longer: the controller interpolates linearly anyway.
    table_step: float | None = None
    # rows: size target of the automatic inverse-table step (readability vs resolution).
    table_max_rows: int = 100

    def __post_init__(self) -> None:
        if self.median_window < 1 or self.median_window % 2 == 0:
            raise ValueError(
                f"median_window: expected an odd integer >= 1, got {self.median_window}"
            )
        if self.table_step is not None and not (
            math.isfinite(self.table_step) and self.table_step > 0
        ):
            raise ValueError(
                f"table_step: expected a finite value > 0 or None, got {self.table_step}"
            )
        if self.table_max_rows < 2:
            raise ValueError(f"table_max_rows: expected >= 2, got {self.table_max_rows}")


@dataclass(frozen=True, eq=False)
class Curve:
    """Fitted, non-decreasing contact area vs pressure.

    Attributes:
        pressures_kpa: ``(N,)`` float64, strictly increasing frame pressures, kPa.
        fit_area: ``(N,)`` float64, non-decreasing fitted area at each pressure (area_unit).
        onset_kpa: contact onset pressure, kPa (area is 0 below it), or None if no contact.
        area_unit: ``"mm²"`` or ``"px"``.
        table_step: default area step of `inverse_table` (area_unit), or None for automatic.
        table_max_rows: row target of the automatic step.
    """

    pressures_kpa: np.ndarray
    fit_area: np.ndarray
    onset_kpa: float | None
    area_unit: str = "mm²"
    table_step: float | None = None
    table_max_rows: int = 100

    def __post_init__(self) -> None:
        p = np.array(self.pressures_kpa, dtype=np.float64).reshape(-1)
        f = np.array(self.fit_area, dtype=np.float64).reshape(-1)
        if p.size != f.size or p.size == 0:
            raise ValueError(f"Curve: expected equal, non-zero lengths, got {p.size} and {f.size}")
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(f))):
            raise ValueError("Curve: pressures and fitted areas must be finite")
        if np.any(np.diff(p) <= 0):
            raise ValueError("Curve: pressures_kpa must be strictly increasing")
        if np.any(f < 0) or np.any(np.diff(f) < 0):
            raise ValueError("Curve: fit_area must be >= 0 and non-decreasing")
        onset = self.onset_kpa
        if onset is not None:
            onset = float(onset)
            if not math.isfinite(onset):
                raise ValueError(f"Curve: onset_kpa must be finite or None, got {onset}")
        p.setflags(write=False)
        f.setflags(write=False)
        object.__setattr__(self, "pressures_kpa", p)
        object.__setattr__(self, "fit_area", f)
        object.__setattr__(self, "onset_kpa", onset)

    @property
    def has_contact(self) -> bool:
        """True when the curve can be inverted (an onset and a positive fitted area)."""
        return self.onset_kpa is not None and float(self.fit_area[-1]) > 0

    def knots(self) -> tuple[np.ndarray, np.ndarray]:
        """Breakpoints ``(pressure kPa, area)`` of the piecewise-linear curve from the onset up.

        Starts at ``(onset, 0)``, or at the first contact frame when the curve jumps there
        (no frame without contact below it). Below the first knot the area is 0.
        """
        p, f = self.pressures_kpa, self.fit_area
        if self.onset_kpa is None:
            return p.copy(), f.copy()
        on = self.onset_kpa
        at = p == on
        if np.any(at) and float(f[at][0]) > 0:
            keep = p >= on
            return p[keep], f[keep]
        above = p > on
        return np.concatenate([[on], p[above]]), np.concatenate([[0.0], f[above]])

    def area_at(self, p_kpa: float) -> float:
        """Fitted area (area_unit) at ``p_kpa``: 0 below the onset, linear between knots, held
        at the last fitted value above the calibrated maximum pressure."""
        q = float(p_kpa)
        if not math.isfinite(q):
            raise ValueError(f"area_at: expected a finite pressure in kPa, got {p_kpa}")
        if self.onset_kpa is None:
            return 0.0
        x, y = self.knots()
        if q < x[0]:
            return 0.0
        return float(np.interp(q, x, y))

    def area_range(self) -> tuple[float, float]:
        """``(min, max)`` invertible area (area_unit): ``min`` is 0 unless the curve jumps."""
        _, y = self.knots()
        return float(y[0]), float(y[-1])

    def pressure_for_area(self, area: float) -> tuple[float, str | None]:
        """Lowest pressure (kPa) at which the fit reaches ``area``, and a warning or None.

        Linear interpolation on the fit; on a flat segment the lowest pressure of the segment
        is returned. ``area == 0`` gives the onset. A target outside the calibrated range is
        clamped to its end and the second element says so (e.g. ``"target 300 mm² above
        calibrated maximum 250 mm² at 20 kPa; clamped"``).

        Raises:
            ValueError: non-finite or negative ``area``, or a curve without contact.
        """
        a = float(area)
        if not math.isfinite(a) or a < 0:
            raise ValueError(f"pressure_for_area: expected a finite area >= 0, got {area}")
        if not self.has_contact:
            raise ValueError("no contact in this calibration; cannot invert")
        x, y = self.knots()
        u = self.area_unit
        if a > y[-1]:
            k = int(np.searchsorted(y, y[-1], side="left"))
            msg = (
                f"target {a:.4g} {u} above calibrated maximum {y[-1]:.4g} {u} at "
                f"{x[k]:.4g} kPa; clamped"
            )
            return float(x[k]), msg
        if a <= y[0]:
            if a < y[0]:
                msg = (
                    f"target {a:.4g} {u} below smallest calibrated area {y[0]:.4g} {u} at "
                    f"{x[0]:.4g} kPa (no frame without contact below it); clamped"
                )
                return float(x[0]), msg
            return float(x[0]), None
        k = int(np.searchsorted(y, a, side="left"))  # y[k-1] < a <= y[k]
        t = (a - y[k - 1]) / (y[k] - y[k - 1])
        return float(x[k - 1] + t * (x[k] - x[k - 1])), None

    def default_table_step(self) -> float:
        """The inverse-table step used when none is given (area_unit)."""
        if self.table_step is not None:
            return float(self.table_step)
        lo, hi = self.area_range()
        return _nice_step((hi - lo) / self.table_max_rows)

    def inverse_table(self, step: float | None = None) -> list[tuple[float, float]]:
        """``[(area, pressure_kpa), ...]`` from the smallest to the largest calibrated area.

        Rows at the smallest area, every multiple of ``step`` in between, and the largest area.

        Args:
            step: area step (area_unit) > 0; None uses `default_table_step`.

        Raises:
            ValueError: bad step, or a curve without contact.
        """
        if not self.has_contact:
            raise ValueError("no contact in this calibration; cannot invert")
        s = self.default_table_step() if step is None else float(step)
        if not (math.isfinite(s) and s > 0):
            raise ValueError(f"inverse_table: expected a finite step > 0, got {step}")
        lo, hi = self.area_range()
        first = math.floor(lo / s) + 1
        last = math.ceil(hi / s) - 1
        if last - first > 100_000:
            raise ValueError(
                f"inverse_table: step {s} gives more than 100000 rows; use a larger one"
            )
        areas = [lo, *(k * s for k in range(first, last + 1)), hi]
        return [(float(a), self.pressure_for_area(a)[0]) for a in areas]


def _nice_step(raw: float) -> float:
    """Smallest 1-2-5 x 10^k number >= ``raw`` (1.0 for raw <= 0)."""
    if not (raw > 0 and math.isfinite(raw)):
        return 1.0
    mag = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * mag >= raw * (1 - 1e-12):
            return m * mag
    return 10.0 * mag


def estimate_onset(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    contact: ArrayLike | None = None,
    config: CurveConfig | None = None,
) -> float | None:
    """Contact onset pressure (kPa), or None when the frames show no contact.

    Rule: the frames sorted by pressure are split at index ``s`` minimising (contact frames
    below ``s``) + (no-contact frames at or above ``s``); ties go to the highest ``s`` below
    ``N``. So frame ``s`` is in contact and frame ``s - 1`` is not; every run of frames
    starting at ``s`` and ending below the top has a strict majority of contacts (at least
    half over the whole range), so an isolated miss inside the contact range does not reset
    it; every run ending at ``s - 1`` has at least as many misses as contacts, so an isolated
    false contact at low pressure does not count (nor does a lone contact followed by a miss
    just below the contact range). ``s == N`` (no contact range) gives None, also when the
    only contact flags are such false positives.

    Refinement: the line through the fitted areas of the first two contact frames of the
    range is extrapolated to zero area, clamped to ``[pressure at s - 1, pressure at s]``.
    With no frame below ``s`` the onset is the lowest pressure (not calibrated below it);
    without a usable slope, the midpoint of the interval. On a convex start (area growing
    faster than linearly) the extrapolation is biased towards the first contact frame: for
    ``area ∝ (p - p0)²`` with ``p0`` on a frame it gives ``p0 + 2/3`` of a step.

    Args:
        pressures_kpa: ``(N,)`` frame pressures, kPa, any order, distinct.
        areas: ``(N,)`` contact areas >= 0 (mm² or px).
        contact: ``(N,)`` bool per frame; None means ``areas > 0``.
        config: fit settings (the refinement uses the fitted curve).
    """
    return fit_monotone(pressures_kpa, areas, contact, config).onset_kpa


def fit_monotone(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    contact: ArrayLike | None = None,
    config: CurveConfig | None = None,
    *,
    area_unit: str = "mm²",
) -> Curve:
    """Robust non-decreasing fit of contact area vs pressure.

    Why a running median before PAVA: PAVA alone averages an outlier spike with the points
    after it, lifting those neighbours (and a false dip drags earlier points down). The
    median of three consecutive points is the identity on monotone data, so a genuine curve
    is not biased, while an isolated spike or dip is replaced by a neighbour first (`despike`:
    worst point first, so the spike's neighbours keep their values); PAVA then removes the
    remaining small non-monotone noise in the least-squares sense.

    Steps: sort by pressure; contact range by the `estimate_onset` rule; the contact frames in
    that range are despiked (``config.median_window``) and fitted with PAVA; misses inside the
    range are interpolated from the fit; areas below the onset are 0.

    Args:
        pressures_kpa: ``(N,)`` frame pressures, kPa, any order, distinct, N >= 2.
        areas: ``(N,)`` measured areas >= 0, same order (mm² or px).
        contact: ``(N,)`` bool per frame, same order; None means ``areas > 0``.
        config: fit settings; None uses the defaults.
        area_unit: unit of ``areas``, stored in the curve (``"mm²"`` or ``"px"``).

    Returns:
        The `Curve` (flat zero with ``onset_kpa=None`` if no frame is in contact: the caller
        decides whether that is an error).

    Raises:
        ValueError: mismatched lengths, fewer than 2 frames, duplicate or non-finite
            pressures, NaN/inf/negative areas.
    """
    cfg = config or CurveConfig()
    p, a, c = prepare_points(pressures_kpa, areas, contact)
    fit = np.zeros_like(a)
    s = onset_index(c)
    onset: float | None = None
    if s is not None:
        idx = np.flatnonzero(c[s:]) + s
        smooth = despike(a[idx], cfg.median_window)
        iso = isotonic_fit(p[idx], smooth)
        fit[s:] = np.interp(p[s:], p[idx], iso)
        onset = refine_onset(p, fit, idx)
    return Curve(p, fit, onset, area_unit, cfg.table_step, cfg.table_max_rows)

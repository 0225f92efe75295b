"""The calibration curve: fitted contact area vs pressure, evaluated and inverted (pure numpy).

`Curve` evaluates the fit (`Curve.area_at`) and inverts it for the controller
(`Curve.pressure_for_area`, `Curve.inverse_table`; with its uncertainty band
`Curve.pressure_interval_for_area`, `Curve.inverse_table_with_interval`).
:mod:`contactcal.infer.calibration.fit` makes the isotonic curve, :mod:`.parametric` the
saturating one (``model``), :mod:`.bootstrap` the band.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from contactcal.infer.calibration.piecewise import lowest_reaching

if TYPE_CHECKING:
    from contactcal.infer.calibration.band import Band
    from contactcal.infer.calibration.parametric import Saturating

#: Area units of a curve: mm² with a pixel scale, else input pixels.
MM2 = "mm²"
PX = "px"
AREA_UNITS = (MM2, PX)


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
        model: the parametric form when the curve is the saturating fit (then ``fit_area`` holds
            its values at ``pressures_kpa`` and evaluation and inverse use the form), or None for
            the piecewise-linear isotonic fit.
        band: the curve's uncertainty band, or None (e.g. read from a format 1-2 record).
        onset_bracket_kpa: ``(lo, hi)``, kPa: the onset lies in ``(lo, hi]``, ``lo`` the highest
            pressure without contact below the contact range (None: contact from the lowest
            pressure), ``hi`` the lowest pressure of the contact range; None when unknown (no
            contact, or read from a record).
        onset_rule: how the onset was placed in its bracket
            (:mod:`~contactcal.infer.calibration.onset`'s ``*_RULE``), or None when unknown.
    """

    pressures_kpa: np.ndarray
    fit_area: np.ndarray
    onset_kpa: float | None
    area_unit: str = MM2
    table_step: float | None = None
    table_max_rows: int = 100
    model: Saturating | None = None
    band: Band | None = None
    onset_bracket_kpa: tuple[float | None, float] | None = None
    onset_rule: str | None = None

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
        if self.area_unit not in AREA_UNITS:
            raise ValueError(
                f"Curve: area_unit must be one of {AREA_UNITS}, got {self.area_unit!r}"
            )
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
        if self.model is not None:  # the smooth form, sampled (for plots and the area range)
            x = np.linspace(on, float(p[-1]), 257)
            return x, self.model.area(x)
        at = p == on
        if np.any(at) and float(f[at][0]) > 0:
            keep = p >= on
            return p[keep], f[keep]
        above = p > on
        return np.concatenate([[on], p[above]]), np.concatenate([[0.0], f[above]])

    def area_at(self, p_kpa: float) -> float:
        """Fitted area (area_unit) at ``p_kpa``: 0 below the onset, linear between knots, held
        at the last fitted value above the calibrated maximum pressure."""
        q = real_number(p_kpa, "area_at", "a pressure in kPa")
        if not math.isfinite(q):
            raise ValueError(f"area_at: expected a finite pressure in kPa, got {p_kpa}")
        if self.onset_kpa is None:
            return 0.0
        x, y = self.knots()
        if q < x[0]:
            return 0.0
        if self.model is not None:
            return float(self.model.area(min(q, float(x[-1]))))
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
            TypeError: ``area`` is not a real number (a string, None, a bool, an array).
            ValueError: non-finite or negative ``area``, or a curve without contact.
        """
        a = real_number(area, "pressure_for_area", f"an area in {self.area_unit}")
        if not math.isfinite(a) or a < 0:
            raise ValueError(f"pressure_for_area: expected a finite area >= 0, got {area}")
        if not self.has_contact:
            raise ValueError("no contact in this calibration; cannot invert")
        x, y = self.knots()
        u = self.area_unit
        if a > y[-1]:
            k = int(np.searchsorted(y, y[-1], side="left"))
            t, m = _apart(a, float(y[-1]))
            msg = f"target {t} {u} above calibrated maximum {m} {u} at {x[k]:.4g} kPa; clamped"
            return float(x[k]), msg
        if a <= y[0]:
            if a < y[0]:
                t, m = _apart(a, float(y[0]))
                msg = (
                    f"target {t} {u} below smallest calibrated area {m} {u} at "
                    f"{x[0]:.4g} kPa (no frame without contact below it); clamped"
                )
                return float(x[0]), msg
            return float(x[0]), None
        if self.model is not None:
            return min(self.model.pressure(a), float(x[-1])), None
        return lowest_reaching(x, y, a), None

    def pressure_interval_for_area(self, area: float) -> tuple[float, float, float, str | None]:
        """``(p, p_lo, p_hi, warning)``: `pressure_for_area` with the band's interval, kPa.

        ``p_lo`` is where the band's upper edge reaches ``area``, ``p_hi`` where its lower
        edge does (so ``p_lo <= p <= p_hi``; each non-decreasing in ``area``). The warning
        joins the curve's and the band's (an end of the interval clamped to the calibrated
        range), or is None.

        Raises:
            ValueError: as `pressure_for_area`, or a curve without a band.
        """
        p, warning = self.pressure_for_area(area)
        if self.band is None:
            raise ValueError(
                "this calibration has no uncertainty band (written before format 3); "
                "re-run contactcal calibrate, or use pressure_for_area"
            )
        lo, hi, band_warning = self.band.pressure_bounds(float(area))
        notes = [w for w in (warning, band_warning) if w]
        return p, min(lo, p), max(hi, p), "; ".join(notes) or None

    def default_table_step(self) -> float:
        """The inverse-table step used when none is given (area_unit)."""
        if self.table_step is not None:
            return float(self.table_step)
        lo, hi = self.area_range()
        return _nice_step((hi - lo) / self.table_max_rows)

    def inverse_table(self, step: float | None = None) -> list[tuple[float, float]]:
        """``[(area, pressure_kpa), ...]`` from the smallest to the largest calibrated area.

        Rows at the smallest area, every multiple of ``step`` in between, and the largest area;
        for the piecewise-linear (isotonic) fit also a row at each of its breakpoints, so that
        linear interpolation between rows is the curve's own inverse. Where the fit holds an
        area over a pressure range (a flat segment below a rise) two rows share that area: the
        range's lowest pressure (the inverse there) and its highest (the start of the rise
        above it); a lookup that takes the first row reaching an area, or ``numpy.interp``
        just above it, then follows the curve.

        Args:
            step: area step (area_unit) > 0; None uses `default_table_step`.

        Raises:
            ValueError: bad step, or a curve without contact.
        """
        from contactcal.infer.calibration.inverse import inverse_rows

        return inverse_rows(self, self.default_table_step() if step is None else float(step))

    def inverse_table_with_interval(
        self, step: float | None = None
    ) -> list[tuple[float, float, float, float]]:
        """``[(area, p, p_lo, p_hi), ...]``: `inverse_table` with the band's interval, kPa.

        Besides `inverse_table`'s rows, a row at each breakpoint of the band's edges, and a
        second row at an area where ``p_lo`` or ``p_hi`` jumps (an edge flat below a rise), so
        that each column interpolates linearly to `pressure_interval_for_area`
        (:mod:`~contactcal.infer.calibration.inverse`).

        Raises:
            ValueError: as `inverse_table`, or a curve without a band.
        """
        from contactcal.infer.calibration.inverse import interval_rows

        return interval_rows(self, self.default_table_step() if step is None else float(step))


def real_number(value: object, where: str, what: str) -> float:
    """``value`` as a float when it is a real number (a Python or numpy scalar, or a 0-d
    array of one), else a TypeError saying what ``where`` expected: ``float("100")`` would
    read a string from a controller's config as a number, and ``float(True)`` as 1.

    Raises:
        TypeError: a string, None, a bool, a complex number or an array with elements.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
        return float(value)
    raise TypeError(
        f"{where}: expected {what} (a real number), got {type(value).__name__} {value!r}"
    )


def _apart(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` (``a != b``) written to 4 significant digits, or as many more as tell them
    apart ("target 143.8 above calibrated maximum 143.8" said nothing)."""
    for digits in range(4, 17):
        ta, tb = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if ta != tb:
            return ta, tb
    return repr(a), repr(b)


def _nice_step(raw: float) -> float:
    """Smallest 1-2-5 x 10^k number >= ``raw`` (1.0 for raw <= 0)."""
    if not (raw > 0 and math.isfinite(raw)):
        return 1.0
    mag = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * mag >= raw * (1 - 1e-12):
            return m * mag
    return 10.0 * mag

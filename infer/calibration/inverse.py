"""The inverse table of a curve: area → pressure rows, with the band's interval (pure numpy).

A controller that cannot run Python reads these rows from ``calibration.json`` and interpolates
linearly, so the rows hold every breakpoint of each column's piecewise-linear inverse: the
isotonic fit's knots (pressure), the band's edges (``p_lo`` from the upper edge, ``p_hi`` from
the lower one). Where a column jumps at an area (its function holds that area over a pressure
range below a rise), a second row with that area holds the values just above it.
"""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from contactcal.infer.calibration.curve import Curve

#: Most rows the area step may give (a step far too small for the curve is refused).
MAX_STEP_ROWS = 100_000


def inverse_rows(curve: Curve, step: float) -> list[tuple[float, float]]:
    """``[(area, pressure_kpa), ...]``: :meth:`Curve.inverse_table`'s rows (see there).

    Raises:
        ValueError: bad step, or a curve without contact.
    """
    if not curve.has_contact:
        raise ValueError("no contact in this calibration; cannot invert")
    if not (math.isfinite(step) and step > 0):
        raise ValueError(f"inverse_table: expected a finite step > 0, got {step}")
    lo, hi = curve.area_range()
    first = math.floor(lo / step) + 1
    last = math.ceil(hi / step) - 1
    if last - first > MAX_STEP_ROWS:
        raise ValueError(
            f"inverse_table: step {step} gives more than {MAX_STEP_ROWS} rows; use a larger one"
        )
    areas = [lo, *(k * step for k in range(first, last + 1)), hi]
    rows = [(float(a), curve.pressure_for_area(a)[0]) for a in areas]
    # the isotonic fit's breakpoints; the smooth form's samples (Curve.knots: 257 pressures),
    # which bound the pressure between rows where the form is nearly flat
    return _with_breakpoints(rows, *curve.knots())


def interval_rows(curve: Curve, step: float) -> list[tuple[float, float, float, float]]:
    """``[(area, p, p_lo, p_hi), ...]``: :meth:`Curve.inverse_table_with_interval`'s rows.

    The pressure rows of :func:`inverse_rows`, and a row at each area where an edge of the band
    has a breakpoint; each row's interval as `Curve.pressure_interval_for_area` gives it, and,
    where a column jumps just above the row's area, a second row with the values there.

    Raises:
        ValueError: as :func:`inverse_rows`, or a curve without a band.
    """
    base = inverse_rows(curve, step)
    curve.pressure_interval_for_area(base[0][0])  # a curve without a band: its error
    band = curve.band
    assert band is not None  # checked just above (not user input)
    a_lo, a_hi = curve.area_range()
    p_at: dict[float, float] = {}
    for a, p in base:
        p_at.setdefault(a, p)  # an area's first row: the pressure at it
    p_above = dict(base)  # its last row: the pressure just above it
    edges = {float(v) for v in (*band.lo, *band.hi) if a_lo < v < a_hi}
    rows: list[tuple[float, float, float, float]] = []
    for a in sorted(p_at.keys() | edges):
        p = p_at[a] if a in p_at else curve.pressure_for_area(a)[0]
        lo, hi, _ = band.pressure_bounds(a)
        rows.append((a, p, min(lo, p), max(hi, p)))  # as Curve.pressure_interval_for_area
        if a < a_hi:
            pa = p_above.get(a, p)
            lo, hi, _ = band.pressure_bounds(a, above=True)
            above = (a, pa, min(lo, pa), max(hi, pa))
            if above != rows[-1]:
                rows.append(above)
    return rows


def _with_breakpoints(
    rows: list[tuple[float, float]], x: np.ndarray, y: np.ndarray
) -> list[tuple[float, float]]:
    """``rows`` with the knots ``(area y, pressure x)`` in their place, sorted by area.

    A row at a knot's area gives way to the knot (the same point, without interpolation's
    rounding). An area the knots hold over a pressure range keeps the range's lowest pressure
    and, unless it is the largest area, its highest (where the curve rises again).
    """
    knots = list(zip(map(float, y), map(float, x), strict=True))
    at_knots = {a for a, _ in knots}
    merged = sorted([r for r in rows if r[0] not in at_knots] + knots)
    top = merged[-1][0]
    out: list[tuple[float, float]] = []
    for a, group in itertools.groupby(merged, key=lambda r: r[0]):
        ps = [p for _, p in group]
        out.append((a, ps[0]))
        if a < top and ps[-1] > ps[0]:
            out.append((a, ps[-1]))
    return out

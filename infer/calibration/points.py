"""A session's measured points: the per-frame record, and its validation before fitting."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from contactcal.infer.calibration.curve import PX
from contactcal.infer.calibration.phases import LOADING


@dataclass(frozen=True)
class CalibrationPoint:
    """Measurement of one frame of a calibration session.

    Attributes:
        file: image path as given (for the record).
        pressure_kpa: chamber pressure, kPa.
        contact: whether skin contact was detected.
        area_px: contact area, px (0 without contact).
        area_mm2: contact area, mm², or None without a pixel scale.
        note: free text (e.g. why a frame is doubtful).
        phase: ``"loading"`` or ``"unloading"``.
        step: 0-based pressure step within the phase (frames of one step share its pressure).
        extras: the manifest row's other columns, ``(name, cell)`` pairs (a reading, kPa, as a
            number, or None where its cell is blank).
        area_interval_px: the method's stated 90 % interval of the area, px, or None.
        area_interval_mm2: the same in mm², or None (no interval or no pixel scale).
    """

    file: str
    pressure_kpa: float
    contact: bool
    area_px: float
    area_mm2: float | None
    note: str = ""
    phase: str = LOADING
    step: int = 0
    extras: tuple[tuple[str, str | float | None], ...] = ()
    area_interval_px: tuple[float, float] | None = None
    area_interval_mm2: tuple[float, float] | None = None

    def area(self, unit: str) -> float | None:
        """The frame's area in ``unit`` (px, else mm²; None without a scale)."""
        if unit == PX:
            return float(self.area_px)
        return None if self.area_mm2 is None else float(self.area_mm2)

    def interval(self, unit: str) -> tuple[float, float] | None:
        """The frame's stated area interval in ``unit``, or None."""
        return self.area_interval_px if unit == PX else self.area_interval_mm2


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

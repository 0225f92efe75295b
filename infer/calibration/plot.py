"""Plot of a calibration: measured points, monotone fit and onset (``curve.png``).

matplotlib is imported inside `plot_curve` only (object API with the Agg canvas).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING

import numpy as np

from contactcal.infer.calibration.curve import PX, Curve

if TYPE_CHECKING:
    from contactcal.infer.calibration.points import CalibrationPoint


def measured_area(r: CalibrationPoint, unit: str) -> float | None:
    """The frame's area in the curve's unit (px when the unit is px, else mm²)."""
    if unit == PX:
        return float(r.area_px)
    return None if r.area_mm2 is None else float(r.area_mm2)


def plot_curve(
    path: str | os.PathLike[str], results: list[CalibrationPoint], curve: Curve, method: str
) -> None:
    """Draw the measured points (coloured by contact), the monotone fit and the onset to a PNG.

    Uses matplotlib's object API with the Agg canvas (imported here, never at module import,
    and without touching pyplot's global backend).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    unit = curve.area_unit
    fig = Figure(figsize=(6.4, 4.4), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for flag, colour, marker, label in (
        (True, "tab:red", "o", "contact"),
        (False, "tab:blue", "x", "no contact"),
    ):
        pts = [(r.pressure_kpa, measured_area(r, unit)) for r in results if bool(r.contact) is flag]
        pts = [(p, a) for p, a in pts if a is not None and math.isfinite(a)]
        if pts:
            xs, ys = zip(*pts, strict=True)
            ax.scatter(xs, ys, c=colour, marker=marker, label=label, zorder=3)
    p = curve.pressures_kpa
    grid = np.union1d(np.linspace(p[0], p[-1], 200), curve.knots()[0])
    if curve.onset_kpa is not None:  # draw the jump at the onset as a vertical step
        grid = np.union1d(grid, [np.nextafter(curve.onset_kpa, -np.inf)])
    ax.plot(grid, [curve.area_at(q) for q in grid], color="black", lw=1.5, label="monotone fit")
    if curve.onset_kpa is not None:
        ax.axvline(curve.onset_kpa, color="tab:green", ls="--", lw=1)
        ax.annotate(
            f"onset {curve.onset_kpa:.2f} kPa",
            xy=(curve.onset_kpa, 0.95),
            xycoords=("data", "axes fraction"),
            xytext=(4, 0),
            textcoords="offset points",
            color="tab:green",
            va="top",
        )
    ax.set_xlabel("pressure (kPa)")
    ax.set_ylabel(f"contact area ({unit})")
    ax.set_title(f"Contact area vs pressure ({method})")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(os.fspath(path), format="png")

"""Plot of a calibration (``curve.png``): each phase's frames, fit, 90 % band and onset.

matplotlib is imported inside `plot_curve` only (object API with the Agg canvas).
"""

from __future__ import annotations

import math
import os
import textwrap
from typing import TYPE_CHECKING

import numpy as np

from contactcal.infer.calibration.curve import Curve

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from contactcal.infer.calibration.points import CalibrationPoint
    from contactcal.infer.calibration.session import SessionFit

#: Characters per title line for the device id: 40 of the widest glyph fit the 6.4-in figure.
TITLE_CHARS = 40
#: Colour and line style per phase.
_STYLE = {"loading": ("tab:red", "-"), "unloading": ("tab:purple", "--")}


def _draw_curve(ax: Axes, curve: Curve, name: str, model: str) -> None:
    colour, ls = _STYLE[name]
    p = curve.pressures_kpa
    grid = np.union1d(np.linspace(p[0], p[-1], 200), curve.knots()[0])
    if curve.onset_kpa is not None:  # draw the jump at the onset as a vertical step
        grid = np.union1d(grid, [np.nextafter(curve.onset_kpa, -np.inf)])
    ax.plot(
        grid,
        [curve.area_at(q) for q in grid],
        color=colour,
        ls=ls,
        lw=1.5,
        label=f"{name} {model} fit",
    )
    if curve.band is not None:
        b = curve.band
        ax.fill_between(
            b.pressures_kpa,
            b.lo,
            b.hi,
            color=colour,
            alpha=0.2,
            lw=0,
            label=f"{name} {b.level:.0%} band",
        )
    if curve.onset_kpa is not None:
        ax.axvline(curve.onset_kpa, color=colour, ls=":", lw=1)
        ax.annotate(
            f"{name} onset {curve.onset_kpa:.2f} kPa",
            xy=(curve.onset_kpa, 0.95 if name == "loading" else 0.85),
            xycoords=("data", "axes fraction"),
            xytext=(4, 0),
            textcoords="offset points",
            color=colour,
            va="top",
        )


def plot_curve(
    path: str | os.PathLike[str],
    results: list[CalibrationPoint],
    fit: SessionFit,
    method: str,
    device_id: str | None = None,
) -> None:
    """Draw every phase's frames (filled: contact, hollow: none), fit, band and onset to a PNG.

    The title names the method and, when given, the calibrated display (``device_id``).

    Uses matplotlib's object API with the Agg canvas (imported here, never at module import,
    and without touching pyplot's global backend).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    unit = fit.curve.area_unit
    fig = Figure(figsize=(6.4, 4.4), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for name, ph in fit.phases.items():
        colour, _ = _STYLE[name]
        for flag in (True, False):
            pts = [
                (r.pressure_kpa, r.area(unit))
                for r in results
                if r.phase == name and bool(r.contact) is flag
            ]
            pts = [(p, a) for p, a in pts if a is not None and math.isfinite(a)]
            if pts:
                xs, ys = zip(*pts, strict=True)
                face = colour if flag else "none"
                label = f"{name} frames" + ("" if flag else " (no contact)")
                ax.scatter(xs, ys, facecolors=face, edgecolors=colour, s=18, label=label, zorder=3)
        _draw_curve(ax, ph.curve, name, ph.selection["model"])
    ax.set_xlabel("pressure (kPa)")
    ax.set_ylabel(f"contact area ({unit})")
    title = f"Contact area vs pressure ({method})"
    if device_id is not None:  # its own line(s), wrapped: an id may be 100 characters
        title += "\n" + "\n".join(textwrap.wrap(f"device {device_id}", TITLE_CHARS))
    ax.set_title(title, parse_math=False)  # a "$" in an id is text, not mathtext
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize="small")
    fig.tight_layout()
    fig.savefig(os.fspath(path), format="png")

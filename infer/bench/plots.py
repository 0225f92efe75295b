"""Figures of ``contactcal bench``: error vs pressure, speed vs error (``pareto.png``) and error
vs perturbation level (``robustness.png``, and the no-contact accuracy in
``robustness_no_contact.png``).

matplotlib is imported inside the functions only, with its object API and the Agg canvas (never
pyplot's global backend); every figure is written atomically.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from contactcal.infer.bench.scoring import SESSION_SUFFIX, SOFT_SUFFIX, ScoredFrame
from contactcal.infer.files.atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Smallest error drawn on the log axes (an exact area shows here instead of vanishing).
FLOOR_PCT, FLOOR_MM2 = 0.01, 1e-3
#: Line styles of the methods, in drawing order: each later line is thinner and broken, so a
#: method whose curve coincides with an earlier one's still shows (both colours visible).
LINE_STYLES = ({"ls": "-", "lw": 2.2}, {"ls": "--", "lw": 1.6}, {"ls": ":", "lw": 1.4})


def line_style(i: int) -> dict[str, Any]:
    """Matplotlib keyword arguments of the ``i``-th method's line (:data:`LINE_STYLES`, cycled)."""
    return dict(LINE_STYLES[i % len(LINE_STYLES)])


def legend_label(method: str, curve: np.ndarray, drawn: Mapping[str, np.ndarray]) -> str:
    """``method``, or ``"method (same as other)"`` when its curve equals an already drawn one's
    (:func:`same_as`): a line hidden under another is named in the legend."""
    twin = same_as(curve, drawn)
    return method if twin is None else f"{method} (same as {twin})"


def same_as(curve: np.ndarray, drawn: Mapping[str, np.ndarray]) -> str | None:
    """The first already drawn method whose curve equals ``curve`` exactly, or None.

    Args:
        curve: ``(P, K)`` values of one method (e.g. pressures and medians).
        drawn: label → curve of the methods drawn before it.
    """
    for label, other in drawn.items():
        if other.shape == curve.shape and np.array_equal(other, curve):
            return label
    return None


def _figure(width: float, height: float) -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: str | os.PathLike[str]) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(os.fspath(tmp), format="png")


def error_quartiles(
    frames: Sequence[ScoredFrame], method: str, mm2: bool
) -> tuple[list[float], np.ndarray]:
    """Per pressure (contact frames of one method): quartiles of |area error|.

    Returns:
        Pressures (kPa, ascending) and a ``(P, 3)`` array of the 25/50/75 % quantiles of the
        absolute error, in % of the true area, or in mm² when ``mm2`` (frames with a pixel scale).
    """
    groups: dict[float, list[float]] = {}
    for f in frames:
        if f.method != method or not f.true_contact or (mm2 and not f.mm_per_px):
            continue
        err = abs(f.area_px - f.true_area_px) * f.mm_per_px**2 if mm2 else 100 * abs(f.rel_error)
        groups.setdefault(round(f.pressure_kpa, 3), []).append(err)
    ps = sorted(groups)
    q = np.array([np.percentile(groups[p], (25, 50, 75)) for p in ps]).reshape(-1, 3)
    return ps, q


def _plain_log_ticks(ax: Any) -> None:
    """Log axes labelled with plain numbers (1, 2, 5, 10, ...) and no crowded minor labels."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() != "log":
            continue
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())


def plot_error_vs_pressure(path: str | os.PathLike[str], frames: Sequence[ScoredFrame]) -> None:
    """|Relative| and |absolute| area error vs pressure per method: median and interquartile
    band over the sessions, on log axes so that methods orders of magnitude apart both read.

    The derived rows (``(soft area)``, ``(session rule)``: the same predictions, re-measured or
    re-decided) are left to the tables: drawn, they would hide the methods behind them."""
    fig = _figure(11, 4.2)
    axes = fig.subplots(1, 2)
    panels = (
        (False, FLOOR_PCT, "|relative area error| (%)"),
        (True, FLOOR_MM2, "|area error| (mm²)"),
    )
    derived = (SOFT_SUFFIX, SESSION_SUFFIX)
    methods = sorted({f.method for f in frames if not f.method.endswith(derived)})
    drawn: list[dict[str, np.ndarray]] = [{}, {}]  # per panel: label → (pressure, quartiles)
    for i, method in enumerate(methods):
        colour = f"C{i}"
        for ax, seen, (mm2, floor, _) in zip(axes, drawn, panels, strict=True):
            ps, q = error_quartiles(frames, method, mm2)
            if not ps:
                continue
            q = np.maximum(q, floor)
            curve = np.column_stack([ps, q])
            label = legend_label(method, curve, seen)
            seen[method] = curve
            ax.fill_between(ps, q[:, 0], q[:, 2], color=colour, alpha=0.2, lw=0)
            ax.plot(ps, q[:, 1], color=colour, marker="o", ms=3, label=label, **line_style(i))
    for ax, (_, _, label) in zip(axes, panels, strict=True):
        ax.set_yscale("log")
        _plain_log_ticks(ax)
        ax.set_xlabel("pressure (kPa)")
        ax.set_ylabel(f"{label}: median, IQR band")
        ax.grid(alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    axes[0].set_title(f"contact frames; exact areas drawn at {FLOOR_PCT:g} %", fontsize=9)
    axes[1].set_title(f"exact areas drawn at {FLOOR_MM2:g} mm²", fontsize=9)
    fig.tight_layout()
    _save(fig, path)


def pareto_points(
    bins: Sequence[Mapping[str, Any]], timing: Sequence[Mapping[str, Any]]
) -> list[tuple[str, float, float, float]]:
    """``(label, ms decoded, ms incl. JPEG decode, error %)`` per timed configuration.

    The error is the method's median |relative error| in the bin starting at 5 kPa; configurations
    without it (or without an end-to-end time) are left out.
    """
    err = {b["method"]: b["median_abs_rel_error"] for b in bins if b["bin_kpa"].startswith("5-")}
    out = []
    for t in timing:
        base = t["config"].split("+")[0].split("@")[0].split(" ")[0]
        e = err.get(base)
        if e is None or t.get("ms_end_to_end_jpg") is None:
            continue
        label = f"{t['config']}, {t['threads']} thread{'s' if t['threads'] > 1 else ''}"
        out.append((label, t["ms_compute"], t["ms_end_to_end_jpg"], 100 * max(e, 1e-6)))
    return out


def plot_pareto(
    path: str | os.PathLike[str],
    bins: Sequence[Mapping[str, Any]],
    timing: Sequence[Mapping[str, Any]],
    size: tuple[int, int] = (2592, 1944),
) -> None:
    """Speed vs error: one colour per configuration (legend), circle = decoded frame, square =
    including the JPEG decode, joined by a line; no in-plot text, so nothing overlaps."""
    from matplotlib import colormaps
    from matplotlib.lines import Line2D

    palette = colormaps["tab20"].colors  # 20 distinct colours: every configuration its own
    fig = _figure(8.5, 4.5)
    ax = fig.add_subplot()
    points = pareto_points(bins, timing)
    handles = []
    for i, (label, ms, ms_jpg, err) in enumerate(points):
        colour = palette[(2 * i + i // 10) % 20]  # dark shades first, then the light ones
        ax.plot([ms, ms_jpg], [err, err], color=colour, lw=1, alpha=0.6)
        ax.scatter([ms], [err], marker="o", color=colour, zorder=3)
        ax.scatter([ms_jpg], [err], marker="s", color=colour, zorder=3)
        handles.append(Line2D([], [], color=colour, marker="o", lw=0, label=label))
    handles += [
        Line2D([], [], color="0.3", marker="o", lw=0, label="decoded frame"),
        Line2D([], [], color="0.3", marker="s", lw=0, label="incl. JPEG decode"),
    ]
    ax.set_xscale("log")
    ax.set_yscale("log")
    _plain_log_ticks(ax)
    ax.set_xlabel(f"median ms/frame at {size[0]}×{size[1]}")
    ax.set_ylabel("median |relative area error| at 5-10 kPa (%)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    _save(fig, path)


#: What :func:`plot_robustness` can draw: row key, y label, log scale, the row key counting the
#: frames that score it, and what a panel says in place of its points when none does.
ROBUSTNESS_METRICS = {
    "error": (
        "median_abs_rel_error_ge5",
        "median |rel. area error| ≥5 kPa (%)",
        True,
        "contact_frames_ge5",
        "no frame with true contact at ≥ 5 kPa",
    ),
    "no_contact": (
        "no_contact_accuracy",
        "no-contact accuracy (%)",
        False,
        "no_contact_frames",
        "no frame without contact",
    ),
}


def plot_robustness(
    path: str | os.PathLike[str], robustness: Mapping[str, Any], metric: str = "error"
) -> None:
    """One robustness metric vs level, one panel per perturbation, one line per method; the
    dashed line marks the baseline, the grey span the levels the training randomises (where the
    2× error target applies). When no sampled frame scores the metric (e.g. a sample without a
    frame free of contact), each panel says so in place of the points:
    ``no frame without contact in the sample (N frames)``.

    Args:
        path: PNG to write.
        robustness: ``results.json``'s ``"robustness"`` (``frames``, ``perturbations`` and
            ``rows``).
        metric: ``"error"``: median |relative area error| at ≥ 5 kPa, %, log y (floored at
            ``FLOOR_PCT``); ``"no_contact"``: share of the frames without true contact reported
            as no contact, %, linear y from 0 to 100 (:data:`ROBUSTNESS_METRICS`).

    Raises:
        ValueError: an unknown ``metric``.
    """
    if metric not in ROBUSTNESS_METRICS:
        raise ValueError(f"metric must be one of {sorted(ROBUSTNESS_METRICS)}, got {metric!r}")
    perts = robustness["perturbations"]
    cols = min(5, len(perts))
    nrows = -(-len(perts) // cols)
    fig = _figure(3.2 * cols, 2.9 * nrows + 0.4)
    axes = fig.subplots(nrows, cols, squeeze=False).ravel()
    for ax, p in zip(axes, perts, strict=False):
        _robustness_panel(ax, p, robustness, metric)
    for ax in axes[len(perts) :]:
        ax.set_visible(False)
    for ax in axes[::cols]:
        ax.set_ylabel(ROBUSTNESS_METRICS[metric][1], fontsize=7)
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(fontsize=7)
    fig.tight_layout()
    _save(fig, path)


def _robustness_panel(
    ax: Axes, p: Mapping[str, Any], robustness: Mapping[str, Any], metric: str
) -> None:
    """Draw perturbation ``p``'s panel of :func:`plot_robustness` into ``ax``."""
    key, _, log, count, none_text = ROBUSTNESS_METRICS[metric]
    rows = [r for r in robustness["rows"] if r["perturbation"] == p["name"]]
    methods = sorted({r["method"] for r in robustness["rows"]})
    for i, method in enumerate(methods):
        pts = [
            (p["levels"].index(r["level"]), 100 * r[key])
            for r in rows
            if r["method"] == method and r[key] is not None
        ]
        if pts:
            x, y = zip(*pts, strict=True)
            y = np.maximum(y, FLOOR_PCT) if log else y
            ax.plot(x, y, color=f"C{i}", marker="o", ms=3, label=method, **line_style(i))
    if not any(r[count] for r in rows):
        n = len(robustness["frames"])
        text = f"{none_text}\nin the sample ({n} frame{'s' if n != 1 else ''})"
        ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=8)
    ax.axvline(p["levels"].index(p["baseline"]), color="0.5", ls="--", lw=0.8)
    inside = [p["levels"].index(r["level"]) for r in rows if r["in_range"]]
    ax.axvspan(min(inside) - 0.3, max(inside) + 0.3, color="0.9", zorder=0)
    ax.set_xticks(range(len(p["levels"])), p["labels"], fontsize=7)
    if log:
        ax.set_yscale("log")
        _plain_log_ticks(ax)
    else:
        ax.set_ylim(-3, 103)
    ax.set_title(p["name"], fontsize=9)
    ax.set_xlabel(p["unit"], fontsize=8)
    ax.grid(alpha=0.3, which="both")

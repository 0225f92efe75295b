"""Tables, plots and ``report.md`` of ``contactcal bench`` (from the raw records)."""

from __future__ import annotations

import os
import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.atomic import atomic_path, write_json, write_text


def _rel(r: dict[str, Any]) -> float:
    return (r["area_px"] - r["true_area_px"]) / r["true_area_px"]


def _med(xs: Sequence[float]) -> float | None:
    return float(statistics.median(xs)) if xs else None


def bin_table(records: list[dict[str, Any]], bins: Sequence[tuple[float, float]]) -> list[dict]:
    """Per method and pressure bin: median |relative error|, mean ± sd, no-contact accuracy."""
    out = []
    for method in sorted({r["method"] for r in records}):
        for lo, hi in bins:
            rs = [r for r in records if r["method"] == method and lo <= r["pressure_kpa"] < hi]
            cont = [r for r in rs if r["true_contact"]]
            rel = [_rel(r) for r in cont]
            none = [r for r in rs if not r["true_contact"]]
            abs_mm2 = [abs(r["area_px"] - r["true_area_px"]) * r["mm_per_px"] ** 2 for r in cont]
            out.append({
                "method": method, "bin_kpa": f"{lo:g}-{hi:.0f}", "contact_frames": len(cont),
                "median_abs_rel_error": _med([abs(x) for x in rel]),
                "mean_rel_error": float(np.mean(rel)) if rel else None,
                "sd_rel_error": float(np.std(rel)) if rel else None,
                "median_abs_error_mm2": _med(abs_mm2),
                "contact_recall": (sum(r["contact"] for r in cont) / len(cont)) if cont else None,
                "no_contact_frames": len(none),
                "no_contact_accuracy": (sum(not r["contact"] for r in none) / len(none))
                if none else None,
            })  # fmt: skip
    return out


def hard_table(records: list[dict[str, Any]], onset: list[dict[str, Any]]) -> list[dict]:
    """Per method: normal vs hard sessions (exposure, off-centre, faint ridges, dim LEDs)."""
    out = []
    for method in sorted({r["method"] for r in records}):
        for hard in (False, True):
            rs = [r for r in records if r["method"] == method and r["hard"] == hard]
            if not rs:
                continue
            hi = [abs(_rel(r)) for r in rs if r["true_contact"] and r["pressure_kpa"] >= 5]
            lo = [abs(_rel(r)) for r in rs if r["true_contact"] and 3 <= r["pressure_kpa"] < 5]
            none = [r for r in rs if not r["true_contact"]]
            sess = {r["session"] for r in rs}
            on = [
                abs(o["error_kpa"])
                for o in onset
                if o["method"] == method and o["session"] in sess and o["error_kpa"] is not None
            ]
            out.append({
                "method": method, "sessions": "hard" if hard else "normal", "n": len(sess),
                "median_abs_rel_error_ge5": _med(hi), "median_abs_rel_error_3to5": _med(lo),
                "no_contact_accuracy": (sum(not r["contact"] for r in none) / len(none))
                if none else None,
                "median_abs_onset_error_kpa": _med(on),
                "onset_missing": sum(o["onset_kpa"] is None for o in onset
                                     if o["method"] == method and o["session"] in sess),
            })  # fmt: skip
    return out


def _fmt(v: object, pct: bool = False) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{100 * v:.1f} %" if pct else f"{v:.3g}"
    return str(v)


def _md_table(rows: list[dict], cols: list[tuple[str, str, bool]]) -> str:
    head = "| " + " | ".join(c[1] for c in cols) + " |"
    sep = "|" + "---|" * len(cols)
    body = ["| " + " | ".join(_fmt(r[c[0]], c[2]) for c in cols) + " |" for r in rows]
    return "\n".join([head, sep, *body])


def _plots(out: Path, results: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recs = results["records"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), dpi=110)
    for method in sorted({r["method"] for r in recs}):
        ps = sorted({r["pressure_kpa"] for r in recs if r["true_contact"]})
        for ax, key in zip(axes, ("rel", "abs"), strict=True):
            mean, sd = [], []
            for p in ps:
                rs = [r for r in recs if r["method"] == method and r["pressure_kpa"] == p
                      and r["true_contact"]]  # fmt: skip
                v = [
                    100 * _rel(r)
                    if key == "rel"
                    else (r["area_px"] - r["true_area_px"]) * r["mm_per_px"] ** 2
                    for r in rs
                ]
                mean.append(np.mean(v))
                sd.append(np.std(v))
            ax.errorbar(ps, mean, yerr=sd, capsize=2, marker="o", ms=3, label=method)
    axes[0].set_ylabel("relative area error (%)  mean ± sd over fingers")
    axes[1].set_ylabel("absolute area error (mm²)  mean ± sd")
    for ax in axes:
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xlabel("pressure (kPa)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylim(-50, 150)
    fig.tight_layout()
    with atomic_path(out / "error_vs_pressure.png") as tmp:
        fig.savefig(tmp)
    plt.close(fig)
    bins = {(r["method"]): r for r in results["bins"] if r["bin_kpa"].startswith("5-")}
    fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
    for t in results["timing"]:
        base = t["config"].split("+")[0].split("@")[0].split(" ")[0]
        err = bins.get(base, {}).get("median_abs_rel_error")
        if err is None or "ms_end_to_end_jpg" not in t:
            continue
        for key, marker in (("ms_compute", "o"), ("ms_end_to_end_jpg", "s")):
            ax.scatter(t[key], 100 * err, marker=marker)
            ax.annotate(f"{t['config']} {t['threads']}t {'(+jpg)' if 'end' in key else ''}",
                        (t[key], 100 * err), fontsize=7)  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median ms/frame at 2592×1944 (circle: decoded; square: incl. JPEG decode)")
    ax.set_ylabel("median |relative area error| at 5-10 kPa (%)")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    with atomic_path(out / "pareto.png") as tmp:
        fig.savefig(tmp)
    plt.close(fig)


def write_report(
    out_dir: str | os.PathLike[str], results: dict[str, Any], bins: Sequence[tuple[float, float]]
) -> None:
    """Add the tables to ``results`` and write ``results.json``, plots and ``report.md``."""
    out = Path(out_dir)
    results["bins"] = bin_table(results["records"], bins)
    results["hard"] = hard_table(results["records"], results["onset"])
    write_json(out / "results.json", results)
    _plots(out, results)
    bcols = [("method", "method", False), ("bin_kpa", "kPa", False),
             ("contact_frames", "frames", False),
             ("median_abs_rel_error", "median abs. rel. error", True),
             ("mean_rel_error", "mean rel err", True), ("sd_rel_error", "sd", True),
             ("median_abs_error_mm2", "median abs. error mm²", False),
             ("contact_recall", "contact recall", True),
             ("no_contact_accuracy", "no-contact acc.", True)]  # fmt: skip
    tcols = [("config", "configuration", False), ("threads", "threads", False),
             ("ms_compute", "ms/frame (decoded)", False),
             ("ms_end_to_end_jpg", "ms/frame incl. JPEG decode", False),
             ("ms_end_to_end_png", "ms/frame incl. PNG decode", False)]  # fmt: skip
    for t in results["timing"]:
        t.setdefault("ms_end_to_end_jpg", None)
        t.setdefault("ms_end_to_end_png", None)
    hcols = [("method", "method", False), ("sessions", "sessions", False), ("n", "n", False),
             ("median_abs_rel_error_ge5", "median abs. rel. error ≥5 kPa", True),
             ("median_abs_rel_error_3to5", "median abs. rel. error 3-5 kPa", True),
             ("no_contact_accuracy", "no-contact acc.", True),
             ("median_abs_onset_error_kpa", "median abs. onset error kPa", False),
             ("onset_missing", "no onset found", False)]  # fmt: skip
    on = [o for o in results["onset"] if o["error_kpa"] is not None]
    onset_rows = [{"method": m, "median_abs": _med([abs(o["error_kpa"]) for o in on
                                                     if o["method"] == m]),
                   "max_abs": max([abs(o["error_kpa"]) for o in on if o["method"] == m],
                                  default=None)}
                  for m in sorted({o["method"] for o in results["onset"]})]  # fmt: skip
    text = f"""# contactcal benchmark

Data: `{results["data"]}` — {results["sessions"]} sessions, {results["frames"]} frames.
Model: `{results["model"]}`. Areas are compared in input pixels with the exact masks; relative
errors over frames with true contact. Timing: median of {results["config"]["repeats"]} runs over
{results["config"]["timing_frames"]} frames upscaled to {results["config"]["full_size"][0]}×\
{results["config"]["full_size"][1]}, in one process.

## Area error per pressure bin

{_md_table(results["bins"], bcols)}

![error vs pressure](error_vs_pressure.png)

## Speed

{_md_table(results["timing"], tcols)}

![speed vs error](pareto.png)

## Contact onset (estimated from each method's frames vs the mechanics' onset)

{
        _md_table(
            onset_rows,
            [
                ("method", "method", False),
                ("median_abs", "median abs. error kPa", False),
                ("max_abs", "max abs. error kPa", False),
            ],
        )
    }

## Hard cases

{_md_table(results["hard"], hcols)}
"""
    write_text(out / "report.md", text)

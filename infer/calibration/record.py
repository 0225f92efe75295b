"""Calibration outputs: ``calibration.json``, ``calibration.csv``, ``curve.png``, and a text table.

All-or-nothing writing: the three files are first written completely to temporary files in the
output folder (`contactcal.infer.atomic.atomic_path`); only when all three succeeded are they
renamed onto their final names, ``calibration.json`` last. If anything fails, the temporary
files are removed and no new file appears (files from an earlier run are left as they were).
A reader should therefore treat ``calibration.json`` as the record of a complete run.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.plot import plot_curve
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.files.atomic import atomic_path, write_synced
from contactcal.infer.files.jsonable import finite_or_none, jsonable

# plot_curve is looked up here at call time, so tests can replace it.

FORMAT = "contactcal.calibration"
FORMAT_VERSION = 1
CSV_COLUMNS = ("file", "pressure_kpa", "contact", "area_px", "area_mm2", "fit_area")
# Distribution names probed for versions (first installed one wins); metadata only, no import.
_DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "contactcal": ("contactcal",),
    "numpy": ("numpy",),
    "opencv": (
        "opencv-contrib-python-headless",
        "opencv-python-headless",
        "opencv-contrib-python",
        "opencv-python",
    ),
    "onnxruntime": ("onnxruntime", "onnxruntime-gpu"),
}


def package_versions() -> dict[str, str | None]:
    """Installed versions of contactcal, numpy, opencv, onnxruntime (None if absent)."""
    out: dict[str, str | None] = {}
    for key, dists in _DISTRIBUTIONS.items():
        out[key] = None
        for dist in dists:
            with contextlib.suppress(metadata.PackageNotFoundError):
                out[key] = metadata.version(dist)
                break
    return out


def calibration_record(
    results: list[CalibrationPoint], curve: Curve, method: str, extra: dict[str, Any]
) -> dict[str, Any]:
    """The content of ``calibration.json`` (JSON-safe: no NaN, None for missing values)."""
    ordered = sorted(results, key=lambda r: r.pressure_kpa)
    points = [
        {
            "file": r.file,
            "pressure_kpa": r.pressure_kpa,
            "contact": bool(r.contact),
            "area_px": r.area_px,
            "area_mm2": r.area_mm2,
            "fit_area": curve.area_at(r.pressure_kpa),
            "note": r.note,
        }
        for r in ordered
    ]
    if curve.has_contact:
        step = curve.default_table_step()
        table = curve.inverse_table(step)
        inverse: dict[str, Any] | None = {
            "step": step,
            "area": [a for a, _ in table],
            "pressure_kpa": [p for _, p in table],
        }
        area_range: list[float] | None = list(curve.area_range())
    else:
        inverse, area_range = None, None
    record = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "method": method,
        "area_unit": curve.area_unit,
        "onset_kpa": curve.onset_kpa,
        "calibrated_range": {
            "pressure_kpa": [float(curve.pressures_kpa[0]), float(curve.pressures_kpa[-1])],
            "area": area_range,
        },
        "points": points,
        "fit": {"pressure_kpa": curve.pressures_kpa, "area": curve.fit_area},
        "inverse": inverse,
        "versions": package_versions(),
        "extra": extra,
    }
    return jsonable(record)


def _csv_text(results: list[CalibrationPoint], curve: Curve) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)

    def num(x: float | None) -> str:
        v = finite_or_none(x)
        return "" if v is None else f"{v:.10g}"

    for r in sorted(results, key=lambda r: r.pressure_kpa):
        writer.writerow(
            [
                r.file,
                num(r.pressure_kpa),
                "true" if r.contact else "false",
                num(r.area_px),
                num(r.area_mm2),
                num(curve.area_at(r.pressure_kpa)),
            ]
        )
    return buf.getvalue()


def write_calibration(
    out_dir: str | os.PathLike[str],
    results: list[CalibrationPoint],
    curve: Curve,
    method: str,
    extra: dict[str, Any] | None = None,
) -> dict[str, Path]:
    """Write ``calibration.json``, ``calibration.csv`` and ``curve.png`` into ``out_dir``.

    All or nothing (see the module docstring): on any error no new file is left behind.

    Args:
        out_dir: output folder (created if missing).
        results: per-frame measurements, any order.
        curve: the fitted curve (its ``area_unit`` decides which area is plotted).
        method: name of the measuring method (recorded and shown in the plot title).
        extra: free, JSON-able metadata (e.g. mm_per_px, model path); NaN becomes null.

    Returns:
        ``{"json": path, "csv": path, "png": path}``, final paths.
    """
    out = Path(out_dir)
    paths = {
        "json": out / "calibration.json",
        "csv": out / "calibration.csv",
        "png": out / "curve.png",
    }
    # Serialise first: a content error fails before anything touches the disk.
    text = (
        json.dumps(
            calibration_record(results, curve, method, extra or {}),
            indent=2,
            ensure_ascii=False,
            allow_nan=False,
        )
        + "\n"
    )
    csv_text = _csv_text(results, curve)
    with contextlib.ExitStack() as stack:
        # Entered first, so renamed last: calibration.json appears only after the others.
        tmp_json = stack.enter_context(atomic_path(paths["json"]))
        tmp_csv = stack.enter_context(atomic_path(paths["csv"]))
        tmp_png = stack.enter_context(atomic_path(paths["png"]))
        plot_curve(tmp_png, results, curve, method)
        write_synced(tmp_csv, csv_text)
        write_synced(tmp_json, text)
    return paths


def load_curve(path: str | os.PathLike[str]) -> Curve:
    """Read the fitted `Curve` back from a ``calibration.json`` (for the controller).

    Raises:
        ValueError: unreadable file or not a contactcal calibration.
    """
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        if data.get("format") != FORMAT:
            raise ValueError(f"format {data.get('format')!r}, expected {FORMAT!r}")
        fit = data["fit"]
        step = (data.get("inverse") or {}).get("step")
        return Curve(
            np.asarray(fit["pressure_kpa"], dtype=np.float64),
            np.asarray(fit["area"], dtype=np.float64),
            data["onset_kpa"],
            data["area_unit"],
            step,
        )
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"{path}: not a readable contactcal calibration ({exc})") from exc

"""Calibration outputs: ``calibration.json``, ``calibration.csv``, ``curve.png``, and a text table.

All or nothing (:func:`contactcal.infer.files.atomic.run_outputs`): the three files are written
completely into a staging folder and moved into place only when all succeeded,
``calibration.json`` last; with ``outputs`` they join an enclosing run (e.g. with its overlays).
If anything fails, no new file appears (files from an earlier run are left as they were).
A reader should therefore treat ``calibration.json`` as the record of a complete run.

``calibration.json`` (format version 2) records what the run used: the method and its
configuration (for the U-Net the model file, its sha256 and its training ``data_digest``), the
sha256 of the manifest and of every frame, the command line, the display's ``device_id`` and the
package versions. :func:`load_curve` reads versions 1 and 2.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.plot import plot_curve
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_synced
from contactcal.infer.files.digest import sha256_file
from contactcal.infer.files.jsonable import finite_or_none, json_text, jsonable

# plot_curve is looked up here at call time, so tests can replace it.

FORMAT = "contactcal.calibration"
FORMAT_VERSION = 2
#: Versions :func:`load_curve` reads (2 added the run's provenance; the curve is unchanged).
READABLE_VERSIONS = (1, 2)
#: Longest accepted ``--device-id``, characters.
DEVICE_ID_MAX = 100
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


def check_device_id(device_id: str | None) -> str | None:
    """Validate a display identifier: None, or 1-100 printable characters.

    Raises:
        ValueError: empty, too long or with control characters (the message says which).
    """
    if device_id is None:
        return None
    if not device_id or not device_id.isprintable() or len(device_id) > DEVICE_ID_MAX:
        shown = device_id if len(device_id) <= 40 else device_id[:40] + "…"
        raise ValueError(
            f"--device-id {shown!r}: expected 1-{DEVICE_ID_MAX} printable characters (e.g. the "
            f"display's serial number), got {len(device_id)} characters"
            + ("" if device_id.isprintable() else " including control characters")
        )
    return device_id


def input_digests(manifest: Path, files: Sequence[Path]) -> dict[str, Any]:
    """sha256 of the manifest and of each frame (frame names relative to the manifest's folder).

    Raises:
        OSError: an unreadable file.
    """
    return {
        "manifest": {"file": str(manifest.resolve()), "sha256": sha256_file(manifest)},
        "frames": [
            {"file": os.path.relpath(f, manifest.parent), "sha256": sha256_file(f)} for f in files
        ],
    }


@dataclass(frozen=True)
class Provenance:
    """What a calibration run used, recorded in ``calibration.json``."""

    method_config: dict[str, Any] | None = None  # Method.describe() (None: not recorded)
    inputs: dict[str, Any] | None = None  # input_digests() (None: not recorded)
    argv: list[str] | None = None  # the command line's arguments (None: not run from the CLI)
    device_id: str | None = None  # the calibrated display's identifier (1-100 printable chars)

    def __post_init__(self) -> None:
        check_device_id(self.device_id)


def calibration_record(
    results: list[CalibrationPoint],
    curve: Curve,
    method: str,
    extra: dict[str, Any],
    provenance: Provenance | None = None,
) -> dict[str, Any]:
    """The content of ``calibration.json`` (JSON-safe: no NaN, None for missing values)."""
    prov = provenance or Provenance()
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
        "method_config": prov.method_config,
        "device_id": prov.device_id,
        "argv": prov.argv,
        "area_unit": curve.area_unit,
        "onset_kpa": curve.onset_kpa,
        "calibrated_range": {
            "pressure_kpa": [float(curve.pressures_kpa[0]), float(curve.pressures_kpa[-1])],
            "area": area_range,
        },
        "points": points,
        "fit": {"pressure_kpa": curve.pressures_kpa, "area": curve.fit_area},
        "inverse": inverse,
        "inputs": prov.inputs,
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
    provenance: Provenance | None = None,
    outputs: OutputSet | None = None,
) -> dict[str, Path]:
    """Write ``calibration.json``, ``calibration.csv`` and ``curve.png`` into ``out_dir``.

    All or nothing (see the module docstring): on any error no new file is left behind.

    Args:
        out_dir: output folder (created if missing).
        results: per-frame measurements, any order.
        curve: the fitted curve (its ``area_unit`` decides which area is plotted).
        method: name of the measuring method (recorded and shown in the plot title).
        extra: free, JSON-able metadata (e.g. mm_per_px, model path); NaN becomes null.
        provenance: what the run used (method configuration, input digests, argv, device).
        outputs: the enclosing run's outputs to stage into (None: this call is the run).

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
    record = calibration_record(results, curve, method, extra or {}, provenance)
    text = json_text(record, ensure_ascii=False)
    csv_text = _csv_text(results, curve)
    with run_outputs(join=outputs) as outs:
        plot_curve(outs.stage(paths["png"]), results, curve, method)
        write_synced(outs.stage(paths["csv"]), csv_text)
        write_synced(outs.stage(paths["json"]), text)  # staged last, so moved last
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
        if data.get("format_version") not in READABLE_VERSIONS:
            raise ValueError(
                f"format_version {data.get('format_version')!r}, expected one of "
                f"{', '.join(map(str, READABLE_VERSIONS))} (written by a newer contactcal?)"
            )
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

"""Calibration outputs: ``calibration.json``, ``calibration.csv``, ``curve.png``, and a text table.

All or nothing (:func:`contactcal.infer.files.atomic.run_outputs`): the three files are written
completely into a staging folder and moved into place only when all succeeded,
``calibration.json`` last; with ``outputs`` they join an enclosing run (e.g. with its overlays).
If anything fails, no new file appears (files from an earlier run are left as they were).
A reader should therefore treat ``calibration.json`` as the record of a complete run.

``calibration.json`` (format version 3) holds the per-frame ``points`` (with phase, step, extra
manifest columns and the method's area interval), the per-step aggregates ``steps`` (median,
spread, frame count), one fit per phase under ``phases`` (model chosen by cross-validation,
parametric parameters, 90 % bootstrap band, inverse table with intervals), ``hysteresis``, and
at the top level the inverted phase's onset, fit and inverse as in version 2. It records what
the run used (:mod:`.provenance`). :func:`~contactcal.infer.calibration.load.load_curve` reads
versions 1 to 3.
"""

from __future__ import annotations

import csv
import io
import os
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.load import FORMAT, FORMAT_VERSION, load_curve
from contactcal.infer.calibration.plot import plot_curve
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.provenance import (
    Provenance,
    check_device_id,
    input_digests,
    package_versions,
)
from contactcal.infer.calibration.session import PhaseFit, SessionFit
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_synced
from contactcal.infer.files.jsonable import finite_or_none, json_text, jsonable

# plot_curve is looked up here at call time, so tests can replace it.
__all__ = ["Provenance", "check_device_id", "input_digests", "load_curve", "write_calibration"]

CSV_COLUMNS = (
    "phase",
    "step",
    "pressure_kpa",
    "n_frames",
    "contact",
    "median_area",
    "min_area",
    "q25_area",
    "q75_area",
    "max_area",
    "fit_area",
    "band_lo",
    "band_hi",
    "area_unit",
)


def _point(r: CalibrationPoint, curve: Curve) -> dict[str, Any]:
    return {
        "file": r.file,
        "pressure_kpa": r.pressure_kpa,
        "phase": r.phase,
        "step": r.step,
        "contact": bool(r.contact),
        "area_px": r.area_px,
        "area_mm2": r.area_mm2,
        "area_interval_px": r.area_interval_px,
        "area_interval_mm2": r.area_interval_mm2,
        "fit_area": curve.area_at(r.pressure_kpa),
        "note": r.note,
        "extras": dict(r.extras),
    }


def _steps(fit: SessionFit) -> list[dict[str, Any]]:
    rows = []
    for ph in fit.phases.values():
        band = ph.curve.band
        for s in ph.steps:
            rows.append(
                {
                    "phase": s.phase,
                    "step": s.step,
                    "pressure_kpa": s.pressure_kpa,
                    "n_frames": s.n,
                    "contact": s.contact,
                    "median_area": s.median,
                    "spread": s.spread(),
                    "fit_area": ph.curve.area_at(s.pressure_kpa),
                    "band": None if band is None else list(band.at(s.pressure_kpa)),
                }
            )
    return rows


def _phase(ph: PhaseFit) -> dict[str, Any]:
    c = ph.curve
    inverse = area_range = None
    if c.has_contact:
        step = c.default_table_step()
        rows = c.inverse_table_with_interval(step)
        inverse = {"step": step, **dict(zip(_INV, map(list, zip(*rows, strict=True)), strict=True))}
        area_range = list(c.area_range())
    m, b = c.model, c.band
    return {
        "model": ph.selection["model"],
        "selection": ph.selection,
        "onset_kpa": c.onset_kpa,
        "onset_bracket_kpa": None if c.onset_bracket_kpa is None else list(c.onset_bracket_kpa),
        "onset_rule": c.onset_rule,
        "resolution": ph.resolution(),
        "calibrated_range": {
            "pressure_kpa": [float(c.pressures_kpa[0]), float(c.pressures_kpa[-1])],
            "area": area_range,
        },
        "fit": {"pressure_kpa": c.pressures_kpa, "area": c.fit_area},
        "parametric": None
        if m is None
        else {"p0_kpa": m.p0_kpa, "k_kpa": m.k_kpa, "a_max": m.a_max},
        "band": None
        if b is None
        else {
            "level": b.level,
            "n_resamples": b.n_resamples,
            "seed": b.seed,
            "pressure_kpa": b.pressures_kpa,
            "lo": b.lo,
            "hi": b.hi,
        },
        "inverse": inverse,
    }


_INV = ("area", "pressure_kpa", "pressure_lo_kpa", "pressure_hi_kpa")


def calibration_record(
    results: list[CalibrationPoint],
    fit: SessionFit,
    method: str,
    extra: dict[str, Any],
    provenance: Provenance | None = None,
) -> dict[str, Any]:
    """The content of ``calibration.json`` (JSON-safe: no NaN, None for missing values)."""
    prov = provenance or Provenance()
    order = {ph: i for i, ph in enumerate(fit.phases)}
    ordered = sorted(results, key=lambda r: (order.get(r.phase, 9), r.pressure_kpa))
    phases = {name: _phase(ph) for name, ph in fit.phases.items()}
    main = phases[fit.inverse_phase]
    record = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "method": method,
        "method_config": prov.method_config,
        "device_id": prov.device_id,
        "argv": prov.argv,
        "area_unit": fit.curve.area_unit,
        "inverse_phase": fit.inverse_phase,
        "phase_source": fit.phase_source,
        "onset_kpa": main["onset_kpa"],
        "calibrated_range": main["calibrated_range"],
        "points": [_point(r, fit.phases[r.phase].curve) for r in ordered],
        "steps": _steps(fit),
        "fit": main["fit"],
        "inverse": main["inverse"],
        "phases": phases,
        "hysteresis": fit.hysteresis,
        "inputs": prov.inputs,
        "versions": package_versions(),
        "extra": extra,
    }
    return jsonable(record)


def _csv_text(fit: SessionFit) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)

    def num(x: float | None) -> str:
        v = finite_or_none(x)
        return "" if v is None else f"{v:.10g}"

    for row in _steps(fit):
        sp, band = row["spread"], row["band"] or [None, None]
        writer.writerow(
            [
                row["phase"],
                row["step"],
                num(row["pressure_kpa"]),
                row["n_frames"],
                "true" if row["contact"] else "false",
                *(num(v) for v in (row["median_area"], sp["min"], sp["q25"], sp["q75"], sp["max"])),
                *(num(v) for v in (row["fit_area"], *band)),
                fit.curve.area_unit,
            ]
        )
    return buf.getvalue()


#: The files a calibration writes into its folder.
CALIBRATION_FILES = ("calibration.json", "calibration.csv", "curve.png")


def write_calibration(
    out_dir: str | os.PathLike[str],
    results: list[CalibrationPoint],
    fit: SessionFit,
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
        fit: the fitted session (its curves' ``area_unit`` decides which area is plotted).
        method: name of the measuring method (recorded and shown in the plot title).
        extra: free, JSON-able metadata (e.g. mm_per_px, model path); NaN becomes null.
        provenance: what the run used (method configuration, input digests, argv, device).
        outputs: the enclosing run's outputs to stage into (None: this call is the run).

    Returns:
        ``{"json": path, "csv": path, "png": path}``, final paths.
    """
    out = Path(out_dir)
    keys = ("json", "csv", "png")
    paths = {key: out / name for key, name in zip(keys, CALIBRATION_FILES, strict=True)}
    # Serialise first: a content error fails before anything touches the disk.
    record = calibration_record(results, fit, method, extra or {}, provenance)
    text = json_text(record, ensure_ascii=False)
    csv_text = _csv_text(fit)
    with run_outputs(join=outputs) as outs:
        plot_curve(outs.stage(paths["png"]), results, fit, method, record["device_id"])
        write_synced(outs.stage(paths["csv"]), csv_text)
        write_synced(outs.stage(paths["json"]), text)  # staged last, so moved last
    return paths

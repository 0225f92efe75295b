"""Calibrate one session: measure every frame, fit area vs pressure, write the outputs."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from contactcal.infer.calibration.curve import MM2, PX, Curve
from contactcal.infer.calibration.fit import CurveConfig, fit_monotone
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.record import Provenance, input_digests, write_calibration
from contactcal.infer.calibration.table import format_table
from contactcal.infer.errors import RunError
from contactcal.infer.files.atomic import OutputSet, run_outputs
from contactcal.infer.methods.registry import make_method
from contactcal.infer.pipeline.manifest import Frame, read_manifest
from contactcal.infer.pipeline.measure import Measured, measure_files
from contactcal.infer.pipeline.scale import PixelScale


@dataclass(frozen=True)
class CalibrationReport:
    """What a calibration run produced."""

    table: str  # the short text table the CLI prints
    frames: list[Frame]  # manifest rows, sorted by pressure
    measured: list[Measured]  # per frame, same order
    curve: Curve
    files: dict[str, Path]  # "json", "csv", "png"


def calibrate_session(
    manifest: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    method_name: str,
    model: str | os.PathLike[str] | None = None,
    scale: PixelScale | None = None,
    curve_config: CurveConfig | None = None,
    outline: bool = False,
    argv: Sequence[str] | None = None,
    device_id: str | None = None,
    outputs: OutputSet | None = None,
    bit_depth: int | None = None,
) -> CalibrationReport:
    """Calibrate the session listed in ``manifest`` and write its outputs into ``out_dir``.

    The lowest-pressure frame is the session's reference (ROI for the classical method).

    Args:
        manifest: CSV with columns ``file,pressure_kpa`` (paths relative to the manifest).
        out_dir: folder for ``calibration.json``, ``calibration.csv`` and ``curve.png``.
        method_name: ``"classical"`` (or ``"unet"`` where available).
        model: ONNX model path for learned methods (None → the shipped one).
        scale: pixel scale; None → the curve is in px (``area_mm2`` null).
        curve_config: fit settings (None → defaults).
        outline: keep each frame's outline in input pixels (for overlays).
        argv: the command line's arguments, recorded (None: not run from the command line).
        device_id: identifier of the calibrated display, recorded (1-100 printable characters).
        outputs: the enclosing run's outputs to stage into (None: this call is the run). The
            manifest and its frames are protected: no output may replace them.
        bit_depth: significant bits of 16-bit frames (``--bit-depth``); None → from the files.

    Returns:
        The :class:`CalibrationReport` (table, measurements, curve, written files).

    Raises:
        ManifestError / ImageError: bad manifest or frame (nothing written).
        ValueError: an invalid ``device_id``, or an output that would replace an input.
        RunError: no contact in any frame (nothing written).
    """
    manifest = Path(manifest)
    provenance = Provenance(argv=None if argv is None else list(argv), device_id=device_id)
    frames = read_manifest(manifest)
    method = make_method(method_name, None if model is None else str(model), outline=outline)
    files = [f.file for f in frames]
    measured = measure_files(files, method, frames[0].file, scale, bit_depth=bit_depth)
    results = _points(manifest, frames, measured)
    if not any(r.contact for r in results):
        raise RunError(
            f"{manifest}: no contact detected in any of its {len(results)} frames "
            f"(method {method.name}); check the frames, the pressure range or the method"
        )
    use_mm = scale is not None
    areas = [r.area_mm2 if use_mm else r.area_px for r in results]
    curve = fit_monotone(
        [r.pressure_kpa for r in results],
        areas,
        [r.contact for r in results],
        curve_config or CurveConfig(),
        area_unit=MM2 if use_mm else PX,
    )
    extra = {
        "manifest": str(manifest.resolve()),
        "mm_per_px": None if scale is None else scale.mm_per_px,
        "scale_image_width_px": None if scale is None else scale.image_width_px,
    }
    provenance = replace(
        provenance, method_config=method.describe(), inputs=input_digests(manifest, files)
    )
    with run_outputs([manifest, model, *files], join=outputs) as outs:
        paths = write_calibration(out_dir, results, curve, method.name, extra, provenance, outs)
    return CalibrationReport(format_table(results, curve), frames, measured, curve, paths)


def _points(
    manifest: Path, frames: list[Frame], measured: list[Measured]
) -> list[CalibrationPoint]:
    """The session's points, file names relative to the manifest's folder."""
    return [
        CalibrationPoint(
            file=os.path.relpath(m.file, manifest.parent),
            pressure_kpa=f.pressure_kpa,
            contact=m.result.contact,
            area_px=float(m.result.area_px),
            area_mm2=m.area_mm2,
            note=m.result.note,
        )
        for f, m in zip(frames, measured, strict=True)
    ]

"""Calibrate one session: measure every frame, fit area vs pressure, write the outputs."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from contactcal.infer.calibration.curve import MM2, PX, Curve
from contactcal.infer.calibration.fit import CurveConfig
from contactcal.infer.calibration.phases import LOADING
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.provenance import Provenance, identical_frames, input_digests
from contactcal.infer.calibration.record import write_calibration
from contactcal.infer.calibration.session import SessionFit, fit_session
from contactcal.infer.calibration.session_checks import check_inverse_contact, session_points
from contactcal.infer.calibration.steps import (
    frames_off_their_step,
    off_step_warning,
    step_outlier_floor,
)
from contactcal.infer.calibration.table import format_table
from contactcal.infer.calibration.table_notes import LISTED_FRAMES, session_notes
from contactcal.infer.files.atomic import OutputSet, run_outputs
from contactcal.infer.image.read import ImageFile
from contactcal.infer.methods.base import Method
from contactcal.infer.pipeline.manifest import Frame, Session, check_sweep_unit, read_session
from contactcal.infer.pipeline.manifest_rows import listed_name
from contactcal.infer.pipeline.measure import Measured
from contactcal.infer.pipeline.options import MeasureOptions
from contactcal.infer.pipeline.readings import DEFAULT_STEP_TOLERANCE_KPA
from contactcal.infer.pipeline.scale import PixelScale


@dataclass(frozen=True)
class CalibrationReport:
    """What a calibration run produced."""

    table: str  # the short text table the CLI prints
    frames: list[Frame]  # manifest rows, sorted by phase (loading first), pressure, row
    measured: list[Measured]  # per frame, same order
    curve: Curve  # the inverted phase's curve (fit.curve)
    files: dict[str, Path]  # "json", "csv", "png"
    fit: SessionFit  # every phase's steps, curve and band; hysteresis


@dataclass(frozen=True)
class SessionOptions:
    """How a session's measurements become its curves (passed whole; command-line defaults)."""

    #: The fit's settings (running median, curve model, bootstrap band, inverse-table step).
    curve: CurveConfig = field(default_factory=CurveConfig)
    #: The phase whose curve is inverted (``--inverse-phase``); a session without that phase
    #: is refused.
    inverse_phase: str = LOADING
    #: Apply the session rule (:mod:`~contactcal.infer.calibration.rings`): the steps whose
    #: region shrinks at the next pressure beyond both stated intervals (with the
    #: non-increasing run of steps before them) and the contacts left below the contact range
    #: become "no contact", each with a note saying so. False: ``--per-frame-contact`` keeps
    #: each frame's own contact flag. Recorded in ``extra``.
    session_rule: bool = True
    #: kPa: manifest readings less than this apart are one step (``--step-tolerance-kpa``;
    #: :mod:`~contactcal.infer.pipeline.readings`): a logger's readings of one held pressure
    #: are pooled as a step's repeats. 0: every distinct value is a step (a video run's
    #: manifest, whose steps are already found). Recorded in ``extra``.
    step_tolerance_kpa: float = DEFAULT_STEP_TOLERANCE_KPA


def calibrate_session(
    manifest: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    method: str | Method,
    measure: MeasureOptions | None = None,
    options: SessionOptions | None = None,
    provenance: Provenance | None = None,
    outputs: OutputSet | None = None,
    manifest_as: str | os.PathLike[str] | None = None,
    session: Session | None = None,
    contents: dict[Path, ImageFile] | None = None,
) -> CalibrationReport:
    """Calibrate the session listed in ``manifest`` and write its outputs into ``out_dir``.

    The lowest-pressure frame of the loading pass is the session's reference. Repeated frames
    of a pressure step are aggregated by their median area; each phase (loading, unloading)
    gets its own curve and band (:func:`fit_session`), after the session rule
    (:attr:`SessionOptions.session_rule`) where it applies.

    Args:
        manifest: CSV with columns ``file,pressure_kpa`` and optionally ``phase`` and others
            (:mod:`contactcal.infer.pipeline.manifest`; paths relative to the manifest).
        out_dir: folder for ``calibration.json``, ``calibration.csv`` and ``curve.png``.
        method: ``"unet"`` or ``"classical"``, built here from ``measure``; or that method
            built already from ``measure`` (a video run's, loaded before its recording is read).
        measure: how the frames are measured (model, scale in mm/px, boundary offset, bit
            depth, change gate, threads, outlines); None: the defaults (areas in px).
        options: how the measurements become curves; None: the defaults.
        provenance: the command line, the display's id, a video run's recording and preview
            method and the overlays' methods to record (its ``method_config`` and ``inputs``
            are filled in here); None: none of them.
        outputs: the enclosing run's outputs to stage into (None: this call is the run). The
            manifest and its frames are protected: no output may replace them.
        manifest_as: the path recorded for the manifest: its final place when the manifest
            itself is an output staged in this run (video input); None → ``manifest``.
        session: ``manifest`` as the caller read it with ``options.step_tolerance_kpa``
            (:func:`~contactcal.infer.pipeline.manifest.read_session`; the command shares its
            one read with its rig note), not read again; None: read here.
        contents: the frames' contents the caller holds (``demo``'s for both methods and the
            montage, ``calibrate --overlay``'s for the outlines and the drawing too): each
            frame not in it yet is read into it once, after the manifest's and the method's
            checks (:func:`~contactcal.infer.pipeline.measure.measure_files`), and measured
            and recorded as read; None: each frame read here, when it is measured.

    Returns:
        The :class:`CalibrationReport` (table, measurements, curve, written files).

    Raises:
        ManifestError / ImageError: bad manifest or frame (nothing written).
        ValueError: an output that would replace an input, or an ``inverse_phase`` the session
            does not have.
        RunError: no contact in any frame, or none in the inverted pass (nothing written).
    """
    manifest = Path(manifest)
    measure = measure if measure is not None else MeasureOptions()
    options = options if options is not None else SessionOptions()
    if session is None:
        session = read_session(manifest, options.step_tolerance_kpa)
    check_sweep_unit(manifest, session.frames)
    frames, files = session.frames, [f.file for f in session.frames]
    method = measure.method(method) if isinstance(method, str) else method
    measured = measure.measure(files, method, files[0], digest=True, contents=contents)
    points = _points(session.folder, frames, measured, measure.scale)
    where = Path(manifest_as if manifest_as is not None else manifest)  # not a staging path
    results, checks = session_points(where, points, options.session_rule, method.name)
    unit = PX if measure.scale is None else MM2
    fit = fit_session(results, unit, options.curve, options.inverse_phase, session.phase_source)
    check_inverse_contact(where, fit)
    floor = step_outlier_floor(unit, measured[0].width)
    off = frames_off_their_step([s for ph in fit.phases.values() for s in ph.steps], floor)
    recorded = Path(manifest_as if manifest_as is not None else manifest).resolve()
    given = provenance if provenance is not None else Provenance()
    digests = [(m.file, m.sha256) for m in measured]
    provenance = replace(
        given,
        method_config=method.describe(),
        inputs=input_digests(manifest, session, digests, recorded, given.recording),
    )
    same = identical_frames(provenance.inputs, [f.pressure_kpa for f in frames])
    listed = listed_name(session.folder, frames[0].file)
    extra = {
        **_extra(recorded, listed, measure.scale, measured),
        "session_rule": options.session_rule,
        "step_tolerance_kpa": options.step_tolerance_kpa,
        "readings_pooled": None if session.pooled is None else asdict(session.pooled),
        "readings_at_rest": None if session.at_rest is None else asdict(session.at_rest),
        "rows_out_of_order": list(session.out_of_order),
        "frames_off_their_step": [asdict(o) for o in off],
        "rig_note": provenance.rig_note,
        "overlay_methods": provenance.overlay_methods,
        "preview_method": provenance.preview_method,
    }
    extra |= checks | {"identical_frames": same}
    model = None if measure.model is None else str(measure.model)
    with run_outputs([manifest, model, *files], join=outputs) as outs:
        paths = write_calibration(out_dir, results, fit, method.name, extra, provenance, outs)
    table = format_table(results, fit, provenance.device_id)
    off_warning = off_step_warning(off, unit, floor, LISTED_FRAMES) if off else None
    notes = session_notes(session, results, checks, same, options, off_warning)
    table += "".join("\n" + line for line in notes)
    return CalibrationReport(table, frames, measured, fit.curve, paths, fit)


def _interval(
    m: Measured, scale: PixelScale | None
) -> tuple[tuple[float, float] | None, tuple[float, float] | None]:
    """The method's stated area interval of a frame, in px and mm² (None where absent)."""
    iv = getattr(m.result, "area_interval_px", None)
    if iv is None:
        return None, None
    px = (float(iv[0]), float(iv[1]))
    if scale is None:
        return px, None
    return px, (scale.area_mm2(px[0], m.width), scale.area_mm2(px[1], m.width))


def _points(
    folder: Path, frames: list[Frame], measured: list[Measured], scale: PixelScale | None
) -> list[CalibrationPoint]:
    """The session's points, frames named as the manifest lists them (``folder``: its
    :attr:`~contactcal.infer.pipeline.manifest.Session.folder`)."""
    return [
        CalibrationPoint(
            listed_name(folder, m.file),
            f.pressure_kpa,
            m.result.contact,
            float(m.result.area_px),
            m.area_mm2,
            m.result.note,
            f.phase,
            f.step,
            f.extras,
            *_interval(m, scale),
        )
        for f, m in zip(frames, measured, strict=True)
    ]


def _extra(
    manifest: Path, reference: str, scale: PixelScale | None, measured: Sequence[Measured]
) -> dict[str, object]:
    """The record's ``extra``: the manifest's path, the reference frame every frame was measured
    against (the loading pass's lowest-pressure frame, as the manifest lists it), the pixel
    scale and the boundary offset applied (mm; null: none, e.g. none in the rig config, or the
    classical routine)."""
    return {
        "manifest": str(manifest),
        "reference_frame": reference,
        "mm_per_px": None if scale is None else scale.mm_per_px,
        "scale_image_width_px": None if scale is None else scale.image_width_px,
        "boundary_offset_mm": measured[0].boundary_offset_mm if measured else None,
    }

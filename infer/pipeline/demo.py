"""``contactcal demo``: the main job on the embedded example session, with both methods."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from contactcal.infer.calibration.calibrate import (
    CalibrationReport,
    SessionOptions,
    calibrate_session,
)
from contactcal.infer.calibration.provenance import Provenance
from contactcal.infer.calibration.record import CALIBRATION_FILES
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_synced
from contactcal.infer.image.read import ImageFile
from contactcal.infer.image.write import write_image
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.pipeline.args import NO_SCALE_NOTE
from contactcal.infer.pipeline.boundary import rig_boundary
from contactcal.infer.pipeline.examples import example_manifest
from contactcal.infer.pipeline.manifest import beside_manifest, read_session
from contactcal.infer.pipeline.options import MeasureOptions
from contactcal.infer.pipeline.overlay import draw_overlay, frame_title, measured_frame, montage
from contactcal.infer.pipeline.scale import read_rig_json, rig_scale

#: Pressures shown in the overlay montage, kPa: per pressure the frame nearest to it over both
#: passes of a two-pass session (not the loading pass only: an unloading frame nearer to it is
#: shown, titled as such), on a tie the first frame in the session's order (loading first, then
#: by pressure and manifest row); a frame nearest to two of them is shown once.
MONTAGE_KPA = (0.0, 2.0, 4.0, 8.0, 14.0, 20.0)
#: The files a demo writes into its output folder: each method's calibration, the montage and
#: the summary.
MONTAGE, SUMMARY = "overlay_montage.png", "summary.txt"
DEMO_FILES = (*(f"{m}/{n}" for m in METHODS for n in CALIBRATION_FILES), MONTAGE, SUMMARY)

#: Where ``demo`` looks for a pixel scale (it has no --mm-per-px or --rig), as
#: :data:`~contactcal.infer.pipeline.args.NO_SCALE_NOTE` says when it finds none.
DEMO_SCALE = "no rig.json beside the manifest"


def demo_measure(manifest: Path, bit_depth: int | None = None) -> MeasureOptions:
    """How ``demo`` measures the session ``manifest`` lists: with the scale and boundary offset
    of the ``rig.json`` beside it, read once as ``calibrate`` reads it (none: no scale, areas in
    px), outlines for the montage, and ``bit_depth`` (``--bit-depth``; None: from each file).

    Raises:
        RigConfigError: that rig.json unreadable or not a rig config's JSON object.
    """
    rig = beside_manifest(manifest)
    measure = MeasureOptions(bit_depth=bit_depth, outline=True)
    if not rig.is_file():
        return measure
    data = read_rig_json(rig)
    return replace(measure, scale=rig_scale(data, rig), boundary=rig_boundary(data, str(rig)))


def run_demo(
    out_dir: str | os.PathLike[str],
    manifest: str | os.PathLike[str] | None = None,
    argv: Sequence[str] | None = None,
    options: SessionOptions | None = None,
    measure: MeasureOptions | None = None,
    outputs: OutputSet | None = None,
) -> str:
    """Calibrate a session (default: the bundled example) with every method.

    Writes ``<out>/<method>/{calibration.json, calibration.csv, curve.png}``, a side-by-side
    overlay montage ``<out>/overlay_montage.png`` (the frames :data:`MONTAGE_KPA` picks, each
    titled by its pressure and pass) and ``<out>/summary.txt``, all or nothing.
    The manifest and each frame are read once: every method measures the same content, each
    record names its sha256, and the montage is drawn on it (a file replaced during the run
    is measured, recorded and drawn as it was read).

    Args:
        out_dir: the output folder.
        manifest: the session; None: the bundled example.
        argv: the command line, recorded in each ``calibration.json`` (None: not run from it).
        options: how the measurements become curves (``--step-tolerance-kpa``); None: the
            defaults, as ``calibrate``'s.
        measure: how its frames are measured, as :func:`demo_measure` decides it (the caller
            decided it first: ``demo`` checks its ``--out`` against the scale); None:
            ``demo_measure(manifest)``.
        outputs: the enclosing run's outputs to stage into (None: this call is the run).

    Returns:
        The printed summary (one table per method).
    """
    out = Path(out_dir)
    manifest = Path(manifest) if manifest is not None else example_manifest()
    measure = demo_measure(manifest) if measure is None else measure
    options = options if options is not None else SessionOptions()
    session = read_session(manifest, options.step_tolerance_kpa)
    frames = session.frames
    read: dict[Path, ImageFile] = {}  # filled by the first method's read: both, the montage
    recorded = Provenance(argv=None if argv is None else list(argv))
    reports: dict[str, CalibrationReport] = {}
    lines = [f"session: {manifest}"]
    with run_outputs(join=outputs) as outs:
        for method in METHODS:
            rep = calibrate_session(
                manifest,
                out / method,
                method,
                measure,
                options,
                recorded,
                outputs=outs,
                session=session,
                contents=read,
            )
            reports[method] = rep
            lines += [f"\n== {method} → {out / method}", rep.table]
        pressures = [f.pressure_kpa for f in frames]
        picks = sorted({int(np.argmin(np.abs(np.subtract(pressures, p)))) for p in MONTAGE_KPA})
        tiles = []
        for i in picks:
            at = {name: rep.measured[i] for name, rep in reports.items()}
            contours = {name: m.result.contour for name, m in at.items()}
            gray = measured_frame(read[frames[i].file], at, measure.bit_depth)
            tiles.append(draw_overlay(gray, contours, frame_title(frames[i])))
        write_image(outs.stage(out / MONTAGE), montage(tiles, columns=3))
        lines.append(f"\noverlays: {out / MONTAGE}")
        if measure.scale is None:  # as calibrate says it
            lines.append(NO_SCALE_NOTE.format(looked=DEMO_SCALE))
        text = "\n".join(lines) + "\n"
        write_synced(outs.stage(out / SUMMARY), text)
    return text

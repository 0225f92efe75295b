"""The ``calibrate`` subcommand (still frames listed in a manifest; video and camera input
through :mod:`contactcal.infer.video.command`)."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from contactcal.infer.parser import folder_arg
from contactcal.infer.pipeline.args import (
    MANIFEST_SCALE,
    NO_SCALE_NOTE,
    VIDEO_SCALE,
    check_change_gate,
    check_out_folder,
    check_output_folder,
    measure_options,
    method_args,
    read_rig,
    run_inputs,
    scale_args,
)
from contactcal.infer.pipeline.overlay_measure import (
    overlay_contents,
    overlay_methods,
    overlay_runs,
)
from contactcal.infer.pipeline.readings import DEFAULT_STEP_TOLERANCE_KPA, check_tolerance

if TYPE_CHECKING:
    from contactcal.infer.calibration.calibrate import CalibrationReport, SessionOptions
    from contactcal.infer.calibration.provenance import Provenance
    from contactcal.infer.pipeline.manifest import Session
    from contactcal.infer.pipeline.options import MeasureOptions


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``calibrate`` to the ``contactcal`` subcommands."""
    from contactcal.infer.video.args import add_video_args

    c = sub.add_parser("calibrate", help="calibrate a session: area vs pressure and its inverse")
    c.add_argument("manifest", type=Path, nargs="?", metavar="MANIFEST.csv")
    method_args(c)
    c.add_argument("--out", type=folder_arg, required=True, help="output folder")
    c.add_argument(
        "--inverse-phase",
        choices=("loading", "unloading"),
        default="loading",
        help="pass whose curve is inverted (default %(default)s)",
    )
    c.add_argument(
        "--per-frame-contact",
        action="store_true",
        help="keep every frame's contact flag as measured: no session rule revising regions "
        "that shrink at the next pressure (the inner ring before contact) to no contact",
    )
    add_step_tolerance_arg(c, "; a video run's steps come from --tolerance-kpa")
    scale_args(c)
    add_video_args(c)
    c.set_defaults(func=_cmd_calibrate)


def add_step_tolerance_arg(parser: argparse.ArgumentParser, more: str = "") -> None:
    """Add ``--step-tolerance-kpa`` (read by :func:`step_tolerance`) to a command that
    calibrates a manifest (``calibrate``, ``demo``); ``more`` ends its help's parenthesis."""
    parser.add_argument(
        "--step-tolerance-kpa",
        type=float,
        metavar="T",
        help="manifest pressures less than T kPa apart are one step, its frames pooled (gauge "
        "readings of one held pressure); 0: every distinct value is a step (default "
        f"{DEFAULT_STEP_TOLERANCE_KPA:g}{more})",
    )


def step_tolerance(args: argparse.Namespace) -> float:
    """kPa: ``--step-tolerance-kpa`` (its default when not given).

    Raises:
        ValueError: out of range, naming the option and the range expected.
    """
    t = DEFAULT_STEP_TOLERANCE_KPA if args.step_tolerance_kpa is None else args.step_tolerance_kpa
    try:
        check_tolerance(t)
    except ValueError as exc:
        raise ValueError(f"--step-tolerance-kpa {t:g}: {exc}") from None
    return t


def session_options(args: argparse.Namespace) -> SessionOptions:
    """The calibration's :class:`~contactcal.infer.calibration.calibrate.SessionOptions` from
    ``--inverse-phase``, ``--per-frame-contact`` and ``--step-tolerance-kpa`` (the fit's
    settings: their defaults)."""
    from contactcal.infer.calibration.calibrate import SessionOptions

    return SessionOptions(
        inverse_phase=args.inverse_phase,
        session_rule=not args.per_frame_contact,
        step_tolerance_kpa=step_tolerance(args),
    )


def _cmd_calibrate(args: argparse.Namespace) -> int:
    """``contactcal calibrate``: every check that needs no frame first, then a manifest's
    still frames here, or a recording (:func:`~contactcal.infer.video.command.calibrate_video`).
    """
    from contactcal.infer.calibration.out_folder import check_reused_out
    from contactcal.infer.calibration.provenance import Provenance
    from contactcal.infer.calibration.record import CALIBRATION_FILES
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.manifest import beside_manifest, read_session, reference_width
    from contactcal.infer.pipeline.overlay import earlier_overlays_note, overlay_names
    from contactcal.infer.pipeline.rig_note import rig_note
    from contactcal.infer.video.args import is_video_run
    from contactcal.infer.video.command import calibrate_video
    from contactcal.infer.video.fresh_out import check_fresh_recording

    provenance = Provenance(argv=args.argv, device_id=args.device_id)  # refuses a bad id
    check_change_gate(args)
    check_out_folder(args.out, "calibrate", CALIBRATION_FILES)  # before the work
    video = is_video_run(args)  # checks the options' combination
    beside = None if video else beside_manifest(args.manifest)
    rig = read_rig(args, beside)
    measure = measure_options(args, rig)  # the run's scale, before the --out check needs it
    no_scale = None if measure.scale is not None else VIDEO_SCALE if video else MANIFEST_SCALE
    # an earlier recording's frames or preview (first: no other fix lets a recording into that
    # --out), another display's record, or one in mm² this run would make px: refused before
    # any work
    manifest = None if video else args.manifest
    if video:
        check_fresh_recording(args.out)
    replaced = check_reused_out(args.out, args.device_id, manifest, no_scale)
    if video:  # --video / --camera: contactcal.infer.video.command
        return calibrate_video(args, measure, provenance, replaced)
    options = session_options(args)
    session = read_session(args.manifest, options.step_tolerance_kpa)  # read once, passed on
    named_as = tuple(overlay_names([f.file for f in session.frames]))
    check_output_folder("--overlay", args.overlay, named_as)  # before any frame is read
    set_aside = rig_note(
        args, measure, beside, rig, lambda: reference_width(session, args.bit_depth)
    )
    provenance = replace(provenance, rig_note=set_aside)  # recorded: extra.rig_note
    rep, written = _write_outputs(args, measure, options, provenance, session)
    overlays = [] if args.overlay is None else [args.overlay]
    with printing_after([args.out, *overlays], [set_aside, replaced]):
        print(rep.table)
        if no_scale is not None:
            print(NO_SCALE_NOTE.format(looked=no_scale))
        for note in (set_aside, replaced, earlier_overlays_note(written)):
            if note is not None:
                print(note)
    return 0


def _write_outputs(
    args: argparse.Namespace,
    measure: MeasureOptions,
    options: SessionOptions,
    provenance: Provenance,
    session: Session,
) -> tuple[CalibrationReport, list[Path]]:
    """Calibrate the manifest's ``session`` into ``--out`` and draw its overlays into
    ``--overlay`` (when given), all or nothing: staged together, moved into place together.

    Returns:
        The calibration's report and the overlays written (none without ``--overlay``).
    """
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.image.read import sources_of
    from contactcal.infer.pipeline.overlay import frame_title, write_overlays

    written: list[Path] = []
    named = {"--out": args.out, "--overlay": args.overlay}
    with run_outputs(run_inputs(args), options=named) as outs:
        read = overlay_contents(args)  # None: no --overlay; filled as the frames are measured
        # the methods drawing only outlines, built (a --model loaded) before a frame is read,
        # recorded as loaded: extra.overlay_methods
        drawn = {} if read is None else overlay_methods(args, measure)
        if read is not None:
            described = {name: m.describe() for name, m in drawn.items()}
            provenance = replace(provenance, overlay_methods=described)
        rep = calibrate_session(
            args.manifest,
            args.out,
            args.method,
            measure,
            options,
            provenance,
            outputs=outs,
            session=session,
            contents=read,
        )
        if read is not None:
            frames = sources_of([f.file for f in rep.frames], read)
            runs = overlay_runs(args, measure, rep.measured, frames, frames[0], drawn)
            titles = [frame_title(f) for f in rep.frames]
            written = write_overlays(
                runs, read, args.overlay, titles, outputs=outs, bit_depth=args.bit_depth
            )
    return rep, written

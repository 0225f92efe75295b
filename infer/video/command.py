"""``contactcal calibrate --video VIDEO | --camera INDEX --pressure-log LOG.csv --out DIR``.

The frames taken in steady pressure steps are written to ``DIR/frames/`` with a manifest
(:mod:`.extract`), then the session is calibrated exactly as ``contactcal calibrate MANIFEST``
(:func:`~contactcal.infer.calibration.calibrate.calibrate_session`), with the method built before
the recording is opened (:func:`_methods`: a bad ``--model`` is refused before any frame). Frames,
manifest, calibration and preview are one run's outputs: all written, or none; the video and the
log are inputs, never replaced, and ``calibration.json`` records them (``inputs.recording``: each
file's path and sha256, the camera's index): the log's of the bytes parsed, the video's streamed
right before it is decoded; a video file that changed by the end of its decoding (its size, time
or inode) is refused, so the recorded sha256 is of the frames decoded. An ``--out`` holding an
earlier recording's outputs (frames, or a preview that a run without ``--preview`` would leave
beside its calibration) is refused before any work
(:func:`~contactcal.infer.video.fresh_out.check_fresh_recording`).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from contactcal.infer.video.step_config import StepConfig

#: ``OPENCV_FFMPEG_LOGLEVEL`` of a video run: FFmpeg's AV_LOG_QUIET (the command says what failed).
FFMPEG_QUIET = "-8"

if TYPE_CHECKING:
    import numpy as np

    from contactcal.infer.calibration.calibrate import CalibrationReport
    from contactcal.infer.calibration.provenance import Provenance
    from contactcal.infer.files.atomic import OutputSet
    from contactcal.infer.methods.base import Method
    from contactcal.infer.pipeline.options import MeasureOptions
    from contactcal.infer.video.extract import Extractor, VideoFile
    from contactcal.infer.video.live import Preview
    from contactcal.infer.video.log import PressureLog

#: Preview frame rate when the camera states none, frames/s.
DEFAULT_CAMERA_FPS = 30.0


def _methods(args: argparse.Namespace, measure: MeasureOptions) -> tuple[Method, Method | None]:
    """The run's method and the preview's U-Net with outlines (None: no preview,
    :func:`~contactcal.infer.video.args.has_preview`), built before the recording is opened: a
    U-Net's model file is read once for both, and a bad ``--model`` refused before any frame.

    Raises:
        ValueError: an unusable ``--model`` (``--model MODEL: ...``).
    """
    from contactcal.infer.video.args import has_preview

    previewed = has_preview(args)
    if args.method == "unet" or previewed:
        measure = measure.read_model()
    preview = measure.method("unet", outline=True) if previewed else None
    return measure.method(args.method), preview


def _preview(
    args: argparse.Namespace,
    method: Method | None,
    outs: OutputSet,
    extractor: Extractor,
    fps: float,
) -> Preview | None:
    """The preview drawn with ``method`` (:func:`_methods`; None: no preview), to a window
    (``--show``) or staged into ``--out``."""
    from contactcal.infer.video.live import Preview, preview_format
    from contactcal.infer.video.preview_files import PREVIEW_STEM

    if method is None:
        return None
    if args.show:
        return Preview(method, extractor, None, "", fps)
    suffix, fourcc = preview_format()
    return Preview(method, extractor, outs.stage(args.out / f"{PREVIEW_STEM}{suffix}"), fourcc, fps)


def _source(
    args: argparse.Namespace,
) -> tuple[
    Iterator[tuple[float, np.ndarray]],
    Callable[[], PressureLog | None],
    Callable[[Extractor, float], bool],
    float,
    VideoFile | None,
]:
    """``(frames, feed, stop, fps, video)`` of the recording (``--video`` with its whole
    pressure log; ``video``: the file opened, with its sha256) or the camera (``--camera``, the
    log polled as it grows; stops back at rest or at ``--duration-s``; ``video`` None), for
    :func:`~contactcal.infer.video.extract.extract_frames`; a recording's log in another unit
    than kPa is refused before its video is hashed and opened."""
    import cv2

    from contactcal.infer.pipeline.manifest import check_sweep_top
    from contactcal.infer.video import extract, live
    from contactcal.infer.video.log import read_pressure_log

    if args.video is not None:
        log = read_pressure_log(args.pressure_log)
        # a log in bar or MPa (or at rest) is refused before the video is read (minutes, for a
        # long one): every step is below its highest reading; the used steps are checked again
        # after extraction, as a live log's can only be then
        check_sweep_top(args.pressure_log, float(log.pressures_kpa.max()))
        logs = iter([log])
        video = extract.open_video(args.video)
        return (
            extract.video_frames(video),
            lambda: next(logs, None),
            lambda e, t: False,
            video.fps,
            video,
        )
    feed = live.LogPoller(args.pressure_log)
    cap = live.open_camera(args.camera)
    fps = cap.get(cv2.CAP_PROP_FPS) or DEFAULT_CAMERA_FPS
    limit = args.duration_s

    def stop(e: extract.Extractor, t: float) -> bool:
        return live.returned_to_zero(e, t) or (limit is not None and t >= limit)

    return live.capture_frames(cap), feed, stop, fps, None


def _recording(args: argparse.Namespace, video: VideoFile | None, ex: Extractor) -> dict[str, Any]:
    """The record of the video (or camera) and the pressure log the frames came from: the log
    as the extractor last used it (read once for a video; a camera's last read)."""
    from contactcal.infer.calibration.provenance import recording_digests

    assert ex.log is not None and ex.log.sha256 is not None  # extract_frames fed it the log
    return recording_digests(
        None if video is None else (video.path, video.sha256),
        args.camera,
        (ex.log.path, ex.log.sha256),
    )


def calibrate_video(
    args: argparse.Namespace,
    measure: MeasureOptions,
    provenance: Provenance,
    replaced: str | None = None,
) -> int:
    """Extract the steady frames, then calibrate them (see the module docstring).

    Args:
        args: the ``calibrate --video | --camera`` command line.
        measure: how the extracted frames are measured (no outlines:
            :func:`~contactcal.infer.video.args.is_video_run` refused --overlay).
        provenance: the command line and the display's id, recorded (the video's or camera's
            and the pressure log's record is added here, ``inputs.recording``, and the
            preview's U-Net, ``extra.preview_method``).
        replaced: the note on an earlier calibration in ``--out`` this run replaces (printed
            last), or None.

    The caller checked ``--out`` first
    (:func:`~contactcal.infer.video.fresh_out.check_fresh_recording`, then
    :func:`~contactcal.infer.calibration.out_folder.check_reused_out`).
    """
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.calibration.command import session_options
    from contactcal.infer.files.atomic import run_outputs, write_synced

    # FFmpeg's own log ("[mjpeg @ …] overread 8" on a truncated file) would precede the one-line
    # error; OpenCV reads this before its first FFmpeg use in the process. A user's value wins.
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", FFMPEG_QUIET)
    cfg = _step_config(args)
    method, outlines = _methods(args, measure)  # before the recording is opened
    if outlines is not None:  # the preview's U-Net, recorded as loaded
        provenance = replace(provenance, preview_method=outlines.describe())
    protect = [args.video, args.pressure_log, args.model, args.rig]
    with run_outputs(protect, options={"--out": args.out}) as outs:
        ex, video, warnings = _extract(args, cfg, outlines, outs)
        provenance = replace(provenance, recording=_recording(args, video, ex))
        final_manifest = args.out / "frames" / "manifest.csv"
        manifest = outs.stage(final_manifest)
        write_synced(manifest, ex.manifest_text())
        rep = calibrate_session(
            manifest,
            args.out,
            method,
            measure,
            replace(session_options(args), step_tolerance_kpa=0.0),  # steps found already
            provenance,
            outputs=outs,
            manifest_as=final_manifest,
        )
    _print_report(args, measure, rep, ex, warnings, replaced)
    return 0


def _step_config(args: argparse.Namespace) -> StepConfig:
    """The steady-step settings: ``--tolerance-kpa`` and ``--settle-s``, else the defaults.

    Raises:
        ValueError: either option not a number >= 0 (:class:`StepConfig`).
    """
    default = StepConfig()
    return StepConfig(
        default.tolerance_kpa if args.tolerance_kpa is None else args.tolerance_kpa,
        default.settle_s if args.settle_s is None else args.settle_s,
    )


def _extract(
    args: argparse.Namespace, cfg: StepConfig, outlines: Method | None, outs: OutputSet
) -> tuple[Extractor, VideoFile | None, list[str]]:
    """Extract the recording's steady frames into ``--out``'s ``frames/`` (staged in ``outs``),
    the preview drawn with ``outlines`` (:func:`_methods`; None: no preview) and a camera's
    progress shown as they come, then check them: every step covered
    (:func:`~contactcal.infer.video.coverage.check_coverage`), the steps left out said on
    stderr, the log's unit (:func:`~contactcal.infer.pipeline.manifest.check_sweep_top`).

    Returns:
        The extractor (its steps and manifest), the video file read (None: a camera) and the
        coverage's warning lines, for the command to print under the calibration's table.

    Raises:
        ValueError: a recording or log that cannot be calibrated, naming it.
    """
    from contactcal.infer.pipeline.manifest import check_sweep_top
    from contactcal.infer.video import coverage, extract, live

    ex = extract.Extractor(cfg, args.out / "frames", outs.stage)
    frames, feed, stop, fps, video = _source(args)
    preview = _preview(args, outlines, outs, ex, fps)
    progress = live.Progress(ex) if args.camera is not None else None
    observers = [o for o in (preview, progress) if o is not None]
    try:
        extract.extract_frames(frames, ex, feed, lambda d: [o(d) for o in observers], stop)
    finally:
        for o in observers:
            o.close()
    warnings = coverage.check_coverage(ex, args.video if args.video is not None else None)
    for step in ex.left_out():
        print(
            f"note: step {step.label()} left out: a one-pressure unloading pass is no "
            "curve (its frames stay in frames/, outside the manifest)",
            file=sys.stderr,
        )
    # the log's unit, named as the log (the manifest written from the steps is this run's own)
    check_sweep_top(args.pressure_log, max((s.pressure_kpa for s in ex.used_steps()), default=0.0))
    return ex, video, warnings


def _print_report(
    args: argparse.Namespace,
    measure: MeasureOptions,
    rep: CalibrationReport,
    ex: Extractor,
    warnings: list[str],
    replaced: str | None,
) -> None:
    """Print the run's table, the note of a run without a pixel scale, the extraction's summary,
    ``warnings`` (under the table, where they are read with the curve) and ``replaced`` (the
    note on an earlier calibration replaced; None: none), after the outputs were moved into
    place (:func:`~contactcal.infer.files.stdout.printing_after`)."""
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.args import NO_SCALE_NOTE, VIDEO_SCALE

    with printing_after([args.out], [replaced]):
        print(rep.table)
        if measure.scale is None:
            print(NO_SCALE_NOTE.format(looked=VIDEO_SCALE))
        print(ex.summary())
        for line in warnings:  # under the table, where they are read with the curve
            print(line)
        if replaced is not None:
            print(replaced)

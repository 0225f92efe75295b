"""``contactcal calibrate --video VIDEO | --camera INDEX --pressure-log LOG.csv --out DIR``.

The frames taken in steady pressure steps are written to ``DIR/frames/`` with a manifest
(:mod:`.extract`), then the session is calibrated exactly as ``contactcal calibrate MANIFEST``
(:func:`~contactcal.infer.calibration.calibrate.calibrate_session`). Frames, manifest,
calibration and preview are one run's outputs: all written, or none; the video and the log are
inputs, never replaced.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from contactcal.infer.video.steps import StepConfig

if TYPE_CHECKING:
    import numpy as np

    from contactcal.infer.calibration.provenance import Provenance
    from contactcal.infer.files.atomic import OutputSet
    from contactcal.infer.pipeline.options import MeasureOptions
    from contactcal.infer.video.extract import Extractor
    from contactcal.infer.video.live import Preview
    from contactcal.infer.video.log import PressureLog

#: Preview frame rate when the camera states none, frames/s.
DEFAULT_CAMERA_FPS = 30.0


def add_video_args(p: argparse.ArgumentParser) -> None:
    """The ``calibrate`` options of video and camera input."""
    g = p.add_argument_group("video or camera input (instead of MANIFEST.csv)")
    source = g.add_mutually_exclusive_group()
    source.add_argument("--video", type=Path, help="video of the session (e.g. .avi, .mp4)")
    source.add_argument("--camera", type=int, metavar="INDEX", help="live camera (0: the first)")
    g.add_argument(
        "--pressure-log",
        type=Path,
        metavar="LOG.csv",
        help="the controller's log: time_s (s since the first frame),pressure_kpa",
    )
    cfg = StepConfig()
    g.add_argument(
        "--settle-s",
        type=float,
        default=cfg.settle_s,
        help="s the pressure must hold before frames are kept (default %(default)s)",
    )
    g.add_argument(
        "--tolerance-kpa",
        type=float,
        default=cfg.tolerance_kpa,
        help="± kPa a steady step stays within (default %(default)s: a tenth of 1 kPa steps, "
        "twice a regulator's noise)",
    )
    g.add_argument(
        "--duration-s",
        type=float,
        help="--camera: stop after this many s (default: when the log is back at 0 kPa)",
    )
    g.add_argument("--preview", action="store_true", help="--video: also write DIR/preview.mp4")
    g.add_argument("--show", action="store_true", help="show the preview in a window")


def is_video_run(args: argparse.Namespace) -> bool:
    """Whether ``calibrate`` reads a video or camera; checks the options' combination.

    Raises:
        ValueError: a missing or conflicting option (one line saying which).
    """
    live = args.video is not None or args.camera is not None
    if not live:
        given = {
            "--pressure-log": args.pressure_log,
            "--show": args.show,
            "--preview": args.preview,
            "--duration-s": args.duration_s,
        }
        extra = [o for o, v in given.items() if v not in (None, False)]
        if args.manifest is None or extra:
            raise ValueError(
                "calibrate: expected MANIFEST.csv, or --video VIDEO / --camera INDEX with "
                f"--pressure-log LOG.csv{f' (got {extra[0]} without them)' if extra else ''}"
            )
        return False
    if args.manifest is not None:
        raise ValueError("calibrate: give MANIFEST.csv or --video/--camera, not both")
    if args.pressure_log is None:
        raise ValueError("calibrate: --video/--camera need --pressure-log LOG.csv")
    if args.overlay is not None:
        raise ValueError("calibrate: --overlay is for MANIFEST.csv; with a video use --preview")
    if args.duration_s is not None and (args.camera is None or not args.duration_s > 0):
        raise ValueError("calibrate: --duration-s is for --camera and must be > 0")
    if args.show and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        raise ValueError("calibrate: --show needs a display (DISPLAY is unset); drop --show")
    return True


def _preview(
    args: argparse.Namespace,
    measure: MeasureOptions,
    outs: OutputSet,
    extractor: Extractor,
    fps: float,
) -> Preview | None:
    from contactcal.infer.video.live import Preview, preview_format

    if not (args.show or args.preview or args.camera is not None):
        return None
    method = measure.method("unet", outline=True)
    if args.show:
        return Preview(method, extractor, None, "", fps)
    suffix, fourcc = preview_format()
    return Preview(method, extractor, outs.stage(args.out / f"preview{suffix}"), fourcc, fps)


def _source(
    args: argparse.Namespace,
) -> tuple[
    Iterator[tuple[float, np.ndarray]],
    Callable[[], PressureLog | None],
    Callable[[Extractor, float], bool],
    float,
]:
    """``(frames, feed, stop, fps)`` of the recording (``--video`` with its whole pressure
    log) or the camera (``--camera``, the log polled as it grows; stops back at 0 kPa or at
    ``--duration-s``), for :func:`~contactcal.infer.video.extract.extract_frames`."""
    import cv2

    from contactcal.infer.video import extract, live
    from contactcal.infer.video.log import read_pressure_log

    if args.video is not None:
        logs = iter([read_pressure_log(args.pressure_log)])
        cap, fps = extract.open_video(args.video)
        return (
            extract.video_frames(cap, fps, args.video),
            lambda: next(logs, None),
            lambda e, t: False,
            fps,
        )
    feed = live.LogPoller(args.pressure_log)
    cap = live.open_camera(args.camera)
    fps = cap.get(cv2.CAP_PROP_FPS) or DEFAULT_CAMERA_FPS
    limit = args.duration_s

    def stop(e: extract.Extractor, t: float) -> bool:
        return live.returned_to_zero(e, t) or (limit is not None and t >= limit)

    return live.capture_frames(cap), feed, stop, fps


def check_fresh_frames(frames_dir: Path) -> None:
    """Refuse a ``frames/`` folder that already holds files: an earlier recording's frames would
    stay beside this one's, outside its manifest (and its ``preview`` beside this calibration).

    Raises:
        ValueError: naming the folder and what to do.
    """
    if frames_dir.is_dir() and any(frames_dir.iterdir()):
        raise ValueError(
            f"{frames_dir}: holds the frames of an earlier recording; expected a new --out "
            "folder for each recording (or remove that folder first)"
        )


def calibrate_video(
    args: argparse.Namespace, measure: MeasureOptions, provenance: Provenance
) -> int:
    """Extract the steady frames, then calibrate them (see the module docstring).

    Args:
        args: the ``calibrate --video | --camera`` command line.
        measure: how the extracted frames are measured (no outlines: :func:`is_video_run`
            refused --overlay).
        provenance: the command line and the display's id, recorded.
    """
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.calibration.command import session_options
    from contactcal.infer.files.atomic import run_outputs, write_synced
    from contactcal.infer.video import extract, live

    cfg = StepConfig(args.tolerance_kpa, args.settle_s)
    check_fresh_frames(args.out / "frames")
    protect = [args.video, args.pressure_log, args.model, args.rig]
    with run_outputs(protect) as outs:
        ex = extract.Extractor(cfg, args.out / "frames", outs.stage)
        frames, feed, stop, fps = _source(args)
        preview = _preview(args, measure, outs, ex, fps)
        progress = live.Progress(ex) if args.camera is not None else None
        observers = [o for o in (preview, progress) if o is not None]
        try:
            extract.extract_frames(frames, ex, feed, lambda d: [o(d) for o in observers], stop)
        finally:
            for o in observers:
                o.close()
        extract.check_coverage(ex, args.video if args.video is not None else None)
        for step in ex.left_out():
            print(
                f"note: step {step.label()} left out: a one-pressure unloading pass is no "
                "curve (its frames stay in frames/, outside the manifest)",
                file=sys.stderr,
            )
        final_manifest = args.out / "frames" / "manifest.csv"
        manifest = outs.stage(final_manifest)
        write_synced(manifest, ex.manifest_text())
        rep = calibrate_session(
            manifest,
            args.out,
            args.method,
            measure,
            session_options(args),
            provenance,
            outputs=outs,
            manifest_as=final_manifest,
        )
    print(rep.table)
    print(ex.summary())
    return 0

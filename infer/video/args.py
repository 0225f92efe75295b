"""``calibrate``'s video and camera options, and the check of their combination.

Kept apart from :mod:`.command` so that building the command line (every ``contactcal`` run)
imports no video code.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from contactcal.infer.video.step_config import StepConfig


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
    g.add_argument(  # None: StepConfig's default; a manifest run refuses it (it would ignore it)
        "--settle-s",
        type=float,
        help=f"s the pressure must hold before frames are kept (default {cfg.settle_s:g})",
    )
    g.add_argument(
        "--tolerance-kpa",
        type=float,
        help=f"± kPa a steady step stays within (default {cfg.tolerance_kpa:g}: a tenth of 1 kPa "
        "steps, twice a regulator's noise)",
    )
    g.add_argument(
        "--duration-s",
        type=float,
        help="--camera: stop after this many s (default: when the log is back at rest, <= 0.5 kPa)",
    )
    g.add_argument("--preview", action="store_true", help="--video: also write DIR/preview.mp4")
    g.add_argument("--show", action="store_true", help="show the preview in a window")


def has_preview(args: argparse.Namespace) -> bool:
    """Whether the run draws a recording's preview (the U-Net outline, whatever ``--method``):
    ``--preview``, ``--show``, or ``--camera`` (always); False for a command without them."""
    shown = getattr(args, "preview", False) or getattr(args, "show", False)
    return shown or getattr(args, "camera", None) is not None


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
            "--settle-s": args.settle_s,
            "--tolerance-kpa": args.tolerance_kpa,
        }
        extra = [o for o, v in given.items() if v is not None and v is not False]  # 0.0 given
        if args.manifest is not None and extra:
            hint = (
                "; a manifest's readings are pooled with --step-tolerance-kpa"
                if extra[0] == "--tolerance-kpa"
                else ""
            )
            raise ValueError(
                f"calibrate: {extra[0]} is for --video/--camera, not for MANIFEST.csv "
                f"({args.manifest}); drop it{hint}"
            )
        if args.manifest is None or extra:
            hint = " (a manifest's readings are pooled with --step-tolerance-kpa)"
            raise ValueError(
                "calibrate: expected MANIFEST.csv, or --video VIDEO / --camera INDEX with "
                f"--pressure-log LOG.csv{f' (got {extra[0]} without them)' if extra else ''}"
                f"{hint if extra and extra[0] == '--tolerance-kpa' else ''}"
            )
        return False
    if args.manifest is not None:
        raise ValueError("calibrate: give MANIFEST.csv or --video/--camera, not both")
    if args.pressure_log is None:
        raise ValueError("calibrate: --video/--camera need --pressure-log LOG.csv")
    if args.overlay is not None:
        raise ValueError("calibrate: --overlay is for MANIFEST.csv; with a video use --preview")
    if getattr(args, "step_tolerance_kpa", None) is not None:
        raise ValueError(
            "calibrate: --step-tolerance-kpa is for MANIFEST.csv; a video run finds its steps "
            "with --tolerance-kpa"
        )
    if args.duration_s is not None and (args.camera is None or not args.duration_s > 0):
        raise ValueError("calibrate: --duration-s is for --camera and must be > 0")
    if args.show and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        raise ValueError("calibrate: --show needs a display (DISPLAY is unset); drop --show")
    return True

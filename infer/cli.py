"""``contactcal`` command line. Subcommands import their heavy dependencies lazily.

Exit codes: 0 success, 1 a run that found nothing usable (e.g. no contact in any frame),
2 bad input or usage (one-line message on stderr, nothing written).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from contactcal.infer.errors import RunError
from contactcal.infer.methods import METHODS


def _scale_args(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mm-per-px", type=float, help="pixel scale at the contact plane (mm/px)")
    g.add_argument("--rig", type=Path, help="rig config JSON with mm_per_px and image_width_px")


def _resolve_scale(args: argparse.Namespace, default_rig: Path | None = None):
    from contactcal.infer.scale import PixelScale, load_rig_config

    if args.mm_per_px is not None:
        return PixelScale(args.mm_per_px, None)
    if args.rig is not None:
        return load_rig_config(args.rig)
    if default_rig is not None and default_rig.is_file():
        return load_rig_config(default_rig)
    return None


def _cmd_measure(args: argparse.Namespace) -> int:
    from contactcal.infer.atomic import write_json
    from contactcal.infer.methods import make_method
    from contactcal.infer.session import measure_files

    method = make_method(args.method, args.model)
    measured = measure_files(args.images, method, args.reference, _resolve_scale(args))
    write_json(args.out, [m.to_json(method.name) for m in measured])
    for m in measured:
        area = (
            f"{m.area_mm2:8.1f} mm²" if m.area_mm2 is not None else f"{m.result.area_px:10.0f} px"
        )
        print(f"{m.file}  contact={'yes' if m.result.contact else 'no ':3s} area={area}")
    return 0


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from contactcal.infer.calibrate import calibrate_session

    report = calibrate_session(
        args.manifest,
        args.out,
        args.method,
        args.model,
        _resolve_scale(args, args.manifest.parent / "rig.json"),
    )
    print(report)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    from contactcal.infer import __version__

    parser = argparse.ArgumentParser(
        prog="contactcal",
        description="Contact-area calibration of pneumatic fingertip displays from rig images.",
    )
    parser.add_argument("--version", action="version", version=f"contactcal {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    m = sub.add_parser("measure", help="measure the contact area in images")
    m.add_argument("images", nargs="+", type=Path, metavar="IMAGE")
    m.add_argument("--method", choices=METHODS, default=METHODS[0])
    m.add_argument("--model", type=Path, help="ONNX model for --method unet")
    m.add_argument("--reference", type=Path, help="the session's zero-pressure frame")
    m.add_argument("--out", type=Path, required=True, help="results JSON (list, one per image)")
    _scale_args(m)
    m.set_defaults(func=_cmd_measure)

    c = sub.add_parser("calibrate", help="calibrate a session: area vs pressure and its inverse")
    c.add_argument("manifest", type=Path, metavar="MANIFEST.csv")
    c.add_argument("--method", choices=METHODS, default=METHODS[0])
    c.add_argument("--model", type=Path, help="ONNX model for --method unet")
    c.add_argument("--out", type=Path, required=True, help="output folder")
    _scale_args(c)
    c.set_defaults(func=_cmd_calibrate)

    d = sub.add_parser("demo", help="calibrate the bundled example session")
    d.add_argument("--out", type=Path, default=Path("out/demo"), help="output folder")
    d.set_defaults(func=_cmd_demo)

    # Heavy roles register their own subcommands; their modules import nothing heavy.
    from contactcal.synth.commands import add_parsers as add_synth_parsers
    from contactcal.train.commands import add_parsers as add_train_parsers

    add_synth_parsers(sub)
    add_train_parsers(sub)
    return parser


def _cmd_demo(args: argparse.Namespace) -> int:
    from contactcal.infer.calibrate import calibrate_session
    from contactcal.infer.examples import example_manifest

    manifest = example_manifest()
    from contactcal.infer.segmenter import DEFAULT_MODEL

    for method in METHODS:
        out = args.out / method
        if method == "unet" and not DEFAULT_MODEL.is_file():
            print(f"== {method}: skipped, no shipped model at {DEFAULT_MODEL}")
            continue
        scale = _resolve_scale(
            argparse.Namespace(mm_per_px=None, rig=None), manifest.parent / "rig.json"
        )
        print(f"== {method} → {out}")
        print(calibrate_session(manifest, out, method, None, scale))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``contactcal`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except RunError as exc:
        print(f"contactcal: {exc}", file=sys.stderr)
        return exc.code
    except (ValueError, OSError) as exc:
        print(f"contactcal: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

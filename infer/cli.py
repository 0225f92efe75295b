"""``contactcal`` command line. Subcommands import their heavy dependencies lazily.

Exit codes: 0 success, 1 a run that found nothing usable (e.g. no contact in any frame),
2 bad input or usage (one-line message on stderr, nothing written).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points
from pathlib import Path
from typing import TYPE_CHECKING

from contactcal.infer.errors import RunError
from contactcal.infer.methods.registry import METHODS

#: Entry-point group through which other roles add subcommands (see pyproject.toml).
COMMAND_GROUP = "contactcal.commands"

if TYPE_CHECKING:
    from contactcal.infer.pipeline.measure import Measured
    from contactcal.infer.pipeline.scale import PixelScale


def _scale_args(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mm-per-px", type=float, help="pixel scale at the contact plane (mm/px)")
    g.add_argument("--rig", type=Path, help="rig config JSON with mm_per_px and image_width_px")
    _bit_depth_arg(p)


def _bit_depth_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--bit-depth",
        type=int,
        metavar="N",
        help="significant bits of 16-bit images (e.g. 12 for a 12-bit camera's PNGs holding "
        "0-4095; 16 for full-range); default: the PNG sBIT chunk, else required when ambiguous",
    )


def _method_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", choices=METHODS, default=METHODS[0], help="default %(default)s")
    p.add_argument("--model", type=Path, help="ONNX model for --method unet (default: shipped)")
    p.add_argument("--threads", type=int, default=1, help="onnxruntime threads (default 1)")
    p.add_argument(
        "--overlay",
        type=Path,
        metavar="DIR",
        help="also write each frame with the learned and classical outlines to DIR",
    )
    p.add_argument(
        "--device-id", help="identifier of the display (1-100 printable characters), recorded"
    )


def _resolve_scale(args: argparse.Namespace, default_rig: Path | None = None) -> PixelScale | None:
    from contactcal.infer.pipeline.scale import PixelScale, load_rig_config

    if args.mm_per_px is not None:
        return PixelScale(args.mm_per_px, None)
    if args.rig is not None:
        return load_rig_config(args.rig)
    if default_rig is not None and default_rig.is_file():
        return load_rig_config(default_rig)
    return None


def _inputs(args: argparse.Namespace) -> list[Path]:
    """The files a run reads besides its images: no output may replace them."""
    names = ("reference", "model", "rig", "manifest")
    return [p for p in (getattr(args, n, None) for n in names) if p is not None]


def _overlay_runs(
    args: argparse.Namespace, primary: list[Measured], files: list[Path], reference: Path | None
) -> dict[str, list[Measured]]:
    """Measurements of every method for the overlays (the primary run is reused)."""
    from contactcal.infer.methods.registry import make_method
    from contactcal.infer.pipeline.measure import measure_files

    runs = {args.method: primary}
    for name in METHODS:
        if name not in runs:
            method = make_method(name, args.model, args.threads, outline=True)
            runs[name] = measure_files(files, method, reference, bit_depth=args.bit_depth)
    return runs


def _cmd_measure(args: argparse.Namespace) -> int:
    from contactcal.infer.calibration.record import check_device_id
    from contactcal.infer.files.atomic import run_outputs, write_synced
    from contactcal.infer.files.jsonable import json_text
    from contactcal.infer.image.read import SUPPORTED_SUFFIXES
    from contactcal.infer.methods.registry import make_method
    from contactcal.infer.pipeline.measure import measure_files
    from contactcal.infer.pipeline.overlay import write_overlays

    check_device_id(args.device_id)
    to_stdout = str(args.out) == "-"
    if args.out.suffix.lower() in SUPPORTED_SUFFIXES:
        raise ValueError(
            f"--out {args.out}: expected a JSON file name (results.json) or - for standard "
            "output, got an image name (did the shell expand a pattern right after --out?)"
        )
    with run_outputs([*args.images, *_inputs(args)]) as outs:
        json_path = None if to_stdout else outs.stage(args.out)  # refused here, before work
        method = make_method(args.method, args.model, args.threads, args.overlay is not None)
        measured = measure_files(
            args.images, method, args.reference, _resolve_scale(args), bit_depth=args.bit_depth
        )
        # device_id: the display measured, per object (the output stays a list of objects).
        rows = [{**m.to_json(method.name), "device_id": args.device_id} for m in measured]
        text = json_text(rows)
        if json_path is not None:
            write_synced(json_path, text)
        if args.overlay is not None:
            runs = _overlay_runs(args, measured, args.images, args.reference)
            write_overlays(runs, args.overlay, outputs=outs, bit_depth=args.bit_depth)
    if to_stdout:
        sys.stdout.write(text)
    for m in measured:
        mm2 = m.area_mm2
        area = f"{mm2:8.1f} mm²" if mm2 is not None else f"{m.result.area_px:10.0f} px"
        line = f"{m.file}  contact={'yes' if m.result.contact else 'no ':3s} area={area}"
        print(line, file=sys.stderr if to_stdout else sys.stdout)
    return 0


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.calibration.record import check_device_id
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.pipeline.overlay import write_overlays

    check_device_id(args.device_id)
    scale = _resolve_scale(args, args.manifest.parent / "rig.json")
    with run_outputs(_inputs(args)) as outs:
        rep = calibrate_session(
            args.manifest,
            args.out,
            args.method,
            args.model,
            scale,
            outline=args.overlay is not None,
            argv=args.argv,
            device_id=args.device_id,
            outputs=outs,
            bit_depth=args.bit_depth,
        )
        if args.overlay is not None:
            files = [f.file for f in rep.frames]
            runs = _overlay_runs(args, rep.measured, files, files[0])
            titles = [f"{f.pressure_kpa:g} kPa" for f in rep.frames]
            write_overlays(runs, args.overlay, titles, outputs=outs, bit_depth=args.bit_depth)
    print(rep.table)
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from contactcal.infer.pipeline.demo import run_demo

    print(run_demo(args.out, args.manifest))
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from contactcal.infer.bench.config import BenchConfig
    from contactcal.infer.bench.run import run_bench

    if args.repeats < 1 or args.timing_frames < 1:
        raise ValueError("--repeats and --timing-frames must be >= 1")
    cfg = BenchConfig(repeats=args.repeats, timing_frames=args.timing_frames)
    res = run_bench(args.data, args.out, None if args.model is None else str(args.model), cfg)
    for row in res["bins"]:
        err = row["median_abs_rel_error"]
        shown = "–" if err is None else f"{100 * err:6.2f} %"
        print(f"{row['method']:>16s} {row['bin_kpa']:>6s} kPa  median |rel err| {shown}")
    print(f"report: {args.out / 'report.md'}")
    return 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from contactcal.infer.evaluate.run import evaluate_session

    rep = evaluate_session(
        args.manifest, args.labels, args.out, args.method, args.model, args.bit_depth
    )
    print(rep.table)
    print(f"evaluation: {rep.files['json']}, {rep.files['png']}")
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
    _method_args(m)
    m.add_argument("--reference", type=Path, help="the session's zero-pressure frame")
    m.add_argument(
        "--out", type=Path, required=True, help="results JSON (list, one per image); - for stdout"
    )
    _scale_args(m)
    m.set_defaults(func=_cmd_measure)

    c = sub.add_parser("calibrate", help="calibrate a session: area vs pressure and its inverse")
    c.add_argument("manifest", type=Path, metavar="MANIFEST.csv")
    _method_args(c)
    c.add_argument("--out", type=Path, required=True, help="output folder")
    _scale_args(c)
    c.set_defaults(func=_cmd_calibrate)

    d = sub.add_parser("demo", help="calibrate the bundled example session with both methods")
    d.add_argument("--out", type=Path, default=Path("out/demo"), help="output folder")
    d.add_argument("--manifest", type=Path, help="another session instead of the example")
    d.set_defaults(func=_cmd_demo)

    b = sub.add_parser("bench", help="accuracy and speed of every method on rendered sessions")
    b.add_argument("--data", type=Path, required=True, help="dataset folder (index.csv)")
    b.add_argument("--out", type=Path, required=True, help="report folder")
    b.add_argument("--model", type=Path, help="ONNX model (default: shipped)")
    b.add_argument("--repeats", type=int, default=5, help="timing runs; median (default 5)")
    b.add_argument("--timing-frames", type=int, default=6, help="frames per timing run")
    b.set_defaults(func=_cmd_bench)

    e = sub.add_parser("evaluate", help="score the methods on your own hand-labelled frames")
    e.add_argument("manifest", type=Path, metavar="MANIFEST.csv")
    e.add_argument(
        "--labels",
        type=Path,
        required=True,
        help="folder of <frame stem>.png masks, or an ImageJ ellipse CSV "
        "(file,cx,cy,major,minor,angle_deg; see docs/evaluate.md)",
    )
    e.add_argument("--out", type=Path, required=True, help="output folder")
    e.add_argument(
        "--method", choices=(*METHODS, "both"), default=METHODS[0], help="default %(default)s"
    )
    e.add_argument("--model", type=Path, help="ONNX model for the U-Net (default: shipped)")
    _bit_depth_arg(e)
    e.set_defaults(func=_cmd_evaluate)

    add_plugin_commands(sub)
    return parser


def add_plugin_commands(sub: argparse._SubParsersAction) -> None:
    """Subcommands registered by other roles (``synth``, ``train``) as entry points.

    Each entry point of the group :data:`COMMAND_GROUP` is a function taking the subparsers
    object; the core names no role, so it imports none.
    """
    for ep in sorted(entry_points(group=COMMAND_GROUP), key=lambda e: e.name):
        ep.load()(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``contactcal`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # recorded in calibration.json
    if getattr(args, "threads", 1) < 1:
        parser.error("--threads must be >= 1")
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

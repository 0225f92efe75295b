"""``contactcal synth`` subcommand (arguments only; Mitsuba is imported when it runs)."""

from __future__ import annotations

import argparse
from pathlib import Path

from contactcal.infer.errors import require_extra
from contactcal.infer.parser import folder_arg
from contactcal.infer.pipeline.args import check_cpu_count, check_out_folder


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``synth`` to the ``contactcal`` subcommands."""
    s = sub.add_parser("synth", help="render a synthetic dataset of calibration sessions")
    s.add_argument("--fingers", type=int, required=True, help="sessions in the whole set")
    s.add_argument("--pressures", default="0:20:1", help="kPa, start:stop:step or a,b,c")
    s.add_argument(
        "--size",
        default="320x240",
        help="frame size W[xH], 4:3, at most 2592x1944 (default 320x240)",
    )
    s.add_argument("--spp", type=int, default=8, help="samples per pixel (default 8)")
    s.add_argument("--seed", type=int, default=0, help="dataset seed (default 0)")
    s.add_argument("--hard-fraction", type=float, default=0.25, help="share of hard sessions")
    s.add_argument(
        "--smooth-fraction",
        type=float,
        default=0.0,
        help="share of the hard sessions with a smooth coating (sharp ring before contact)",
    )
    s.add_argument(
        "--speck-fraction",
        type=float,
        default=0.0,
        help="share of the sessions with a bright dust speck near the centre of the window",
    )
    s.add_argument(
        "--departure-fraction",
        type=float,
        default=0.0,
        help="share of the sessions whose membrane leaves the contact edge at a drawn slope "
        "(the inner ring then closes on the contact edge, or leaves it; docs/synth.md)",
    )
    s.add_argument("--out", type=folder_arg, required=True, help="dataset folder")
    s.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    s.add_argument("--shard", default="0/1", help="render only shard i of n (i/n)")
    s.add_argument("--variant", default="auto", choices=("auto", "llvm_ad_rgb", "scalar_rgb"))
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=_cmd_synth)
    add_fidelity_parser(sub)


#: The files ``fidelity`` writes into its ``--out`` folder.
FIDELITY_FILES = ("fidelity.json", "fidelity.md", "fidelity_strip.jpg")
STRIP_MAX_WIDTH_PX = 2400  # fidelity_strip.jpg is downscaled to at most this width

#: Modules of the ``synth`` extra that rendering needs (checked before anything is written).
SYNTH_MODULES = ("mitsuba", "drjit")


def _cmd_synth(args: argparse.Namespace) -> int:
    require_extra("synth", "synth", SYNTH_MODULES)
    from contactcal.infer.files.stdout import printing_after
    from contactcal.synth.dataset import DatasetConfig, build_dataset, parse_shard
    from contactcal.synth.layout import parse_pressures, parse_size
    from contactcal.synth.session import RenderConfig

    check_cpu_count("--workers", args.workers)
    width, height = parse_size(args.size)
    config = DatasetConfig(
        fingers=args.fingers,
        pressures_kpa=parse_pressures(args.pressures),
        seed=args.seed,
        hard_fraction=args.hard_fraction,
        smooth_fraction=args.smooth_fraction,
        speck_fraction=args.speck_fraction,
        departure_fraction=args.departure_fraction,
        render=RenderConfig(width=width, height=height, spp=args.spp, variant=args.variant),
    )
    shard = parse_shard(args.shard)
    check_out_folder(args.out, "synth", ("config.json",))  # e.g. a file above it: named
    stats = build_dataset(
        args.out, config, args.workers, shard, progress=not args.quiet, run_args=_args(args)
    )
    made, fingers = stats["frames_rendered"], stats["fingers"]
    with printing_after([args.out]):
        print(f"synth: {made} frame(s) rendered, {fingers} finger(s) → {args.out}")
        if not stats["run_record_written"]:
            record = f"run_shard{shard[0]}of{shard[1]}.json"
            print(
                f"synth: every frame was there; {record} kept (the record of the run that rendered)"
            )
    return 0


def _args(args: argparse.Namespace) -> dict[str, object]:
    return {k: str(v) if isinstance(v, Path) else v for k, v in vars(args).items() if k != "func"}


def add_fidelity_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``fidelity`` (nominal renders against the rig paper) to the subcommands."""
    s = sub.add_parser(
        "fidelity", help="render nominal sessions and measure them against the rig paper"
    )
    s.add_argument("--sessions", type=int, default=12, help="nominal sessions (default 12)")
    s.add_argument("--seed", type=int, default=9000, help="dataset seed (default 9000)")
    s.add_argument(
        "--size",
        default="400x300",
        help="frame size W[xH], 4:3, at most 2592x1944 (default 400x300)",
    )
    s.add_argument("--spp", type=int, default=8, help="samples per pixel (default 8)")
    s.add_argument("--pressures", default="0,1,2,3,4,5,7.5,10,12.5,15,17.5,20", help="kPa")
    s.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    s.add_argument(
        "--out", type=folder_arg, required=True, help="folder for fidelity.json/.md/.jpg"
    )
    s.set_defaults(func=_cmd_fidelity)


def _cmd_fidelity(args: argparse.Namespace) -> int:
    require_extra("synth", "fidelity", SYNTH_MODULES)
    import cv2
    import numpy as np

    from contactcal.infer.files.atomic import run_outputs, write_json, write_text
    from contactcal.infer.files.replaced import replaced_note
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.image.write import write_image
    from contactcal.synth.fidelity_report import (
        PAPER_BINS,
        FidelityConfig,
        run_fidelity,
        summarise,
        summary_markdown,
    )
    from contactcal.synth.layout import parse_pressures, parse_size
    from contactcal.synth.session import RenderConfig

    if args.sessions < 1:
        raise ValueError(f"--sessions must be >= 1, got {args.sessions}")
    check_cpu_count("--workers", args.workers)
    check_out_folder(args.out, "fidelity", FIDELITY_FILES)  # before the renders, not after
    json_name, md_name, jpg_name = FIDELITY_FILES
    width, height = parse_size(args.size)
    pressures = tuple(parse_pressures(args.pressures))
    if max(pressures) > PAPER_BINS[-1][1]:
        raise ValueError(
            f"--pressures {args.pressures}: up to {max(pressures):g} kPa; fidelity compares with "
            f"the rig paper's bins, which end at {PAPER_BINS[-1][1]:g} kPa (a frame above would "
            "be in no bin): give pressures from 0 to 20 kPa"
        )
    replaced = replaced_note(args.out, FIDELITY_FILES, "fidelity report")
    config = FidelityConfig(
        sessions=args.sessions,
        pressures_kpa=pressures,
        seed=args.seed,
        render=RenderConfig(width=width, height=height, spp=args.spp),
        workers=args.workers,
    )
    results = run_fidelity(config)
    summary = summarise([r for r, _ in results]) | {"args": _args(args)}
    with run_outputs(options={"--out": args.out}) as out:
        write_json(out.stage(args.out / json_name), summary)
        write_text(out.stage(args.out / md_name), summary_markdown(summary))
        strip = np.ascontiguousarray(results[0][1][:, :, ::-1])  # RGB → BGR
        if strip.shape[1] > STRIP_MAX_WIDTH_PX:  # a figure for docs, not data: keep it small
            f = STRIP_MAX_WIDTH_PX / strip.shape[1]
            strip = cv2.resize(strip, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
        jpeg = (cv2.IMWRITE_JPEG_QUALITY, 85)
        write_image(out.stage(args.out / jpg_name), strip, jpeg)
    with printing_after([args.out], [replaced]):
        print(summary_markdown(summary), end="")
        ok = f"{summary['roi_ok']}/{args.sessions}"
        print(f"fidelity: ROI found within tolerance in {ok} sessions")
        if replaced is not None:
            print(replaced)
    return 0

"""``contactcal procedural`` subcommand: a procedural cross-check set (never for training)."""

from __future__ import annotations

import argparse

from contactcal.infer.parser import folder_arg


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``procedural`` to the ``contactcal`` subcommands."""
    s = sub.add_parser(
        "procedural",
        help="draw a procedural cross-check dataset (no renderer; for `bench --crosscheck`)",
    )
    s.add_argument("--fingers", type=int, required=True, help="sessions in the set")
    s.add_argument("--pressures", default="0:20:1", help="kPa, start:stop:step or a,b,c")
    s.add_argument(
        "--size",
        default="400x300",
        help="frame size W[xH], 4:3, at most 2592x1944 (default 400x300)",
    )
    s.add_argument("--seed", type=int, default=7000, help="dataset seed (default 7000)")
    s.add_argument("--hard-fraction", type=float, default=0.25, help="share of hard sessions")
    s.add_argument("--out", type=folder_arg, required=True, help="dataset folder (must not exist)")
    s.set_defaults(func=_cmd_procedural)


def _cmd_procedural(args: argparse.Namespace) -> int:
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.args import check_out_folder
    from contactcal.synth.layout import parse_pressures, parse_size
    from contactcal.synth.procedural.config import GeneratorConfig
    from contactcal.synth.procedural.dataset import build_dataset

    check_out_folder(args.out, "procedural", ("index.csv",))  # e.g. a file above it: named
    width, height = parse_size(args.size)
    config = GeneratorConfig(
        fingers=args.fingers,
        pressures_kpa=tuple(sorted(parse_pressures(args.pressures))),
        seed=args.seed,
        width=width,
        height=height,
        hard_fraction=args.hard_fraction,
    )
    stats = build_dataset(args.out, config)
    with printing_after([args.out]):
        print(
            f"procedural: {stats['frames']} frames, {stats['fingers']} fingers in "
            f"{stats['seconds']:.1f} s ({stats['frames_per_s']:.1f} frames/s) → {args.out}"
        )
    return 0

"""The ``evaluate`` subcommand."""

from __future__ import annotations

import argparse
from pathlib import Path

from contactcal.infer.files.regular import read_input_json
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.parser import folder_arg
from contactcal.infer.pipeline.args import (
    change_gate_arg,
    check_change_gate,
    check_out_folder,
    measure_options,
    read_rig,
    scale_args,
)


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``evaluate`` to the ``contactcal`` subcommands."""
    e = sub.add_parser("evaluate", help="score the methods on your own hand-labelled frames")
    e.add_argument("manifest", type=Path, metavar="MANIFEST.csv")
    e.add_argument(
        "--labels",
        type=folder_arg,
        required=True,
        help="folder of <frame stem>.png masks, or an ImageJ ellipse CSV "
        "(file,cx,cy,major,minor,angle_deg; see docs/evaluate.md)",
    )
    e.add_argument("--out", type=folder_arg, required=True, help="output folder")
    e.add_argument(
        "--method", choices=(*METHODS, "both"), default=METHODS[0], help="default %(default)s"
    )
    e.add_argument("--model", type=Path, help="ONNX model for the U-Net (default: shipped)")
    change_gate_arg(e)
    scale_args(e)
    e.set_defaults(func=_cmd_evaluate)
    b = sub.add_parser(
        "boundary-offset",
        help="pool the U-Net's boundary offset over several sessions' evaluations",
    )
    b.add_argument(
        "evaluations",
        nargs="+",
        type=folder_arg,
        metavar="EVAL_DIR",
        help="`contactcal evaluate` output folders (or their evaluation.json), one per session",
    )
    b.set_defaults(func=_cmd_boundary_offset)


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from contactcal.infer.evaluate.run import (
        EVALUATION_FILES,
        evaluate_session,
        evaluated_session,
    )
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.manifest import beside_manifest, reference_width
    from contactcal.infer.pipeline.rig_note import rig_note

    check_change_gate(args)
    check_out_folder(args.out, "evaluate", EVALUATION_FILES)  # before the work
    default_rig = beside_manifest(args.manifest)
    rig = read_rig(args, default_rig)  # read once; the file protected from --out
    measure = measure_options(args, rig)
    session = evaluated_session(args.manifest)  # read once, passed on
    set_aside = rig_note(
        args, measure, default_rig, rig, lambda: reference_width(session, args.bit_depth)
    )
    replaced = earlier_evaluation_note(args.out, args.manifest)
    with run_outputs(options={"--out": args.out}) as outs:
        rep = evaluate_session(
            args.manifest,
            args.labels,
            args.out,
            args.method,
            measure,
            outputs=outs,
            also_read=[rig.path] if rig else [],
            session=session,
        )
    with printing_after([args.out], [set_aside, replaced]):
        print(rep.table)
        print(f"evaluation: {rep.files['json']}, {rep.files['png']}")
        for note in (set_aside, replaced):
            if note is not None:
                print(note)
    return 0


def earlier_evaluation_note(out: Path, manifest: Path) -> str | None:
    """A line naming the evaluation ``out`` holds before a run replaces it (None: none), so
    that a typo in ``--out`` (one session's folder for another's) does not lose an evaluation
    of the boundary-offset pool without a word.

    Args:
        out: the run's output folder, before the run.
        manifest: the manifest this run evaluates.
    """
    from contactcal.infer.evaluate.run import EVALUATION_FILES

    held = [n for n in EVALUATION_FILES if (out / n).is_file()]
    if not held:
        return None
    try:
        record = read_input_json(out / "evaluation.json", "an earlier evaluation", ValueError)
        earlier = Path(record["manifest"])
        what = (
            "an earlier evaluation of this manifest"
            if earlier == manifest.resolve()
            else f"the evaluation of {earlier}"
        )
    except (OSError, ValueError, KeyError, TypeError):
        what = f"{' and '.join(held)}, not readable as an evaluation"
    return f"note: replaced {what} that {out} held; give each session its own --out to keep both"


def _cmd_boundary_offset(args: argparse.Namespace) -> int:
    from contactcal.infer.evaluate.pool import pool_offsets, pooled_text

    print(pooled_text(pool_offsets(args.evaluations)))
    return 0

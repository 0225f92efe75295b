"""The ``bench`` subcommand."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from contactcal.infer.parser import folder_arg

if TYPE_CHECKING:
    from contactcal.infer.bench.models import BenchModel

#: Frames the robustness suite samples when ``--robustness-frames`` is not given.
DEFAULT_ROBUSTNESS_FRAMES = 40


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``bench`` to the ``contactcal`` subcommands."""
    b = sub.add_parser("bench", help="accuracy and speed of every method on rendered sessions")
    b.add_argument("--data", type=folder_arg, required=True, help="dataset folder (index.csv)")
    b.add_argument(
        "--crosscheck",
        type=folder_arg,
        action="append",
        default=[],
        metavar="DIR",
        help="another dataset scored beside --data (e.g. `contactcal procedural`); repeatable",
    )
    b.add_argument("--out", type=folder_arg, required=True, help="report folder")
    b.add_argument("--model", type=Path, help="ONNX model (default: shipped)")
    b.add_argument(
        "--variant",
        action="append",
        default=[],
        metavar="LABEL=MODEL",
        help="a further U-Net model scored and timed beside --model as unet[LABEL] "
        "(e.g. int8=models/contact_unet_int8.onnx; LABEL of letters, digits, . _ + -, not a "
        "method name); repeatable",
    )
    b.add_argument(
        "--no-reference",
        action="store_true",
        help="measure accuracy without the sessions' zero-pressure frames",
    )
    b.add_argument("--repeats", type=int, default=5, help="timing runs; median (default 5)")
    b.add_argument("--timing-frames", type=int, default=6, help="frames per timing run")
    b.add_argument(
        "--robustness",
        action="store_true",
        help="also run the robustness suite (perturbed frames; robustness.png, "
        "robustness_no_contact.png, report section)",
    )
    b.add_argument(
        "--robustness-frames",
        type=int,
        metavar="N",
        help="frames the robustness suite samples across sessions and pressures (default 40)",
    )
    b.set_defaults(func=_cmd_bench)


def _cmd_bench(args: argparse.Namespace) -> int:
    from contactcal.infer.bench.config import BenchConfig
    from contactcal.infer.bench.dataset import check_dataset_folder
    from contactcal.infer.bench.models import load_models
    from contactcal.infer.bench.report import REPORT_FILES, ROBUSTNESS_FILES
    from contactcal.infer.bench.run import run_bench
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.files.replaced import replaced_note
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.args import check_out_folder

    if args.repeats < 1 or args.timing_frames < 1:
        raise ValueError("--repeats and --timing-frames must be >= 1")
    check_dataset_folder(args.data, "--data")
    for folder in args.crosscheck:
        check_dataset_folder(folder, "--crosscheck")
    check_out_folder(args.out, "bench", REPORT_FILES)  # before the work, not after
    _check_out_outside_data(args.out, [args.data, *args.crosscheck])
    variants = tuple(_variant(v) for v in args.variant)
    if len({label for label, _ in variants}) < len(variants):
        labels = [label for label, _ in variants]
        twice = sorted({x for x in labels if labels.count(x) > 1})
        raise ValueError(f"--variant: label(s) {', '.join(twice)} given twice; expected one each")
    models = load_models(args.model, variants)  # each file read once, for the whole run
    _check_distinct_models(models)
    cfg = BenchConfig(
        repeats=args.repeats,
        timing_frames=args.timing_frames,
        robustness_frames=_robustness_frames(args),
        use_reference=not args.no_reference,
        variants=variants,
    )
    if cfg.robustness_frames:
        from contactcal.infer.bench.accuracy import variant_name
        from contactcal.infer.bench.robustness_text import unperturbed_note

        if note := unperturbed_note([variant_name(label) for label, _ in variants]):
            print(f"note: {note}", file=sys.stderr)
    model = None if args.model is None else str(args.model)
    writes = [n for n in REPORT_FILES if args.robustness or n not in ROBUSTNESS_FILES]
    replaced = replaced_note(args.out, writes, "report")
    with run_outputs(options={"--out": args.out}) as outs:
        res = run_bench(args.data, args.out, model, cfg, args.crosscheck, outs, models)
    with printing_after([args.out], [replaced]):
        _print_summary(res, args.out)
        if replaced is not None:
            print(replaced)
    return 0


def _check_out_outside_data(out: Path, datasets: list[Path]) -> None:
    """Refuse a report folder that is a dataset folder or inside one: the report's files would
    mix with the frames (and be read as a dataset's files by a later run)."""
    where = out.resolve()
    for data in datasets:
        folder = data.resolve()
        if where == folder or folder in where.parents:
            raise ValueError(
                f"--out {out}: inside the dataset folder {data}; give the report a folder of "
                "its own (e.g. out/bench)"
            )


def _print_summary(res: dict[str, Any], out: Path) -> None:
    """The error bins, the robustness line and where the report is, on standard output."""
    from contactcal.infer.bench.report import ROBUSTNESS_FILES

    for row in res["bins"]:
        print(f"{row['method']:>16s} {row['bin_kpa']:>6s} kPa  median |rel err| {_pct(row)}")
    for c in res.get("crosscheck", []):
        for row in c["bins"]:
            method, kpa = row["method"], row["bin_kpa"]
            print(f"[{c['label']}] {method:>16s} {kpa:>6s} kPa  median |rel err| {_pct(row)}")
    if "robustness" in res:
        print(_robustness_line(res["robustness"], out / "robustness.png"))
    else:
        earlier = [n for n in ROBUSTNESS_FILES if (out / n).exists()]
        if earlier:
            print(
                f"note: {', '.join(earlier)} in {out} are an earlier run's (this one ran "
                "without --robustness; report.md has no robustness section)"
            )
    print(f"report: {out / 'report.md'}")


#: A variant's label: it becomes ``unet[label]`` in Markdown tables, CSV cells and plot labels.
_LABEL = re.compile(r"[A-Za-z0-9._+-]{1,40}")


def _variant(text: str) -> tuple[str, str]:
    """``LABEL=MODEL`` → ``(label, path)``: a label of the allowed characters, not a method's
    name (its rows would read ``unet[unet]``); the file is checked by
    :func:`~contactcal.infer.bench.models.load_models`."""
    from contactcal.infer.methods.registry import METHODS

    label, sep, path = text.partition("=")
    if not sep or not label or not path:
        raise ValueError(f"--variant {text!r}: expected LABEL=MODEL.onnx, e.g. int8=m_int8.onnx")
    if not _LABEL.fullmatch(label):
        raise ValueError(
            f"--variant {text!r}: label {label!r} may hold letters, digits and . _ + - only (it "
            "names the report's table rows and plot labels, where | or a space breaks them)"
        )
    if label.lower() in METHODS:
        raise ValueError(
            f"--variant {text}: label {label!r} is a method's name (its rows would read "
            f"unet[{label}]); expected a label naming the variant, e.g. int8={path}"
        )
    return label, path


def _check_distinct_models(models: list[BenchModel]) -> None:
    """Refuse a ``--variant`` whose file holds the content of ``--model`` (the shipped model
    without it) or of an earlier variant: its rows would repeat that model's under another
    label (a mistyped INT8 path would read as an INT8 model that loses nothing). ``models``:
    as :func:`~contactcal.infer.bench.models.load_models` read them (their sha256)."""
    seen: dict[str, str] = {}  # sha256 → the model first seen with it
    for m in models:
        if m.sha256 in seen:
            raise ValueError(
                f"{m.given}: the same model as {seen[m.sha256]} (identical content); expected "
                "another model, e.g. the INT8 one `contactcal quantize` wrote"
            )
        seen[m.sha256] = m.given


def _robustness_frames(args: argparse.Namespace) -> int:
    """Frames of the robustness suite: 0 without ``--robustness``."""
    n = args.robustness_frames
    if n is not None and not args.robustness:
        raise ValueError("--robustness-frames needs --robustness")
    if n is not None and n < 1:
        raise ValueError(f"--robustness-frames must be >= 1, got {n}")
    return (DEFAULT_ROBUSTNESS_FRAMES if n is None else n) if args.robustness else 0


def _robustness_line(rob: dict[str, Any], figure: Path) -> str:
    """The CLI's one line on the robustness suite: frames sampled, and how many score each row."""
    first, n = rob["rows"][0], len(rob["frames"])
    scored = first["contact_frames_ge5"]
    errors = (
        f"{scored} with true contact at >= 5 kPa score the error rows"
        if scored
        else "none with true contact at >= 5 kPa, so no error rows (sample more frames)"
    )
    return (
        f"robustness: {n} frame{'s' if n != 1 else ''} sampled, {errors}, "
        f"{first['no_contact_frames']} without contact score no-contact accuracy; {figure}"
    )


def _pct(row: dict[str, object]) -> str:
    err = row["median_abs_rel_error"]
    return "–" if not isinstance(err, float) else f"{100 * err:6.2f} %"

"""``contactcal train``, ``contactcal export`` and ``contactcal quantize`` subcommands.

This module imports neither torch nor onnx: the handlers import them when they run, so the
deployment CLI stays fast and works without the ``train`` extra installed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from contactcal.infer.errors import option_error, require_extra
from contactcal.infer.parser import folder_arg
from contactcal.train.train_args import (
    add_look_args,
    add_reference_args,
    add_ridge_args,
    build_config,
)

#: ONNX opsets ``export`` accepts: tested at both ends (``tests/test_export.py``); at opset 10 the
#: export failed its parity check. Within the range the export's own checks still decide.
OPSETS = range(13, 21)


def add_parsers(sub: Any) -> None:
    """Add ``train``, ``export`` and ``quantize`` to the CLI's subparsers object.

    Args:
        sub: what ``ArgumentParser.add_subparsers()`` returned.
    """
    _add_train_parser(sub)
    _add_export_parser(sub)
    _add_quantize_parser(sub)


def _add_train_parser(sub: Any) -> None:
    """``contactcal train``: the U-Net contact segmenter trained on synthetic datasets."""
    t = sub.add_parser(
        "train",
        help="train the contact segmenter on synthetic datasets",
        description="Train the U-Net contact segmenter. Options left out take the defaults "
        "(or, with --resume, the run's saved settings).",
    )
    _add_run_args(t)
    _add_input_args(t)
    add_reference_args(t)
    add_ridge_args(t)
    add_look_args(t)
    _add_optimiser_args(t)
    _add_model_args(t)
    t.add_argument("--quiet", action="store_true", help="no progress bars")
    t.set_defaults(func=_cmd_train)


def _add_run_args(t: argparse.ArgumentParser) -> None:
    """``train``'s datasets, run folder, epochs, device and ``--resume``."""
    t.add_argument(
        "--data", nargs="+", type=folder_arg, required=True, metavar="DIR", help="dataset folder(s)"
    )
    t.add_argument(
        "--out",
        type=folder_arg,
        required=True,
        metavar="RUN_DIR",
        help="run folder: new or empty, or with --resume an unfinished run's (holding last.pt)",
    )
    t.add_argument("--epochs", type=int, help="number of epochs (default 40)")
    t.add_argument("--device", choices=("cpu", "cuda", "auto"), help="default auto")
    t.add_argument("--resume", action="store_true", help="continue from RUN_DIR/last.pt")


def _add_input_args(t: argparse.ArgumentParser) -> None:
    """``train``'s network input: its side and the normalisation's floor."""
    t.add_argument(
        "--input-size", type=int, metavar="S", help="network input side, px (default 256)"
    )
    t.add_argument(
        "--norm-floor",
        type=float,
        metavar="F",
        help="percentile of the crop subtracted before the normalisation, as deployment will "
        "(u = (g - F)/(P - F): invariant to black level and contrast; default 0: none)",
    )


def _add_optimiser_args(t: argparse.ArgumentParser) -> None:
    """``train``'s optimisation: seed, batch size, weight average and torch's CPU threads."""
    t.add_argument("--seed", type=int, help="split/init/shuffle/augmentation seed (default 0)")
    t.add_argument("--batch-size", type=int, metavar="B", help="frames per step (default 16)")
    t.add_argument(
        "--ema",
        dest="ema_decay",
        type=float,
        metavar="DECAY",
        help="validate and save an exponential average of the weights, DECAY per step in (0, 1) "
        "(0.995 spans ~200 steps; default, or 0: off)",
    )
    # dest differs from the deployment commands' --threads (onnxruntime's and OpenCV's threads,
    # an int >= 1 checked by contactcal.infer.cli.main); here 0 or absent means torch's default.
    t.add_argument(
        "--threads",
        dest="torch_threads",
        type=int,
        metavar="T",
        help="torch CPU threads (default: torch's)",
    )


def _add_model_args(t: argparse.ArgumentParser) -> None:
    """``train``'s U-Net size: channels at the first level and resolution levels."""
    t.add_argument("--base", type=int, help="U-Net channels at the first level (default 8)")
    t.add_argument("--levels", type=int, help="U-Net resolution levels (default 3)")


def _add_export_parser(sub: Any) -> None:
    """``contactcal export``: a trained run's model as ONNX."""
    e = sub.add_parser("export", help="export a trained run to ONNX")
    e.add_argument("run_dir", type=folder_arg, metavar="RUN_DIR", help="run folder with best.pt")
    e.add_argument("--out", type=Path, required=True, metavar="MODEL.onnx", help="output model")
    e.add_argument(
        "--opset",
        type=int,
        default=17,
        help=f"ONNX opset, {OPSETS[0]}-{OPSETS[-1]} (default 17; the export checks itself at any)",
    )
    e.add_argument(
        "--tune-min-area",
        action="store_true",
        help="choose the no-contact minimum area on the run's validation fingers",
    )
    e.set_defaults(func=_cmd_export)


def _add_quantize_parser(sub: Any) -> None:
    """``contactcal quantize``: the INT8 variant of an exported model."""
    q = sub.add_parser("quantize", help="write the INT8 variant of an exported model")
    q.add_argument("model", type=Path, metavar="MODEL.onnx", help="float model (contactcal export)")
    q.add_argument("--out", type=Path, required=True, metavar="INT8.onnx", help="output model")
    q.add_argument(
        "--data",
        nargs="+",
        type=folder_arg,
        required=True,
        metavar="DIR",
        help="calibration datasets (validation renders; never the benchmark or cross-check sets)",
    )
    q.add_argument(
        "--frames",
        type=int,
        default=64,
        help="calibration frames (default 64); as many others check the INT8 model",
    )
    q.set_defaults(func=_cmd_quantize)


#: Modules of the ``train`` extra that training and export need (checked before anything runs).
TRAIN_MODULES = ("torch", "kornia", "onnx")


def _check_dirs(dirs: list[Path], out: Path | None = None) -> None:
    """Cheap path checks before torch is imported (clear message, exit 2 in the CLI): dataset
    folders, no procedural cross-check set (:func:`check_render_folders`); ``out``
    (a run folder) must neither be nor lie inside nor hold a dataset folder: its config.json
    and checkpoints would land among (or replace) the data's."""
    from contactcal.train.render_sets import check_render_folders

    check_render_folders(dirs)
    for d in dirs:
        if out is not None and (
            out.resolve().is_relative_to(d.resolve()) or d.resolve().is_relative_to(out.resolve())
        ):
            raise ValueError(
                f"--out {out}: the run folder overlaps the dataset folder {d} (it would write its "
                "config.json and checkpoints among the data); expected another --out, e.g. "
                "runs/r1"
            )


def _cmd_train(args: argparse.Namespace) -> int:
    require_extra("train", "train", TRAIN_MODULES)
    _check_dirs(list(args.data), args.out)
    from contactcal.train.run_folder import check_run_folder

    try:  # before torch is imported; train() checks it again
        check_run_folder(args.out, args.resume)
    except ValueError as exc:
        raise option_error("--out", args.out, exc) from None
    from contactcal.infer.files.stdout import printing_after
    from contactcal.train.loop import train

    summary = train(
        args.data, args.out, build_config(args), resume=args.resume, progress=not args.quiet
    )
    if summary.get("finished"):  # nothing written: a failed stdout says only that
        written = []
        line = (
            f"{summary['out_dir']}: the run is finished (best epoch {summary['best_epoch']}; it "
            "holds val_bins.csv, written after its last epoch): nothing to --resume, its files "
            "left as they are"
        )
    else:
        written, iou = [args.out], summary["val"].get("val_iou")
        line = (
            f"{summary['out_dir']}: best epoch {summary['best_epoch']}, "
            f"val IoU {'-' if iou is None else f'{iou:.3f}'}, {summary['parameters']} parameters"
        )
    with printing_after(written):
        print(line)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    require_extra("export", "train", TRAIN_MODULES)
    if args.opset not in OPSETS:
        raise ValueError(f"--opset must be {OPSETS[0]}-{OPSETS[-1]}, got {args.opset}")
    from contactcal.train.restate import check_model_out, earlier_model_note

    check_model_out(args.out, [args.run_dir / "best.pt", args.run_dir / "config.json"])
    replaced = earlier_model_note(args.out)
    from contactcal.infer.errors import RunError
    from contactcal.infer.files.stdout import printing_after
    from contactcal.train.export import export_onnx
    from contactcal.train.export_check import ExportCheckError
    from contactcal.train.run_folder import ran_to_end

    min_area = None
    if args.tune_min_area:
        from contactcal.train.threshold import tune_min_area

        min_area, summary = tune_min_area(args.run_dir)
        print(f"minimum contact area tuned on the validation fingers: {summary}")
    try:
        path = export_onnx(args.run_dir, args.out, opset=args.opset, min_contact_area_px=min_area)
    except ExportCheckError as exc:  # the export's own checks (checker, parity, decisions, ...)
        raise RunError(f"export: {' '.join(str(exc).split())}; nothing was written") from exc
    warning = None if ran_to_end(args.run_dir) else _unfinished_warning(args.run_dir, path)
    with printing_after([path], [warning, replaced]):
        print(f"wrote {path}")
        if replaced is not None:
            print(replaced)
    if warning is not None:
        print(warning, file=sys.stderr)
    return 0


def _unfinished_warning(run_dir: Path, model: Path) -> str:
    """The warning of an export from a run without ``val_bins.csv`` (written after its last
    epoch): stopped, or still training, its ``best.pt`` is the best epoch so far."""
    return (
        f"warning: {run_dir}: an unfinished run (no val_bins.csv, written after its last epoch: "
        f"it was stopped, or is still training); {model} is its best.pt so far (best_epoch in "
        "its metadata): --resume the run to its last epoch and export again for the run's model"
    )


def _cmd_quantize(args: argparse.Namespace) -> int:
    require_extra("quantize", "train", ("onnx",))
    _check_dirs(list(args.data))
    if args.frames < 1:
        raise ValueError(f"--frames must be >= 1, got {args.frames}")
    from contactcal.train.restate import check_model_out, earlier_model_note

    check_model_out(args.out, [args.model])
    replaced = earlier_model_note(args.out)
    from contactcal.infer.files.stdout import printing_after
    from contactcal.train.quantize import quantize_model

    check = quantize_model(args.model, args.out, args.data, args.frames)
    ratio = check["median_area_ratio"]
    ratio_text = "no frame where both see contact" if ratio is None else f"{ratio:.4f}"
    with printing_after([args.out], [replaced]):
        print(
            f"wrote {args.out}: calibrated on {check['frames']:.0f} frames; on "
            f"{check['check_frames']:.0f} others the INT8 model makes the float model's contact "
            f"decision in {100 * check['contact_agreement']:.1f} %, median area ratio {ratio_text}"
        )
        if replaced is not None:
            print(replaced)
    return 0

"""The options of ``contactcal train`` that shape its config, and the ``TrainConfig`` they build
(:func:`build_config`): defaults, or the resumed run's saved config, with the given options.

Like :mod:`contactcal.train.commands`, it imports neither torch nor onnx at import time.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

from contactcal.infer.pipeline.args import check_cpu_count


def build_config(args: argparse.Namespace) -> Any:
    """The TrainConfig for ``args``: defaults (or the saved run's with --resume) + given options.

    Raises:
        ValueError: unreadable saved config or invalid option values.
    """
    import dataclasses

    from contactcal.train.config import TrainConfig, saved_train_config
    from contactcal.train.run_folder import read_run_info

    base = TrainConfig()
    saved = args.out / "config.json"
    # lexists, not is_file: a folder, a pipe or a link to nothing there is refused
    # (read_run_info), not taken for a run stopped before its config.json was written
    if args.resume and os.path.lexists(saved):
        base = saved_train_config(read_run_info(args.out).get("train"), str(saved))
    given = {
        "epochs": args.epochs,
        "device": args.device,
        "input_size": args.input_size,
        "use_reference": args.reference,
        "reference_dropout": args.reference_dropout,
        "ridge_work_px": args.ridge_work_px,
        "seed": args.seed,
        "batch_size": args.batch_size,
        "ema_decay": args.ema_decay,
        "num_threads": args.torch_threads,
    }
    if args.torch_threads is not None:
        check_cpu_count("--threads", args.torch_threads, lowest=0)
    cfg = dataclasses.replace(base, **{k: v for k, v in given.items() if v is not None})
    gain = None if args.contact_gain is None else tuple(args.contact_gain)
    cfg = _with_augment(cfg, "ridgeless", p=args.ridgeless, flatten=args.ridgeless_flatten)
    cfg = _with_augment(cfg, "contact", gain=gain)
    camera = {"ridge_blur": args.ridge_blur, "gamma": args.gamma, "blur_sigma": args.blur_sigma}
    camera["blur_kernel_px"] = args.blur_kernel
    if args.blur_p is not None and not 0.0 <= args.blur_p <= 1.0:
        raise ValueError(f"--blur-p {args.blur_p:g}: expected a probability in [0, 1]")
    camera["blur_p"] = args.blur_p
    camera = {k: tuple(v) if isinstance(v, list) else v for k, v in camera.items() if v is not None}
    if camera:
        cfg = dataclasses.replace(cfg, augment=dataclasses.replace(cfg.augment, **camera))
    if args.norm_floor is not None:
        try:
            pre = dataclasses.replace(cfg.preprocess, norm_floor_percentile=args.norm_floor)
        except ValueError as exc:
            raise ValueError(f"--norm-floor {args.norm_floor:g}: {exc}") from None
        cfg = dataclasses.replace(cfg, preprocess=pre)
    arch = {"base": args.base, "levels": args.levels}
    arch = {k: v for k, v in arch.items() if v is not None}
    return dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, **arch)) if arch else cfg


def _with_augment(cfg: Any, part: str, **fields: Any) -> Any:
    """``cfg`` with the given (not None) fields of its ``augment.<part>`` config replaced."""
    import dataclasses

    given = {k: v for k, v in fields.items() if v is not None}
    if not given:
        return cfg
    sub = dataclasses.replace(getattr(cfg.augment, part), **given)
    return dataclasses.replace(cfg, augment=dataclasses.replace(cfg.augment, **{part: sub}))


def add_ridge_args(t: argparse.ArgumentParser) -> None:
    """``--ridge-channel``, ``--ridgeless`` and ``--ridgeless-flatten``."""
    t.add_argument(
        "--ridge-channel",
        dest="ridge_work_px",
        type=int,
        metavar="W",
        help="add the ridge-energy channel, measured on the crop resampled to W px "
        "(>= the input size; default off)",
    )
    t.add_argument(
        "--ridgeless",
        type=float,
        metavar="P",
        help="share of contact frames with visible ridges whose ridges are erased and which are "
        "labelled no contact (needs --ridge-channel; default 0)",
    )
    t.add_argument(
        "--ridgeless-flatten",
        type=float,
        metavar="F",
        help="share of the erased patches whose brightness also becomes the membrane's, leaving "
        "only the ring around them (default 0)",
    )


def add_look_args(t: argparse.ArgumentParser) -> None:
    """``--contact-gain``, ``--ridge-blur``, ``--gamma``, ``--blur-sigma``, ``--blur-p`` and
    ``--blur-kernel``."""
    ranges = (
        ("--gamma", "range of the gamma (tone curve) augmentation (default 0.7 1.4)"),
        (
            "--blur-sigma",
            "range of the blur augmentation's sigma, px at the network input (default 0.1 1.2; "
            "σ 12 px of a 2592-px frame is ~1.3 there)",
        ),
        (
            "--contact-gain",
            "range of the contact region's brightness factor in the contact appearance "
            "augmentation, log-uniform (default 0.6 1.5; below ~0.5 the skin is darker than the "
            "membrane)",
        ),
    )
    for flag, text in ranges:
        t.add_argument(flag, type=float, nargs=2, metavar=("LO", "HI"), help=text)
    t.add_argument(
        "--ridge-blur",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="the blur augmentation also weakens the ridge-energy channel, as blur weakens "
        "ridges (needs --ridge-channel; default off)",
    )
    t.add_argument(
        "--blur-p",
        type=float,
        metavar="P",
        help="share of training frames the blur augmentation blurs (default 0.3; of those, "
        "the share beyond the robustness suite's σ 12 px is set by --blur-sigma's range)",
    )
    t.add_argument(
        "--blur-kernel",
        type=int,
        metavar="K",
        help="taps of the blur augmentation's kernel, odd >= 3 (default, or 0: the whole "
        "Gaussian of the largest sigma; 5 reproduces models up to v2.2)",
    )


def add_reference_args(t: argparse.ArgumentParser) -> None:
    """``--reference/--no-reference`` and ``--reference-dropout``."""
    t.add_argument(
        "--reference",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="feed the session's zero-pressure frame as a 2nd channel (default on)",
    )
    t.add_argument(
        "--reference-dropout",
        type=float,
        metavar="P",
        help="share of training frames whose reference channel is blanked, so one model works "
        "with and without a reference frame (default 0)",
    )

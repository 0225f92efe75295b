"""Command-line options shared by the core subcommands, and what they resolve to."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from contactcal.infer.methods.registry import METHODS
from contactcal.infer.parser import folder_arg

if TYPE_CHECKING:
    from contactcal.infer.pipeline.boundary import BoundaryOffset
    from contactcal.infer.pipeline.options import MeasureOptions
    from contactcal.infer.pipeline.scale import PixelScale


def check_cpu_count(option: str, value: int, lowest: int = 1) -> None:
    """Refuse a thread or worker count outside ``lowest`` … this machine's CPU count.

    More threads than cores gains nothing and a slip costs the machine: ``--threads 100000``
    started that many OpenCV threads (16 GB of memory, a load of 600) before it was refused.

    Args:
        option: the option's name, for the message (e.g. ``"--threads"``).
        value: the count given.
        lowest: the smallest valid value (0 where 0 means a library's default).

    Raises:
        ValueError: ``"<option> <value>: expected <lowest>-<CPUs> (this machine has <CPUs>
            CPUs)"``.
    """
    most = os.cpu_count() or 1
    if not lowest <= value <= most:
        raise ValueError(
            f"{option} {value}: expected {lowest}-{most} (this machine has {most} CPUs)"
        )


def scale_args(p: argparse.ArgumentParser) -> None:
    """``--mm-per-px`` | ``--rig``, and ``--bit-depth``."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mm-per-px", type=float, help="pixel scale at the contact plane (mm/px)")
    g.add_argument(
        "--rig",
        type=Path,
        help="rig config JSON with mm_per_px and image_width_px (and, optionally, the rig's "
        "boundary offset for the U-Net model, as `contactcal evaluate` prints it)",
    )
    bit_depth_arg(p)


def bit_depth_arg(p: argparse.ArgumentParser) -> None:
    """``--bit-depth N``: significant bits of 16-bit frames."""
    p.add_argument(
        "--bit-depth",
        type=int,
        metavar="N",
        help="significant bits of 16-bit images (e.g. 12 for a 12-bit camera's PNGs holding "
        "0-4095; 16 for full-range; refused for 8-bit images, which are full range); default: "
        "the PNG sBIT chunk, else required when ambiguous",
    )


def check_bit_depth(bit_depth: int | None) -> None:
    """Refuse a ``--bit-depth`` outside 1 to the deepest sample read.

    Raises:
        ValueError: ``"--bit-depth N: expected 1-16 significant bits per sample ..."``.
    """
    from contactcal.infer.image.bit_depth import MAX_BIT_DEPTH

    if bit_depth is not None and not 1 <= bit_depth <= MAX_BIT_DEPTH:
        raise ValueError(
            f"--bit-depth {bit_depth}: expected 1-{MAX_BIT_DEPTH} significant bits per "
            f"sample (e.g. 12 for a 12-bit camera's PNGs, {MAX_BIT_DEPTH} for full range)"
        )


def method_args(p: argparse.ArgumentParser) -> None:
    """``--method``, ``--model``, ``--no-change-gate``, ``--threads``, ``--overlay``,
    ``--device-id``."""
    p.add_argument("--method", choices=METHODS, default=METHODS[0], help="default %(default)s")
    p.add_argument("--model", type=Path, help="ONNX model for --method unet (default: shipped)")
    change_gate_arg(p)
    p.add_argument(
        "--threads",
        type=int,
        default=1,
        help="CPU threads of onnxruntime and OpenCV (default 1: a calibration runs beside other "
        "work, and the speeds in the model card are on one thread)",
    )
    p.add_argument(
        "--overlay",
        type=folder_arg,
        metavar="DIR",
        help="also write each frame with the learned and classical outlines to DIR",
    )
    p.add_argument(
        "--device-id", help="identifier of the display (1-100 printable characters), recorded"
    )


def change_gate_arg(p: argparse.ArgumentParser) -> None:
    """``--no-change-gate``: the U-Net model's change gate off (recorded)."""
    p.add_argument(
        "--no-change-gate",
        action="store_true",
        help="the U-Net (and its overlay outlines): call a region contact even when it has "
        "not changed since the reference frame (the model's min_change gate is off; "
        "recorded). For a rig whose contacts look almost like its 0 kPa frame, i.e. whose "
        "frames' notes say 'unchanged from the reference frame' without it",
    )


def check_change_gate(args: argparse.Namespace) -> None:
    """Refuse the U-Net's options where no U-Net would run (they would be silently ignored).

    Raises:
        ValueError: ``--no-change-gate`` or ``--model`` with ``--method classical`` and no
            U-Net outline drawn: no ``--overlay``, and no preview of a recording (``--preview``,
            ``--show``; ``--camera`` always writes one); the message says what would run it.
    """
    from contactcal.infer.video.args import has_preview

    outlines = getattr(args, "overlay", None) is not None or has_preview(args)
    runs_unet = args.method in ("unet", "both") or outlines
    unet_only = (("--no-change-gate", args.no_change_gate), ("--model", args.model))
    given = [option for option, value in unet_only if value]
    if given and not runs_unet:
        raise ValueError(
            f"{given[0]} applies to the U-Net only, and --method {args.method} runs none; "
            f"drop it, {_unet_runs(args)}"
        )


def _unet_runs(args: argparse.Namespace) -> str:
    """How ``args``' command would run the U-Net: ``evaluate``'s ``--method both``, a
    manifest's or images' ``--overlay`` (it draws the U-Net's outline too), else ``--method
    unet`` or a video's ``--preview`` (a video run has no ``--overlay``; a ``--camera`` run always
    writes a preview, so it never gets here)."""
    if not hasattr(args, "overlay"):  # evaluate
        return "or use --method unet or --method both"
    if getattr(args, "video", None) is not None:  # a recording's preview draws it
        return "use --method unet, or add --preview (it draws the U-Net's outline)"
    return "use --method unet, or add --overlay DIR (it draws the U-Net's outline too)"


class RigConfig(NamedTuple):
    """The rig config a run reads (:func:`read_rig`), read once and passed on."""

    #: The file: ``--rig``, else the ``rig.json`` beside the manifest.
    path: Path
    #: Its JSON object (:func:`~contactcal.infer.pipeline.scale.read_rig_json`).
    data: dict[str, Any]


def read_rig(args: argparse.Namespace, default_rig: Path | None = None) -> RigConfig | None:
    """The rig config a run reads, read once: ``--rig``, else the ``rig.json`` at
    ``default_rig`` if it exists; None: none.

    Raises:
        RigConfigError: that file missing, unreadable or not a rig config's JSON object.
    """
    from contactcal.infer.pipeline.scale import read_rig_json

    path = args.rig
    if path is None and default_rig is not None and default_rig.is_file():
        path = default_rig
    return None if path is None else RigConfig(path, read_rig_json(path))


def resolve_rig(
    args: argparse.Namespace, rig: RigConfig | None
) -> tuple[PixelScale | None, BoundaryOffset | None]:
    """The pixel scale and the boundary offset of a run: the scale from ``--mm-per-px``, else
    from the rig config ``rig`` (:func:`read_rig`); the offset from the rig config, also with
    ``--mm-per-px`` (the offset is in mm, so another source of the scale does not change it, and
    dropping it silently would). None: not given."""
    from contactcal.infer.pipeline.boundary import rig_boundary
    from contactcal.infer.pipeline.scale import PixelScale, rig_scale

    boundary = None if rig is None else rig_boundary(rig.data, str(rig.path))
    if args.mm_per_px is not None:
        try:
            return PixelScale(args.mm_per_px, None), boundary
        except ValueError as exc:
            raise ValueError(f"--mm-per-px {args.mm_per_px:g}: {exc}") from None
    return (None if rig is None else rig_scale(rig.data, rig.path)), boundary


#: The line a run without a pixel scale prints (its areas, curve and inverse are in px);
#: ``{looked}``: where a scale was looked for (:data:`MANIFEST_SCALE`, :data:`VIDEO_SCALE`).
NO_SCALE_NOTE = (
    "note: no pixel scale ({looked}): areas are in px; a controller must look px up in this "
    'curve (load_curve(..., area_unit="px"))'
)
#: Where a manifest run looks for a scale.
MANIFEST_SCALE = "no rig.json beside the manifest, no --mm-per-px or --rig"
#: Where a video or camera run looks for one (its manifest is written by the run).
VIDEO_SCALE = "no --mm-per-px or --rig; a video or camera run reads no rig.json"


def check_out_folder(out: Path, command: str, files: tuple[str, ...] = ()) -> None:
    """Refuse ``--out -`` for a command whose outputs are a folder of files, and, before the
    work, an ``out`` that could not receive them or any of ``files`` in it that could not be
    written (:func:`check_output_folder`).

    Raises:
        ValueError: ``out`` is ``-`` (standard output: ``measure``'s JSON only), or an output
            that must not be written (``--out OUT: ...``).
    """
    if str(out) == "-":
        raise ValueError(
            f"--out -: {command} writes a folder of files, not one stream; give a folder "
            "(standard output is for `contactcal measure --out -` only)"
        )
    check_output_folder("--out", out, files)


def check_output_folder(option: str, folder: Path | None, files: tuple[str, ...] = ()) -> None:
    """Refuse, before the work, an output folder option whose folder could not receive outputs
    (it, or the nearest existing folder above it, is a file or a link) or any of ``files`` in it
    that could not be written (a link, a folder, a device: ``check_destination``), rather than
    after measuring every frame.

    Args:
        option: the option, for the message (``"--out"``, ``"--overlay"``).
        folder: its value (None: not given, nothing to check).
        files: names of the outputs the run writes into ``folder`` (may hold a subfolder).

    Raises:
        ValueError: ``OPTION FOLDER: ...``, naming the path refused and why.
    """
    from contactcal.infer.files.destination import (
        OutputError,
        by_option,
        check_destination,
        check_receiving_folder,
    )

    if folder is None:
        return
    try:
        check_receiving_folder(folder / "output")  # the folder itself receives the outputs
        for name in files:
            check_destination(folder / name)
    except OutputError as exc:
        raise by_option(folder, exc, {option: folder}) from None


def measure_options(args: argparse.Namespace, rig: RigConfig | None) -> MeasureOptions:
    """The run's :class:`~contactcal.infer.pipeline.options.MeasureOptions` from its command
    line: ``--model``, the scale and boundary offset (:func:`resolve_rig`; ``rig``: the rig
    config the run read, :func:`read_rig`),
    ``--bit-depth``, ``--no-change-gate``, ``--threads`` and ``--overlay`` (outlines)."""
    from contactcal.infer.pipeline.options import MeasureOptions

    check_bit_depth(args.bit_depth)
    scale, boundary = resolve_rig(args, rig)
    return MeasureOptions(
        model=args.model,
        scale=scale,
        boundary=boundary,
        bit_depth=args.bit_depth,
        change_gate=not args.no_change_gate,
        threads=getattr(args, "threads", 1),
        outline=getattr(args, "overlay", None) is not None,
    )


def run_inputs(args: argparse.Namespace) -> list[Path]:
    """The files a run reads besides its images: no output may replace them."""
    names = ("reference", "model", "rig", "manifest")
    return [p for p in (getattr(args, n, None) for n in names) if p is not None]

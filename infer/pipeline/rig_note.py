"""The note a run prints when ``--rig`` or ``--mm-per-px`` sets aside the ``rig.json`` beside
its manifest (:func:`~contactcal.infer.pipeline.args.resolve_rig` reads the option and says
nothing): ``--rig`` leaves that file unread, ``--mm-per-px`` replaces its scale (that file is
the rig config the run read, passed on, not read again)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from contactcal.infer.pipeline.args import RigConfig
    from contactcal.infer.pipeline.boundary import BoundaryOffset
    from contactcal.infer.pipeline.options import MeasureOptions
    from contactcal.infer.pipeline.scale import PixelScale


def rig_note(
    args: argparse.Namespace,
    options: MeasureOptions,
    beside: Path,
    read: RigConfig | None,
    width_px: Callable[[], int],
) -> str | None:
    """The note on a ``rig.json`` beside the manifest that ``--rig`` or ``--mm-per-px`` set aside:
    ``--rig`` leaves it unread, ``--mm-per-px`` replaces its scale (its boundary offset still
    applies).

    Args:
        args: the command line (``rig``, ``mm_per_px``).
        options: the run's resolved scale and boundary offset
            (:func:`~contactcal.infer.pipeline.args.measure_options`).
        beside: the ``rig.json`` beside the manifest; one not valid is said, not refused.
        read: the rig config the run read (:func:`~contactcal.infer.pipeline.args.read_rig`):
            with ``--mm-per-px``, ``beside`` as read (None: there was none).
        width_px: the frames' width, px; called only to compare ``--mm-per-px`` with its scale.

    Returns:
        One ``note:`` line naming both sources and what each states; None without either
        option or that file, with ``--rig`` naming that file, or where it states the same: the
        same scale at the frames' width (at any width, for two rig configs) and boundary offset.
    """
    from contactcal.infer.pipeline.boundary import rig_boundary
    from contactcal.infer.pipeline.scale import read_rig_json, rig_scale

    rig, mm = args.rig, args.mm_per_px
    if rig is None and (mm is None or read is None):
        return None
    if rig is not None and (not beside.is_file() or rig.resolve() == beside.resolve()):
        return None
    try:  # --mm-per-px: beside is the rig config the run read, passed on; --rig: not read yet
        data = read.data if rig is None else read_rig_json(beside)
        scale = rig_scale(data, beside) if data.keys() & {"mm_per_px", "image_width_px"} else None
        offset, valid = rig_boundary(data, str(beside)), True
    except ValueError:  # a rig config error: the file is set aside, so it is not refused
        scale, offset, valid = None, None, False
    if rig is not None:
        # equal at every width: the same mm per px of a 1 px wide image (the field's width)
        fields = [None if s is None else f"{s.at_width(1):.9g}" for s in (options.scale, scale)]
        keys = [None if b is None else (b.mm, b.model_sha256) for b in (options.boundary, offset)]
        if valid and fields[0] == fields[1] and keys[0] == keys[1]:
            return None
        with_offset = keys[0] != keys[1]
        said = _rig_said(scale, offset, with_offset) if valid else "not a valid rig config"
        used = _rig_said(options.scale, options.boundary, with_offset)
        unread = f"{beside} beside the manifest ({said}) was not read"
        return f"note: --rig {rig} used ({used}); {unread}"
    if valid and (scale is None or math.isclose(mm, scale.at_width(width_px()), rel_tol=1e-9)):
        return None  # no scale replaced (it states only an offset), or the same one
    said = _rig_said(scale, None, False) if valid else "not a valid scale"
    kept = "" if options.boundary is None else "; its boundary offset still applies"
    return f"note: --mm-per-px {mm:g} used in place of the scale of {beside} ({said}){kept}"


def _rig_said(scale: PixelScale | None, offset: BoundaryOffset | None, with_offset: bool) -> str:
    """What a rig config states, for :func:`rig_note`: ``0.05 mm/px at 400 px wide``, and, with
    ``with_offset``, ``, boundary offset +0.170 mm`` (or ``none``)."""
    said = "no scale" if scale is None else f"{scale.mm_per_px:g} mm/px"
    if scale is not None and scale.image_width_px is not None:
        said += f" at {scale.image_width_px} px wide"
    if with_offset:
        said += ", boundary offset " + ("none" if offset is None else f"{offset.mm:+.3f} mm")
    return said

"""A frame's hand label rasterised at the frame's size: a mask PNG read (of the frame's size),
or an ellipse drawn (its centre inside the frame, not running past its edge, covering a pixel
centre); the labels themselves: :mod:`~contactcal.infer.evaluate.labels`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contactcal.infer.evaluate.ellipse import ImageJEllipse, rasterise
from contactcal.infer.evaluate.errors import LabelError
from contactcal.infer.evaluate.labels import Label
from contactcal.infer.evaluate.mask_read import read_mask


@dataclass(frozen=True)
class LabelMask:
    """A label rasterised at its frame's size."""

    mask: np.ndarray  # (H, W) bool, True = contact
    area_px: int  # pixel count of ``mask`` (the area errors are computed against)
    analytic_area_px: float | None  # π·major·minor/4 for an ellipse, else None
    note: str | None = None  # how the label was read, when not as drawn (a soft-edged mask)


def label_mask(label: Label, frame_size: tuple[int, int]) -> LabelMask:
    """Rasterise ``label`` at its frame's ``(width, height)`` in px.

    Raises:
        LabelError: a mask of another size than the frame (naming both files), an ellipse
            whose centre lies outside the frame, or one covering no pixel centre.
    """
    w, h = frame_size
    if label.row is None:
        mask, note = read_mask(label.source)
        if mask.shape != (h, w):
            raise LabelError(
                f"{label.source}: mask is {mask.shape[1]}×{mask.shape[0]} px but its frame "
                f"{label.frame} is {w}×{h} px; expected a mask of the frame's size"
            )
        return LabelMask(mask, int(mask.sum()), None, note)
    e = label.ellipse
    if e is None:
        return LabelMask(np.zeros((h, w), dtype=bool), 0, None)
    if not (0 <= e.cx <= w and 0 <= e.cy <= h):
        raise LabelError(
            f"{label.where()}: centre ({e.cx:g}, {e.cy:g}) lies outside the {w}×{h} px frame "
            f"{label.frame.name}; expected pixels (in ImageJ: Analyze › Set Scale › remove scale)"
        )
    _check_inside(label, e, (w, h))
    mask = rasterise(e.to_opencv(), (h, w))
    if not mask.any():
        raise LabelError(
            f"{label.where()}: the ellipse covers no pixel centre; expected axes of >= 1 px"
        )
    return LabelMask(mask, int(mask.sum()), e.analytic_area_px)


#: px an ellipse may run past the frame's edge (its outline's rounding) before it is refused.
EDGE_SLACK_PX = 1.0


def _check_inside(label: Label, e: ImageJEllipse, frame_size: tuple[int, int]) -> None:
    """Refuse an ellipse running past the frame's edge: its clipped raster would be scored
    against an area the label does not state (a unit or a column mistake)."""
    w, h = frame_size
    a, b, t = e.major / 2.0, e.minor / 2.0, math.radians(e.angle_deg)
    hx = math.hypot(a * math.cos(t), b * math.sin(t))  # half extents of the bounding box
    hy = math.hypot(a * math.sin(t), b * math.cos(t))
    past = max(hx - e.cx, e.cx + hx - w, hy - e.cy, e.cy + hy - h)
    if past > EDGE_SLACK_PX:
        raise LabelError(
            f"{label.where()}: the ellipse runs {past:.0f} px past the edge of the {w}×{h} px "
            f"frame {label.frame.name}; expected a contact label inside the frame (axes in "
            "pixels, full lengths)"
        )

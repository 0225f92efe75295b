"""The largest contact a label can state on this rig: the area inside the window ring.

The skin touches the window inside the rig's bright outer ring, so a label whose contact covers
the whole frame, or more pixels than the disc of that ring, cannot be a contact label (an
inverted mask, a mask of another frame or an ellipse in the wrong unit): it is refused naming
its file, not scored; so is a label lying mostly outside that ring (an ellipse in mm, its centre
near the frame's corner). The ring is the one the U-Net centres its crop on
(:func:`~contactcal.infer.methods.unet.ring.locate_ring`), found on the session's reference
frame; where none is found only the whole-frame check applies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from contactcal.infer.evaluate.label_raster import LabelMask
from contactcal.infer.evaluate.labels import Label, LabelError
from contactcal.infer.image.read import ImageFile
from contactcal.infer.methods.unet.ring import locate_ring
from contactcal.infer.pipeline.frame_check import RING_RADIUS_TOLERANCE


@dataclass(frozen=True)
class Window:
    """The reference frame's window ring, as a bound on a label's contact area."""

    reference: Path  # the frame the ring was found on
    radius_px: float  # px of the frame, the ring's outer edge
    cx: float = math.nan  # px, the ring's centre (x right)
    cy: float = math.nan  # px (y down)

    @property
    def max_area_px(self) -> float:
        """px², the disc of the ring's outer edge, its radius grown by the tolerance a frame's
        ring may differ from the reference's (``RING_RADIUS_TOLERANCE``)."""
        return math.pi * (self.radius_px * (1.0 + RING_RADIUS_TOLERANCE)) ** 2


def find_window(reference: ImageFile, bit_depth: int | None = None) -> Window | None:
    """The window ring of ``reference`` (None when no ring is found).

    Args:
        reference: the session's reference frame (the manifest's lowest-pressure frame), as
            read for its measurement.
        bit_depth: significant bits of a 16-bit frame (None: from the file), as measured.

    Raises:
        ImageError: an undecodable frame (``measure`` refuses it as well).
    """
    ring = locate_ring(reference.decode(bit_depth=bit_depth))
    return Window(reference.path, ring.radius, ring.cx, ring.cy) if ring.found else None


def check_label_area(
    label: Label, mask: LabelMask, frame_size: tuple[int, int], window: Window | None
) -> None:
    """Refuse a label whose contact is larger than any contact on this rig can be.

    Args:
        label: the label (for its file or CSV row).
        mask: its rasterised mask.
        frame_size: its frame's ``(width, height)``, px.
        window: the reference frame's ring (None: no check here; the frame bounds a label,
            :mod:`~contactcal.infer.evaluate.label_raster`).

    Raises:
        LabelError: the label covers more than the window ring's area, or lies mostly
            outside it (naming the label's file and the reference frame).
    """
    w, h = frame_size  # a label of the whole frame never gets here: a mask needs a pixel 0,
    # an ellipse must lie inside the frame (labels.py)
    if window is not None and mask.area_px > window.max_area_px:
        raise LabelError(
            f"{label.where()}: labels {mask.area_px} px of its frame {label.frame.name} as "
            f"contact ({mask.area_px / (w * h):.0%} of the frame), more than the "
            f"{window.max_area_px:.0f} px inside the window ring (radius {window.radius_px:.0f} "
            f"px found on the reference {window.reference.name}, "
            f"+{RING_RADIUS_TOLERANCE:.0%} tolerance); "
            "expected the contact patch only (an inverted mask?)"
        )
    if window is not None and mask.area_px > 0 and _inside_share(mask.mask, window) < 0.5:
        ys, xs = np.nonzero(mask.mask)
        raise LabelError(
            f"{label.where()}: its contact (centred at {xs.mean():.0f}, {ys.mean():.0f} px) "
            f"lies mostly outside the window ring (centre {window.cx:.0f}, {window.cy:.0f} px, "
            f"radius {window.radius_px:.0f} px, found on the reference {window.reference.name}); "
            "expected a label in pixels of the frame (ImageJ: remove the scale, "
            "docs/evaluate.md)"
        )


def _inside_share(mask: np.ndarray, window: Window) -> float:
    """The share of the ``(H, W) bool`` mask's pixels inside the window ring (with the ring's
    tolerance); 1.0 without a ring centre."""
    if not (math.isfinite(window.cx) and math.isfinite(window.cy)):
        return 1.0
    ys, xs = np.nonzero(mask)
    reach = window.radius_px * (1.0 + RING_RADIUS_TOLERANCE)
    return float(np.mean(np.hypot(xs - window.cx, ys - window.cy) <= reach))

"""The check that every frame of a session matches its reference frame: same size, and a window
ring in the same place at the same radius (one camera set-up), cheap enough for every frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.image.gray import ImageError
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.ring import RingFit, locate_ring

#: A frame's ring centre may lie this far from the reference's, as a fraction of the reference
#: ring's radius. Frames of one session agree within 0.5 % (example session, also under noise,
#: blur and 0.3-2.5× exposure); a bumped rig or another crop moves it further.
RING_CENTRE_TOLERANCE = 0.05
#: A frame's ring radius may differ from the reference's by this fraction. The fit on a frame in
#: contact is ~3 % larger than on the 0 kPa reference (the inflated membrane's glow joins the
#: ring's outline), so 5 % would leave too little margin; another zoom or scale differs more.
RING_RADIUS_TOLERANCE = 0.10
#: Longest side (px) the ring check works at (an integer-factor area reduction of the decoded
#: frame). Its cost per 2592×1944 frame, ~1.7 ms fully decoded (the classical path, ~40 ms a
#: frame) and ~0.25 ms at the U-Net's 1/8 decode (~15 ms a frame), is small enough to check
#: every frame rather than a sample; the fit is still within 0.3 % of the radius.
RING_CHECK_PX = 160


@dataclass(frozen=True)
class FrameReference:
    """What every frame of a session is checked against."""

    path: Path
    size: tuple[int, int]  # (width, height) of the file, px
    ring: RingFit  # at the check's working size (found=False: position not checked)
    image: np.ndarray  # the method's decode of it at 1/k: measured as is where it is a frame
    sha256: str | None  # of the content read once, that the method decoded (None: not asked)


def file_size(img: np.ndarray, k: int) -> tuple[int, int]:
    """``(width, height)`` of the file decoded at 1/k into ``img``: exactly k times its size,
    since a method chooses k > 1 only when every file's sides divide by k (:meth:`Method.start`,
    which read every file's header to choose it)."""
    return img.shape[1] * k, img.shape[0] * k


def coarse_ring(img: np.ndarray) -> RingFit:
    """The ring of ``img`` reduced by an integer factor to <= :data:`RING_CHECK_PX` (cheap)."""
    f = math.ceil(max(img.shape) / RING_CHECK_PX)
    if f > 1:
        img = cv2.resize(img, None, fx=1.0 / f, fy=1.0 / f, interpolation=cv2.INTER_AREA)
    return locate_ring(img, PreprocessConfig(ring_work_px=max(img.shape)))


def check_frame(ref: FrameReference, path: Path, img: np.ndarray, size: tuple[int, int]) -> str:
    """Raise unless the frame matches the reference (size and ring; a reference without a ring
    while the frame has one is a dark reference); return a note when unchecked, else ""."""
    what = ""
    if size != ref.size:
        what = f"{size[0]}×{size[1]} px, the reference {ref.size[0]}×{ref.size[1]} px"
    elif not ref.ring.found:
        if coarse_ring(img).found:  # the rig was lit, its reference frame was not
            raise ImageError(
                f"{ref.path}: the reference frame shows no window ring while {path.name} does "
                "(a dark reference: lights off, lens cap?); expected the session's 0 kPa frame "
                "of the lit rig, framed as its other frames"
            )
        return f"ring position not checked: no ring found in the reference {ref.path.name}"
    else:
        ring = coarse_ring(img)
        if not ring.found:
            return "ring position not checked: no ring found in this frame"
        moved = math.hypot(ring.cx - ref.ring.cx, ring.cy - ref.ring.cy) / ref.ring.radius
        grown = abs(ring.radius / ref.ring.radius - 1.0)
        if moved > RING_CENTRE_TOLERANCE:
            what = (
                f"its ring centre is {moved:.0%} of the ring radius away from the reference's "
                f"(tolerance {RING_CENTRE_TOLERANCE:.0%})"
            )
        elif grown > RING_RADIUS_TOLERANCE:
            what = (
                f"its ring radius differs from the reference's by {grown:.0%} "
                f"(tolerance {RING_RADIUS_TOLERANCE:.0%})"
            )
    if what:
        raise ImageError(
            f"{path}: does not match the reference frame {ref.path}: {what}; a session's "
            "frames and its reference must come from one camera set-up, same size and framing"
        )
    return ""

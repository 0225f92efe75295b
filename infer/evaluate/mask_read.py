"""A hand-label mask PNG read as contact: 0 = background, > 0 = contact; a soft edge read at half
its largest value; a shape drawn in the alpha channel only, or no background, refused.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.evaluate.errors import LabelError
from contactcal.infer.image.decode import decode_strict
from contactcal.infer.image.read import read_file_bytes

#: The advice for a mask whose content is another format than PNG (a JPEG saved as .png).
MASK_FIX = (
    "masks must be PNG (lossless: a JPEG's compression moves the label's edge); save the mask "
    "again as PNG, with 0 = background, > 0 = contact"
)


def read_mask(path: Path) -> tuple[np.ndarray, str | None]:
    """``(H, W)`` bool: any colour channel > 0 (alpha ignored, unless it alone holds a shape);
    a mask of several non-zero values (a soft, anti-aliased or JPEG-damaged edge) is read at
    half its largest value, the edge's half coverage, and the note says so (None otherwise).

    Raises:
        LabelError: not a decodable image, or no pixel 0 (no background: an inverted mask, or a
            background of another value), which would make the whole frame contact.
    """
    buf = np.frombuffer(read_file_bytes(path, MASK_FIX), np.uint8)
    img = decode_strict(buf, cv2.IMREAD_UNCHANGED, str(path))
    if img is None or img.ndim not in (2, 3):
        raise LabelError(
            f"{path}: not a decodable PNG mask; expected 0 = background, > 0 = contact"
        )
    if img.ndim == 3:
        colour = img[..., : 3 if img.shape[2] >= 3 else 1]
        _check_alpha(path, img, colour)
        img = colour.max(axis=2)
    mask, note = img > 0, None
    levels = np.unique(img[mask]) if mask.any() else img[:0]
    if levels.size > 1 and not mask.all():
        top = levels[-1]
        mask = img > top / 2
        note = (
            f"soft edge: {levels.size} non-zero values, read as contact above half the largest "
            f"({top}); {int(np.count_nonzero(img[img > 0] < top))} px between"
        )
    if mask.all():
        values = np.unique(img)
        shown = ", ".join(str(v) for v in values[:4]) + (", …" if values.size > 4 else "")
        raise LabelError(
            f"{path}: no pixel is 0 (values {shown}), so the whole frame would be contact; "
            "expected 0 = background, > 0 = contact (an inverted mask, or a background other "
            "than 0?)"
        )
    return mask, note


def _check_alpha(path: Path, img: np.ndarray, colour: np.ndarray) -> None:
    """Refuse a mask whose contact is drawn in its alpha channel only (one colour everywhere,
    alpha not uniform): read by colour it would label every frame "no contact" (colour 0) or
    "contact everywhere" (e.g. white on transparent).

    Args:
        path: the mask file, for the message.
        img: ``(H, W, C)`` the decoded mask, ``C`` 2 (grey + alpha) or 4 (BGRA) with alpha.
        colour: ``(H, W, C')`` its colour channels.
    """
    if img.shape[2] not in (2, 4) or colour.min() != colour.max():
        return
    alpha = img[..., -1]
    if alpha.min() != alpha.max():
        raise LabelError(
            f"{path}: every colour value is {colour.flat[0]} and the shape is in the alpha "
            "channel only; "
            "expected 0 = background, > 0 = contact in the colour (grey) values (flatten the "
            "mask, or export it without transparency)"
        )

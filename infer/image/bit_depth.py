"""The bit depth of integer samples: 16-bit samples holding N-bit data → the 8-bit canonical form.

Bit depth is never guessed silently. 8-bit samples are full range (``--bit-depth`` is refused
for them, and a PNG ``sBIT`` chunk stating fewer bits is the source's depth, which PNG scales
to the full 8 bits: it changes nothing). 16-bit samples holding N-bit data (10- or 12-bit
cameras) are scaled by ``255 / (2**N - 1)``; N comes from the PNG ``sBIT`` chunk or from the
caller (``--bit-depth``). Without either, a 16-bit file is full range (255/65535) only when its
maximum exceeds :data:`LOW_BITS_MAX`; otherwise it is an error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from contactcal.infer.image.frame import LOW_BITS_MAX
from contactcal.infer.image.gray import ImageError
from contactcal.infer.image.png import png_significant_bits

#: Bits per sample of the deepest image read (16-bit PNG or TIFF); ``--bit-depth`` states
#: 1 to this many significant bits.
MAX_BIT_DEPTH = 16


def _stated_depth(p: Path, data: bytes, bit_depth: int | None) -> tuple[int | None, str]:
    """The data's bit depth and who stated it: the caller, the PNG ``sBIT`` chunk, or nobody."""
    sbit = png_significant_bits(data) if p.suffix.lower() == ".png" else None
    if sbit is not None and not 1 <= sbit <= 16:
        raise ImageError(f"{p}: invalid PNG sBIT chunk ({sbit} bits); re-export the file")
    if bit_depth is not None and sbit is not None and bit_depth != sbit:
        raise ImageError(
            f"{p}: --bit-depth {bit_depth} contradicts the file's sBIT chunk ({sbit} bits); "
            "drop the option or correct it"
        )
    if sbit is not None:
        return sbit, "the PNG sBIT chunk"
    return bit_depth, "--bit-depth"


def scale_depth(p: Path, img: np.ndarray, data: bytes, bit_depth: int | None) -> np.ndarray:
    """Integer samples holding N-bit data (:func:`_stated_depth`) → uint8; full-range samples,
    8-bit ones always, pass unchanged.

    Args:
        p: the file, for the messages.
        img: its samples as decoded, ``(H, W)`` or ``(H, W, C)``; uint8, uint16 or float.
        data: the file's content (its PNG ``sBIT`` chunk states the depth).
        bit_depth: ``--bit-depth``: significant bits of 16-bit samples; None: not given.

    Returns:
        ``img`` as uint8 when its N-bit samples were scaled, else ``img`` unchanged.

    Raises:
        ImageError: an unknown or contradictory bit depth, naming ``p``.
    """
    if img.dtype not in (np.uint8, np.uint16):
        return img  # float (intensities in [0, 1]) or a dtype to_gray_u8 reports
    bits = 8 * img.dtype.itemsize
    if bits == 8 and bit_depth is not None:
        raise ImageError(
            f"{p}: --bit-depth {bit_depth} states the depth of 16-bit files, and this file holds "
            "8-bit samples (full range); drop the option, or export every frame as 16-bit"
        )
    if bits == 8:  # full range, also under an sBIT chunk (no scan of the frame for its maximum)
        return img
    depth, source = _stated_depth(p, data, bit_depth)
    colour = img[..., :3] if img.ndim == 3 and img.shape[2] == 4 else img  # alpha is dropped
    top = int(colour.max())
    if depth is None:
        if top > LOW_BITS_MAX:
            return img
        raise ImageError(
            f"{p}: 16-bit samples with maximum {top} (<= {LOW_BITS_MAX}) and no sBIT chunk; "
            "the bit depth cannot be told: pass --bit-depth N (10 or 12 for such cameras, "
            "16 for a dark 16-bit frame)"
        )
    full = (1 << depth) - 1
    if top > full and source == "--bit-depth":
        raise ImageError(
            f"{p}: maximum {top} exceeds the {depth}-bit range 0-{full} of --bit-depth {depth}; "
            f"pass the data's true depth (--bit-depth {bits} for full-range samples)"
        )
    if depth == bits or top > full:  # PNG's convention: N-bit data scaled to the full range
        return img
    return np.rint(img.astype(np.float32) * (255.0 / full)).astype(np.uint8)

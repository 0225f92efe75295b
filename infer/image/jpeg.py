"""JPEG frame size from the file header (Pillow reads the header; the pixels are not decoded)."""

from __future__ import annotations

import os
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from contactcal.infer.image.gray import ImageError


def jpeg_size(path: str | os.PathLike[str]) -> tuple[int, int]:
    """``(height, width)`` of a JPEG file, read from its header (the pixels are not decoded).

    Raises:
        ImageError: missing or unreadable file, or not a JPEG.
    """
    p = Path(path)
    try:
        with Image.open(p) as im:
            fmt, (w, h) = im.format, im.size
    except FileNotFoundError as exc:
        raise ImageError(f"{p}: no such file") from exc
    except (OSError, UnidentifiedImageError) as exc:
        raise ImageError(f"{p}: not a readable JPEG ({exc})") from exc
    if fmt != "JPEG":
        raise ImageError(f"{p}: expected a JPEG file, got {fmt}")
    return int(h), int(w)

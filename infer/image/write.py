"""The one image writer: encode with OpenCV (format from the suffix), write atomically."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.files.atomic import atomic_path


def write_image(
    path: str | os.PathLike[str], image: np.ndarray, params: Sequence[int] = ()
) -> Path:
    """Write a PNG/JPEG atomically.

    Args:
        path: destination; the suffix chooses the format (``.png`` when there is none).
        image: ``(H, W)`` gray or ``(H, W, 3)`` BGR array, uint8 (or uint16 for PNG).
        params: OpenCV encoder parameters, e.g. ``(cv2.IMWRITE_JPEG_QUALITY, 95)``.

    Returns:
        ``path`` as a Path.

    Raises:
        OSError: encoding or writing failed; the message names the file.
    """
    path = Path(path)
    ok, buf = cv2.imencode(path.suffix or ".png", image, list(params))
    if not ok:
        raise OSError(f"{path}: could not encode image")
    with atomic_path(path) as tmp:
        tmp.write_bytes(buf.tobytes())
    return path

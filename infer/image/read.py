"""Image input: any PNG/JPEG/TIFF/BMP file or array → one canonical form.

The canonical form is a ``(H, W) uint8`` grayscale image, the form the published OpenCV routine
works on (its ROI threshold of 150 is an 8-bit grey level). Colour is converted with OpenCV's
ITU-R BT.601 luma (``cv2.cvtColor(..., COLOR_BGR2GRAY)``), alpha is dropped, 16-bit samples are
scaled by 255/65535 with rounding, float arrays are taken as ``[0, 1]`` intensities.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.image.gray import ImageError, to_gray_u8

#: File suffixes accepted by :func:`load_image` (lower case).
SUPPORTED_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


def _check_complete(path: Path, data: bytes) -> None:
    """Reject truncated PNG/JPEG files, which OpenCV may decode partially without failing."""
    suffix = path.suffix.lower()
    if suffix == ".png" and not data.rstrip(b"\x00").endswith(b"IEND\xaeB`\x82"):
        raise ImageError(f"{path}: truncated PNG (no IEND chunk at the end); re-export the file")
    if suffix in (".jpg", ".jpeg") and b"\xff\xd9" not in data[-64:]:
        raise ImageError(f"{path}: truncated JPEG (no end-of-image marker); re-export the file")


def read_file_bytes(path: str | os.PathLike[str]) -> bytes:
    """Read an image file's bytes with clear errors for missing, unreadable or empty files.

    Args:
        path: image file.

    Returns:
        The file content.

    Raises:
        ImageError: missing, not a file, unreadable, empty, unsupported suffix, or truncated.
    """
    p = Path(path)
    if p.suffix.lower() not in SUPPORTED_SUFFIXES:
        raise ImageError(
            f"{p}: unsupported image type {p.suffix!r}; expected one of "
            f"{', '.join(SUPPORTED_SUFFIXES)}"
        )
    if not p.exists():
        raise ImageError(f"{p}: no such file")
    if not p.is_file():
        raise ImageError(f"{p}: not a file")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise ImageError(f"{p}: cannot read ({exc.strerror})") from exc
    if not data:
        raise ImageError(f"{p}: empty file (0 bytes)")
    _check_complete(p, data)
    return data


def load_image(path: str | os.PathLike[str], reduce: int = 1) -> np.ndarray:
    """Load an image file into the canonical ``(H, W) uint8`` grayscale form.

    Args:
        path: PNG, JPEG, TIFF or BMP file; 8- or 16-bit; gray, RGB or RGBA.
        reduce: 1, 2, 4 or 8. For JPEG, decode at 1/reduce resolution directly (libjpeg's
            DCT scaling: several times cheaper); other formats are decoded fully and
            area-resized. The result is about ``(H/reduce, W/reduce)``.

    Returns:
        ``(H, W) uint8`` grayscale image.

    Raises:
        ImageError: the file is missing, unreadable, empty, truncated or not an image.
    """
    if reduce not in (1, 2, 4, 8):
        raise ValueError(f"reduce must be 1, 2, 4 or 8, got {reduce}")
    p = Path(path)
    data = read_file_bytes(p)
    buf = np.frombuffer(data, dtype=np.uint8)
    jpeg = p.suffix.lower() in (".jpg", ".jpeg")
    if reduce > 1 and jpeg:
        flag = {2: cv2.IMREAD_REDUCED_GRAYSCALE_2, 4: cv2.IMREAD_REDUCED_GRAYSCALE_4}.get(
            reduce, cv2.IMREAD_REDUCED_GRAYSCALE_8
        )
        img = cv2.imdecode(buf, flag)
    else:
        img = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise ImageError(f"{p}: not a decodable image (corrupt or unsupported content)")
    gray = to_gray_u8(img, name=str(p), bgr=True)
    if reduce > 1 and not jpeg:
        h, w = gray.shape
        size = (max(1, round(w / reduce)), max(1, round(h / reduce)))
        gray = cv2.resize(gray, size, interpolation=cv2.INTER_AREA)
    return gray

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

#: File suffixes accepted by :func:`load_image` (lower case).
SUPPORTED_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


class ImageError(ValueError):
    """An image file or array that cannot be used; the message names the file."""


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


def to_gray_u8(image: np.ndarray, name: str = "<array>", bgr: bool = False) -> np.ndarray:
    """Convert an array to the canonical ``(H, W) uint8`` grayscale form.

    Args:
        image: ``(H, W)``, ``(H, W, 1)``, ``(H, W, 3)`` or ``(H, W, 4)`` array of dtype uint8,
            uint16 (scaled to 8 bits), bool, or float (intensities in ``[0, 1]``, clipped;
            NaN/inf rejected).
        name: how to refer to the input in error messages (usually its file name).
        bgr: channel order is OpenCV's BGR(A) (files) rather than RGB(A) (arrays).

    Returns:
        ``(H, W) uint8`` contiguous array.

    Raises:
        ImageError: wrong shape or dtype, empty, or non-finite values.
    """
    if not isinstance(image, np.ndarray):
        raise ImageError(f"{name}: expected a numpy array, got {type(image).__name__}")
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] not in (3, 4)):
        raise ImageError(f"{name}: expected (H, W), (H, W, 3) or (H, W, 4), got {image.shape}")
    if image.shape[0] < 1 or image.shape[1] < 1:
        raise ImageError(f"{name}: empty image of shape {image.shape}")
    if image.dtype == np.bool_:
        image = image.astype(np.uint8) * 255
    elif image.dtype == np.uint16:
        image = np.rint(image.astype(np.float32) * (255.0 / 65535.0)).astype(np.uint8)
    elif np.issubdtype(image.dtype, np.floating):
        if not np.all(np.isfinite(image)):
            raise ImageError(f"{name}: float image contains NaN or inf; expected finite values")
        image = np.rint(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)
    elif image.dtype != np.uint8:
        raise ImageError(f"{name}: expected uint8, uint16, bool or float, got {image.dtype}")
    if image.ndim == 3:
        if image.shape[2] == 4:
            image = image[:, :, :3]
        code = cv2.COLOR_BGR2GRAY if bgr else cv2.COLOR_RGB2GRAY
        image = cv2.cvtColor(np.ascontiguousarray(image), code)
    return np.ascontiguousarray(image)


_SOF_MARKERS = {0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}


def _sof_size(data: bytes) -> tuple[int, int] | None:
    """``(height, width)`` from the first JPEG frame header in ``data``, or None."""
    i = 2
    while data[:2] == b"\xff\xd8" and i + 9 < len(data):
        if data[i] != 0xFF:
            i += 1
            continue
        marker = data[i + 1]
        if marker == 0xFF or marker == 0x01 or 0xD0 <= marker <= 0xD8:
            i += 2 if marker != 0xFF else 1
            continue
        if marker in _SOF_MARKERS:
            h, w = data[i + 5 : i + 7], data[i + 7 : i + 9]
            return int.from_bytes(h, "big"), int.from_bytes(w, "big")
        i += 2 + int.from_bytes(data[i + 2 : i + 4], "big")
    return None


def jpeg_size(path: str | os.PathLike[str]) -> tuple[int, int]:
    """``(height, width)`` of a JPEG file from its frame header, without decoding it.

    Reads only the first 64 KiB (the header sits there unless large metadata precede it; then
    the whole file is read).

    Raises:
        ImageError: missing or unreadable file, not a JPEG, or no frame header found.
    """
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            size = _sof_size(fh.read(65536))
    except OSError:
        size = None  # read_file_bytes below raises the clear error
    if size is None:
        size = _sof_size(read_file_bytes(p))
    if size is None:
        raise ImageError(
            f"{p}: no JPEG frame header found; expected a baseline or progressive JPEG"
        )
    return size

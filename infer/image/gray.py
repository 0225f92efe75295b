"""Any image array → the canonical ``(H, W) uint8`` grayscale form (the published routine's).

Colour is converted with OpenCV's ITU-R BT.601 luma, alpha is dropped, 16-bit samples are scaled
by 255/65535 with rounding, float arrays are taken as ``[0, 1]`` intensities (values outside are
an error, never clipped: a float image in 0-255 would otherwise read as almost all white).
"""

from __future__ import annotations

import cv2
import numpy as np


class ImageError(ValueError):
    """An image file or array that cannot be used; the message names the file."""


def to_gray_u8(image: np.ndarray, name: str = "<array>", bgr: bool = False) -> np.ndarray:
    """Convert an array to the canonical ``(H, W) uint8`` grayscale form.

    Args:
        image: ``(H, W)``, ``(H, W, 1)``, ``(H, W, 3)`` or ``(H, W, 4)`` array of dtype uint8,
            uint16 (scaled to 8 bits), bool, or float (intensities in ``[0, 1]``; NaN, inf and
            values outside ``[0, 1]`` rejected).
        name: how to refer to the input in error messages (usually its file name).
        bgr: channel order is OpenCV's BGR(A) (files) rather than RGB(A) (arrays).

    Returns:
        ``(H, W) uint8`` contiguous array.

    Raises:
        ImageError: wrong shape or dtype, empty, non-finite or out-of-range float values.
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
        lo, hi = float(image.min()), float(image.max())
        if lo < 0.0 or hi > 1.0:
            raise ImageError(
                f"{name}: float image values span [{lo:g}, {hi:g}]; expected intensities in "
                "[0, 1] (divide a 0-255 image by 255, or save it as 8- or 16-bit integers)"
            )
        image = np.rint(image * 255.0).astype(np.uint8)
    elif image.dtype != np.uint8:
        raise ImageError(f"{name}: expected uint8, uint16, bool or float, got {image.dtype}")
    if image.ndim == 3:
        if image.shape[2] == 4:
            image = image[:, :, :3]
        code = cv2.COLOR_BGR2GRAY if bgr else cv2.COLOR_RGB2GRAY
        image = cv2.cvtColor(np.ascontiguousarray(image), code)
    return np.ascontiguousarray(image)


def reduce_area(gray: np.ndarray, k: int) -> np.ndarray:
    """Shrink a ``(H, W) uint8`` frame ``k`` times per side by area averaging (``k × k`` blocks).

    What a JPEG decoded at 1/k (libjpeg's DCT scaling) gives for other formats and for decoded
    arrays. With sides divisible by ``k`` the blocks tile the frame exactly, so areas scale back
    by exactly ``k²`` (OpenCV's integer INTER_AREA path, ~1 ms for 2592×1944 at k = 4); other
    sides are rounded to the nearest pixel.

    Args:
        gray: ``(H, W) uint8`` frame.
        k: integer factor ≥ 1 (1 returns ``gray`` itself).

    Returns:
        ``(round(H / k), round(W / k)) uint8``.
    """
    if k == 1:
        return gray
    if k < 1:
        raise ValueError(f"reduce_area: k must be >= 1, got {k}")
    h, w = gray.shape[:2]
    size = (max(1, round(w / k)), max(1, round(h / k)))
    return cv2.resize(gray, size, interpolation=cv2.INTER_AREA)

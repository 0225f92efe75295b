"""The crop of a frame around its ring, and the way back: input pixels ↔ network pixels.

Pixel convention: pixel ``(i, j)`` has its centre at ``x = j``, ``y = i`` (OpenCV's). The crop
box covers input pixels ``x0 .. x0 + side - 1`` (columns) and ``y0 .. y0 + side - 1`` (rows);
network pixel ``u`` has its centre at input ``x = x0 + (u + 0.5) · side / S - 0.5`` (the
mapping ``cv2.resize`` uses).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.ring import RingFit


@dataclass(frozen=True)
class CropBox:
    """Square crop in input pixels; may extend outside the image (padded with zeros)."""

    x0: int  # px, first column
    y0: int  # px, first row
    side: int  # px

    def scale(self, size: int) -> float:
        """Input pixels per network pixel for a network input of ``size`` px."""
        return self.side / size

    def to_network_affine(self, size: int) -> np.ndarray:
        """``(2, 3) float64`` affine mapping input pixel coordinates to network coordinates."""
        k = size / self.side
        return np.array(
            [[k, 0.0, (0.5 - self.x0) * k - 0.5], [0.0, k, (0.5 - self.y0) * k - 0.5]], np.float64
        )


def crop_box(
    ring: RingFit, shape: tuple[int, ...], config: PreprocessConfig = PreprocessConfig()
) -> CropBox:
    """Square box of side ``crop_factor × ring.radius`` centred on the ring.

    Args:
        ring: outer ring (from :func:`locate_ring`).
        shape: input image shape ``(H, W)``; the box must overlap the image.
        config: ``crop_factor``.

    Returns:
        Integer box in input pixels (may extend outside the image).
    """
    h, w = int(shape[0]), int(shape[1])
    side = max(2, round(config.crop_factor * ring.radius))
    x0 = round(ring.cx - (side - 1) / 2.0)
    y0 = round(ring.cy - (side - 1) / 2.0)
    if x0 >= w or y0 >= h or x0 + side <= 0 or y0 + side <= 0:
        raise ValueError(f"crop box {x0, y0, side} does not overlap the {w}×{h} image")
    return CropBox(x0, y0, side)


def crop_resize(image: np.ndarray, box: CropBox, size: int) -> np.ndarray:
    """Crop ``box`` (zero padding outside the image) and resize to ``(size, size)``.

    Args:
        image: ``(H, W)`` uint8 or float32 array (frames, or a mask as 0/1 float).
        box: crop in input pixels.
        size: output side, px. INTER_AREA when shrinking (anti-aliasing), linear otherwise.

    Returns:
        ``(size, size) float32`` in the input's units.
    """
    h, w = image.shape[:2]
    crop = np.zeros((box.side, box.side), np.float32)
    xa, ya = max(box.x0, 0), max(box.y0, 0)
    xb, yb = min(box.x0 + box.side, w), min(box.y0 + box.side, h)
    if xb > xa and yb > ya:
        crop[ya - box.y0 : yb - box.y0, xa - box.x0 : xb - box.x0] = image[ya:yb, xa:xb]
    interp = cv2.INTER_AREA if box.side > size else cv2.INTER_LINEAR
    return cv2.resize(crop, (size, size), interpolation=interp)


def valid_window(box: CropBox, shape: tuple[int, ...], size: int) -> tuple[slice, slice]:
    """Network-pixel rows/cols whose centres fall inside the image.

    Args:
        box: the crop.
        shape: input image shape ``(H, W)``.
        size: network input side ``S``, px.

    Returns:
        ``(rows, cols)`` slices into an ``(S, S)`` map; EMPTY (``slice(0, 0)`` both) when no
        network pixel centre falls inside the image (a box that barely overlaps it): such a
        crop holds no measurable pixel.
    """
    k = box.side / size
    u = (np.arange(size) + 0.5) * k - 0.5
    cols = np.flatnonzero((u + box.x0 >= -0.5) & (u + box.x0 <= shape[1] - 0.5))
    rows = np.flatnonzero((u + box.y0 >= -0.5) & (u + box.y0 <= shape[0] - 0.5))
    if cols.size == 0 or rows.size == 0:
        return slice(0, 0), slice(0, 0)
    return slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)


def from_network(prob: np.ndarray, box: CropBox, out_shape: tuple[int, ...]) -> np.ndarray:
    """Map a network-space map back to input pixels (exact inverse affine, bilinear).

    Args:
        prob: ``(S, S) float32`` probabilities (or logits) in network pixels.
        box: the crop used for the input.
        out_shape: input image shape ``(H, W)``.

    Returns:
        ``(H, W) float32``; 0 outside the crop.
    """
    prob = np.asarray(prob)
    if prob.ndim != 2 or prob.shape[0] != prob.shape[1]:
        raise ValueError(f"from_network: expected a square (S, S) map, got shape {prob.shape}")
    if not np.all(np.isfinite(prob)):
        raise ValueError("from_network: map contains NaN or inf")
    m = box.to_network_affine(prob.shape[0])  # input → network = dst → src for warpAffine
    h, w = int(out_shape[0]), int(out_shape[1])
    return cv2.warpAffine(
        prob.astype(np.float32),
        m,
        (w, h),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0.0,
    )

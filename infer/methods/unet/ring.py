"""Find the bright outer (window/LGP) ring that centres the U-Net's crop, whatever the exposure."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.infer.image.gray import to_gray_u8
from contactcal.infer.image.percentile import percentiles
from contactcal.infer.methods.unet.config import PreprocessConfig

#: Largest plausible ring radius, × the image's longest side: the ring may be cut by the border,
#: but a circle fitted to a few nearly straight contour points can be arbitrarily large (and its
#: crop would then ask for an arbitrarily large allocation).
MAX_RADIUS_FRACTION = 1.0


@dataclass(frozen=True)
class RingFit:
    """Outer ring in input pixels (x right, y down)."""

    cx: float  # px
    cy: float  # px
    radius: float  # px, outer edge of the ring
    found: bool = True  # False: fallback (image centre, fallback radius)


def _fit_circle(points: np.ndarray) -> tuple[float, float, float, float]:
    """Algebraic (Kåsa) least-squares circle through ``(N, 2)`` points: cx, cy, r, RMS residual."""
    x, y = points[:, 0], points[:, 1]
    a = np.stack([x, y, np.ones_like(x)], axis=1)
    b = x * x + y * y
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    cx, cy = sol[0] / 2.0, sol[1] / 2.0
    r2 = sol[2] + cx * cx + cy * cy
    if not r2 > 0.0:
        return cx, cy, 0.0, float("inf")
    r = float(np.sqrt(r2))
    resid = float(np.sqrt(np.mean((np.hypot(x - cx, y - cy) - r) ** 2)))
    return float(cx), float(cy), r, resid


def locate_ring(gray: np.ndarray, config: PreprocessConfig = PreprocessConfig()) -> RingFit:
    """Find the bright outer ring, independently of exposure.

    Threshold at ``ring_threshold_fraction`` × the ``ring_percentile``-th percentile (not an
    absolute grey level), close small gaps, take the largest external contour (the ring's
    outer outline encloses everything inside it) and fit a circle to its points (works for a
    ring cut by the image border, unlike an enclosing circle).

    Args:
        gray: ``(H, W) uint8`` frame (other forms accepted by ``to_gray_u8`` are converted).
        config: thresholds.

    Returns:
        The fit in input pixels; ``found=False`` with the image centre and
        ``fallback_radius_fraction × min(H, W)`` when no plausible ring is found.

    Raises:
        ValueError: not an image (wrong ndim, NaN, ...).
    """
    gray = to_gray_u8(gray, name="locate_ring input")
    h, w = gray.shape
    fallback = RingFit(
        (w - 1) / 2.0, (h - 1) / 2.0, config.fallback_radius_fraction * min(h, w), False
    )
    s = min(1.0, config.ring_work_px / max(h, w))
    work = gray
    if s < 1.0:
        work = cv2.resize(
            gray, (max(1, round(w * s)), max(1, round(h * s))), interpolation=cv2.INTER_AREA
        )
    # For a uint8 image its 50th percentile is np.median's value.
    bright, median = percentiles(work, (config.ring_percentile, 50.0))
    if bright < 8.0 or bright < config.ring_min_contrast * max(median, 1.0):
        return fallback
    binary = (work >= config.ring_threshold_fraction * bright).astype(np.uint8)
    k = max(3, 2 * round(0.004 * max(work.shape)) + 1)
    binary = cv2.morphologyEx(
        binary, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    )
    contours, _ = cv2.findContours(binary, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return fallback
    contour = max(contours, key=cv2.contourArea).reshape(-1, 2).astype(np.float64)
    if len(contour) < 8:
        return fallback
    sx, sy = w / work.shape[1], h / work.shape[0]  # work pixel centre u → input (u + 0.5)·s - 0.5
    pts = np.stack([(contour[:, 0] + 0.5) * sx - 0.5, (contour[:, 1] + 0.5) * sy - 0.5], axis=1)
    cx, cy, r, resid = _fit_circle(pts)
    if (
        r < config.ring_min_radius_fraction * min(h, w)
        or r > MAX_RADIUS_FRACTION * max(h, w)
        or resid > config.ring_max_residual_fraction * r
    ):
        return fallback
    return RingFit(cx, cy, r, True)

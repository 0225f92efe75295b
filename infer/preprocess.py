"""Network preprocessing shared by training and deployment (numpy + OpenCV only).

A frame is cropped to a square box centred on the bright outer (window/LGP) ring, resized to
``input_size`` and normalised; the network's probabilities are mapped back to input pixels with
the exact inverse of that crop/resize. Training (``contactcal.train.data``) and deployment use
these same functions, so they cannot drift.

Pixel convention: pixel ``(i, j)`` has its centre at ``x = j``, ``y = i`` (OpenCV's). The crop
box covers input pixels ``x0 .. x0 + side - 1`` (columns) and ``y0 .. y0 + side - 1`` (rows);
network pixel ``u`` has its centre at input ``x = x0 + (u + 0.5) · side / S - 0.5`` (the
mapping ``cv2.resize`` uses).

Normalisation: ``u = clip(crop / P, 0, 1)`` with ``P`` the ``norm_percentile``-th percentile of
the crop's in-image pixels (exposure/gain invariance: the brightest structure, the outer ring,
is in every crop), then ``x = (u - norm_mean) / norm_std`` with FIXED constants (not the
image's own mean/std, which would depend on the contact size, i.e. on the signal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import cv2
import numpy as np

from contactcal.infer.io import to_gray_u8

T = TypeVar("T")


@dataclass(frozen=True)
class PreprocessConfig:
    """Crop, resize and normalisation of a frame into the network input."""

    input_size: int = 256  # px, network input side; finer ridges vs ~quadratic time
    crop_factor: float = 2.2  # × outer-ring radius = crop side; 2.0 is the ring's diameter,
    #   the margin keeps the whole ring (context + scale cue) in view; larger wastes resolution
    norm_percentile: float = 99.5  # %, brightness reference P; lower is less sparkle-sensitive
    #   but saturates larger bright areas (big contacts)
    norm_mean: float = 0.25  # fixed offset after dividing by P (typical mean of u); no effect
    #   on the optimum, only on conditioning
    norm_std: float = 0.25  # fixed scale after dividing by P (typical spread of u); idem
    ring_threshold_fraction: float = 0.5  # of the ring search's bright percentile; lower merges
    #   the ring with the background glow, higher breaks a dim ring into pieces
    ring_percentile: float = 99.5  # %, bright level the ring threshold is relative to
    ring_min_contrast: float = 2.0  # bright percentile / median needed to accept a ring;
    #   lower accepts noise as a ring, higher rejects dim rigs
    ring_min_radius_fraction: float = 0.2  # of min(H, W); smaller circles are not the ring
    ring_max_residual_fraction: float = 0.08  # RMS circle-fit residual / radius; higher accepts
    #   ellipses and blobs, lower rejects slightly broken rings
    ring_work_px: int = 512  # px, longest side the ring search works at; smaller is faster, coarser
    fallback_radius_fraction: float = 0.45  # of min(H, W), ring radius assumed when none is found

    def __post_init__(self) -> None:
        if self.input_size < 8:
            raise ValueError(f"input_size must be >= 8 px, got {self.input_size}")
        if not self.crop_factor > 0.0:
            raise ValueError(f"crop_factor must be > 0, got {self.crop_factor}")
        for name in ("norm_percentile", "ring_percentile"):
            if not 0.0 < getattr(self, name) <= 100.0:
                raise ValueError(f"{name} must be in (0, 100], got {getattr(self, name)}")
        if not self.norm_std > 0.0:
            raise ValueError(f"norm_std must be > 0, got {self.norm_std}")
        if not 0.0 < self.ring_threshold_fraction < 1.0:
            raise ValueError(
                f"ring_threshold_fraction not in (0, 1): {self.ring_threshold_fraction}"
            )


@dataclass(frozen=True)
class RingFit:
    """Outer ring in input pixels (x right, y down)."""

    cx: float  # px
    cy: float  # px
    radius: float  # px, outer edge of the ring
    found: bool = True  # False: fallback (image centre, fallback radius)


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


@dataclass(frozen=True)
class Prepared:
    """A frame ready for the network."""

    x: np.ndarray  # (C, S, S) float32; C = 1 (frame) or 2 (frame, reference)
    box: CropBox
    ring: RingFit


def _gray(image: np.ndarray, name: str) -> np.ndarray:
    """Canonical ``(H, W) uint8``; raises ``ImageError`` (a ValueError) on bad input."""
    return to_gray_u8(image, name=name)


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
    gray = _gray(gray, "locate_ring input")
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
    bright = float(np.percentile(work, config.ring_percentile))
    median = float(np.median(work))
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
        or resid > config.ring_max_residual_fraction * r
    ):
        return fallback
    return RingFit(cx, cy, r, True)


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


def valid_window(box: CropBox, shape: tuple[int, int], size: int) -> tuple[slice, slice]:
    """Network-pixel rows/cols whose centres fall inside the image."""
    k = box.side / size
    u = (np.arange(size) + 0.5) * k - 0.5
    cols = np.flatnonzero((u + box.x0 >= -0.5) & (u + box.x0 <= shape[1] - 0.5))
    rows = np.flatnonzero((u + box.y0 >= -0.5) & (u + box.y0 <= shape[0] - 0.5))
    if cols.size == 0 or rows.size == 0:
        return slice(0, size), slice(0, size)
    return slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)


def unit_to_network(u: T, config: PreprocessConfig) -> T:
    """``[0, 1]`` intensities → network values (numpy arrays or torch tensors alike)."""
    return (u - config.norm_mean) / config.norm_std  # type: ignore[operator]


def network_to_unit(x: T, config: PreprocessConfig) -> T:
    """Inverse of :func:`unit_to_network` (used by training augmentation)."""
    return x * config.norm_std + config.norm_mean  # type: ignore[operator]


def to_network(
    gray: np.ndarray, box: CropBox, config: PreprocessConfig = PreprocessConfig()
) -> np.ndarray:
    """Crop, resize and normalise one frame.

    Args:
        gray: ``(H, W) uint8`` frame.
        box: crop (same box for a frame and its reference).
        config: size and normalisation.

    Returns:
        ``(S, S) float32`` network input, ``S = config.input_size``.
    """
    gray = _gray(gray, "to_network input")
    s = config.input_size
    crop = crop_resize(gray, box, s)
    rows, cols = valid_window(box, gray.shape, s)
    ref = float(np.percentile(crop[rows, cols], config.norm_percentile))
    u = np.clip(crop / max(ref, 1.0), 0.0, 1.0)
    return unit_to_network(u, config).astype(np.float32)


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


def prepare(
    gray: np.ndarray,
    reference_gray: np.ndarray | None = None,
    config: PreprocessConfig = PreprocessConfig(),
) -> Prepared:
    """Full preprocessing of one frame (and optionally its session's zero-pressure frame).

    The ring (hence the box) comes from the reference when given (the ring is fixed in a
    session, and the reference has no contact to confuse the search); if it has no ring, from
    the frame itself.

    Args:
        gray: ``(H, W) uint8`` frame.
        reference_gray: ``(H, W) uint8`` zero-pressure frame of the same session, or None.
        config: preprocessing.

    Returns:
        :class:`Prepared` with ``x`` of shape ``(1, S, S)`` or ``(2, S, S)`` (frame, reference).

    Raises:
        ValueError: bad image, or reference of a different shape.
    """
    gray = _gray(gray, "frame")
    if reference_gray is None:
        ring = locate_ring(gray, config)
    else:
        reference_gray = _gray(reference_gray, "reference frame")
        if reference_gray.shape != gray.shape:
            raise ValueError(
                f"reference frame shape {reference_gray.shape} differs from the frame shape "
                f"{gray.shape}"
            )
        ring = locate_ring(reference_gray, config)
        if not ring.found:
            own = locate_ring(gray, config)
            ring = own if own.found else ring
    box = crop_box(ring, gray.shape, config)
    channels = [to_network(gray, box, config)]
    if reference_gray is not None:
        channels.append(to_network(reference_gray, box, config))
    return Prepared(np.stack(channels), box, ring)

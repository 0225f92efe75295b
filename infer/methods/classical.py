"""The published automatic contact-area routine (classical baseline), as pure OpenCV functions.

Routine (Sensors 2024 calibration-rig paper), constants expressed for 2592×1944 frames and scaled
with the image width:

* ROI, from the zero-pressure (reference) frame: grayscale → threshold at 150 → erode with a
  circular 10 px kernel → largest contour → ``minEnclosingCircle`` → concentric circular ROI of
  55 % of that circle's diameter.
* Each frame: grayscale → ``bitwise_and`` with the ROI → threshold at half the frame's maximum →
  erode 3 px → dilate 15 px → largest contour → ``minAreaRect`` → area of the inscribed ellipse
  ``π·w·h/4``.

It overestimates systematically (dilation grows the blob; the rectangle's ellipse covers the
bright inner ring) and it finds "contact" in any frame that has a bright pixel, which is why it is
meaningless below the contact onset. It is kept faithful on purpose: it is the baseline to beat.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from contactcal.infer.image.frame import as_frame
from contactcal.infer.image.gray import ImageError, to_gray_u8
from contactcal.infer.image.read import ImageFile, ImageSource
from contactcal.infer.methods.base import AreaResult, Started, load_reference


@dataclass(frozen=True)
class ClassicalConfig:
    """Constants of the published routine, for frames ``reference_width_px`` wide."""

    reference_width_px: int = 2592  # px; kernel sizes below are for this width, scaled linearly
    ring_threshold: int = 150  # grey level (8-bit) separating the LGP ring from the rest
    ring_erode_px: float = 10.0  # px circular kernel; removes sparkle before finding the ring
    roi_fraction: float = 0.55  # of the ring's enclosing diameter; smaller cuts off big contacts
    contact_threshold_fraction: float = 0.5  # of the frame's max; lower grows the blob
    erode_px: float = 3.0  # px; removes isolated bright specks
    dilate_px: float = 15.0  # px; merges ridges into one blob (and inflates the area)
    work_scale: float = 1.0  # process at this fraction of the input size; <1 is faster, coarser

    def __post_init__(self) -> None:
        if not 0.0 < self.work_scale <= 1.0:
            raise ValueError(f"work_scale must be in (0, 1], got {self.work_scale}")
        if not 0.0 < self.roi_fraction <= 1.0:
            raise ValueError(f"roi_fraction must be in (0, 1], got {self.roi_fraction}")
        if not 0 <= self.ring_threshold <= 255:
            raise ValueError(
                f"ring_threshold must be a grey level 0-255, got {self.ring_threshold}"
            )


@dataclass(frozen=True)
class Roi:
    """Circular region of interest in input pixels (x right, y down)."""

    cx: float
    cy: float
    radius: float
    ring_radius: float  # radius of the ring's minimum enclosing circle, px

    def mask(self, shape: tuple[int, int], scale: float = 1.0) -> np.ndarray:
        """``(H, W) uint8`` mask (255 inside) for an image of ``shape`` at ``scale`` × input."""
        m = np.zeros(shape, np.uint8)
        centre = (round(self.cx * scale), round(self.cy * scale))
        cv2.circle(m, centre, max(1, round(self.radius * scale)), 255, thickness=-1)
        return m


@dataclass(frozen=True)
class ClassicalResult:
    """Outcome of the routine on one frame. Areas and coordinates are in input pixels."""

    contact: bool
    area_px: float  # ellipse area π·w·h/4 (0.0 when no contact)
    ellipse: tuple[tuple[float, float], tuple[float, float], float] | None  # cv2 RotatedRect
    roi: Roi | None
    reason: str  # "" when contact, else why not ("no ring found", "no contact", ...)
    debug: dict[str, np.ndarray] = field(default_factory=dict, repr=False)


def _kernel(size_px: float, scale: float) -> np.ndarray:
    """Circular (elliptic) structuring element of ``size_px`` at 2592 px, scaled."""
    k = max(1, round(size_px * scale))
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))


def _scale_of(width: int, config: ClassicalConfig) -> float:
    return width / config.reference_width_px


def _largest_contour(binary: np.ndarray) -> np.ndarray | None:
    contours, _ = cv2.findContours(binary, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    return max(contours, key=cv2.contourArea)


def _work_image(image: np.ndarray, config: ClassicalConfig) -> np.ndarray:
    gray = to_gray_u8(image)
    if config.work_scale < 1.0:
        h, w = gray.shape
        size = (max(1, round(w * config.work_scale)), max(1, round(h * config.work_scale)))
        gray = cv2.resize(gray, size, interpolation=cv2.INTER_AREA)
    return gray


def ring_pixels(gray: np.ndarray, config: ClassicalConfig = ClassicalConfig()) -> np.ndarray:
    """The ROI step's binary image: threshold at ``ring_threshold``, then the circular erosion.

    Args:
        gray: ``(H, W) uint8`` working image (kernel sizes scale with its width).
        config: routine constants.

    Returns:
        ``(H, W) uint8`` binary image (255 = kept).
    """
    _, ring = cv2.threshold(gray, config.ring_threshold, 255, cv2.THRESH_BINARY)
    return cv2.erode(ring, _kernel(config.ring_erode_px, _scale_of(gray.shape[1], config)))


def find_roi(reference: np.ndarray, config: ClassicalConfig = ClassicalConfig()) -> Roi | None:
    """ROI from the zero-pressure frame's bright window ring.

    Args:
        reference: ``(H, W)`` or ``(H, W, 3)`` image (canonical form preferred).
        config: routine constants.

    Returns:
        The ROI in input pixels, or None when nothing exceeds the ring threshold after erosion.
    """
    gray = _work_image(reference, config)
    s = config.work_scale
    contour = _largest_contour(ring_pixels(gray, config))
    if contour is None:
        return None
    (cx, cy), r = cv2.minEnclosingCircle(contour)
    return Roi(cx / s, cy / s, config.roi_fraction * r / s, r / s)


def measure_classical(
    image: np.ndarray,
    roi: Roi | None = None,
    config: ClassicalConfig = ClassicalConfig(),
    debug: bool = False,
) -> ClassicalResult:
    """Run the published per-frame routine.

    Args:
        image: ``(H, W)`` uint8 (canonical) or any array :func:`to_gray_u8` accepts.
        roi: ROI from :func:`find_roi` on the session's reference frame; None → taken from
            this frame itself (the window ring is visible in every frame).
        config: routine constants.
        debug: keep the intermediate images (``gray``, ``masked``, ``threshold``, ``eroded``,
            ``dilated``, at working resolution) in ``result.debug``.

    Returns:
        A :class:`ClassicalResult`; never raises for an image without ring or contact.
    """
    gray = _work_image(image, config)
    s = config.work_scale
    if roi is None:
        roi = find_roi(image, config)
        if roi is None:
            return ClassicalResult(False, 0.0, None, None, "no ring found")
    scale = _scale_of(gray.shape[1], config)
    masked = cv2.bitwise_and(gray, gray, mask=roi.mask(gray.shape, s))
    peak = int(masked.max())
    steps: dict[str, np.ndarray] = {"gray": gray, "masked": masked} if debug else {}
    if peak == 0:
        return ClassicalResult(False, 0.0, None, roi, "no contact (ROI is black)", steps)
    _, thr = cv2.threshold(masked, peak * config.contact_threshold_fraction, 255, 0)
    eroded = cv2.erode(thr, _kernel(config.erode_px, scale))
    dilated = cv2.dilate(eroded, _kernel(config.dilate_px, scale))
    if debug:
        steps.update(threshold=thr, eroded=eroded, dilated=dilated)
    contour = _largest_contour(dilated)
    if contour is None:
        return ClassicalResult(
            False, 0.0, None, roi, "no contact (nothing left after erosion)", steps
        )
    (cx, cy), (w, h), angle = cv2.minAreaRect(contour)
    area = math.pi * (w / s) * (h / s) / 4.0
    if not area > 0.0:
        return ClassicalResult(False, 0.0, None, roi, "no contact (degenerate blob)", steps)
    ellipse = ((cx / s, cy / s), (w / s, h / s), float(angle))
    return ClassicalResult(True, float(area), ellipse, roi, "", steps)


class ClassicalMethod:
    """The published routine as a :class:`~contactcal.infer.methods.base.Method`."""

    name = "classical"
    NO_REFERENCE = "no reference frame: the ROI was taken from this frame's own ring"

    def __init__(self, config: ClassicalConfig | None = None) -> None:
        self.config = config or ClassicalConfig()
        self.roi: Roi | None = None
        self.shape: tuple[int, int] | None = None  # the reference frame's (H, W), px

    def start(
        self,
        files: Sequence[ImageSource],
        reference: ImageFile | None,
        bit_depth: int | None = None,
    ) -> Started:
        """Read the reference fully decoded (the routine's constants are for full frames)."""
        ref = load_reference(reference, bit_depth=bit_depth)
        self.set_reference(ref)
        return Started(1, ref)

    def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
        """Take the ROI from the reference frame; without one, each frame finds its own."""
        if reduction != 1:
            raise ValueError("the classical routine runs on fully decoded frames (reduction 1)")
        if reference is None:
            self.roi, self.shape = None, None
            return
        gray = as_frame(reference, "reference frame")
        self.roi, self.shape = find_roi(gray, self.config), gray.shape

    def _frame(self, image: np.ndarray) -> np.ndarray:
        """The checked frame (:func:`as_frame`), of the reference frame's size when there is one
        (its ROI would fall elsewhere on a frame of another size)."""
        gray = as_frame(image, "frame")
        if self.shape is not None and gray.shape != self.shape:
            (h, w), (rh, rw) = gray.shape, self.shape
            raise ImageError(
                f"frame: {w}×{h} px, but the reference frame is {rw}×{rh} px; measure a "
                "session's frames against its own reference (same camera and size)"
            )
        return gray

    def measure(self, image: np.ndarray) -> AreaResult:
        """Run the routine; the contour is the fitted ellipse.

        The routine states no interval of its area: ``area_interval_px`` is None.
        """
        res = measure_classical(self._frame(image), self.roi, self.config)
        contour = None
        if res.ellipse is not None:
            (cx, cy), (w, h), ang = res.ellipse
            pts = cv2.ellipse2Poly(
                (round(cx), round(cy)), (round(w / 2), round(h / 2)), round(ang), 0, 360, 5
            )
            contour = pts.reshape(-1, 1, 2).astype(np.int32)
        return AreaResult(res.contact, res.area_px, res.reason, contour)

    def describe(self) -> dict[str, Any]:
        """``{"name": "classical", "config": <ClassicalConfig fields>}``."""
        return {"name": self.name, "config": dataclasses.asdict(self.config)}

"""Contact-area methods behind one small interface, so the CLI and the benchmark treat them alike.

A method is prepared once per session with the reference (lowest-pressure) frame, then measures
frames. Areas are in pixels of the input image.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np

from contactcal.infer.classical import ClassicalConfig, Roi, find_roi, measure_classical


@dataclass(frozen=True)
class AreaResult:
    """One frame's outcome."""

    contact: bool
    area_px: float  # in pixels of the input image; 0.0 when no contact
    note: str  # "" or why there is no contact
    contour: np.ndarray | None  # (N, 1, 2) int32 outline in input pixels, for overlays
    soft_area_px: float | None = None  # U-Net: sum of probabilities over the region (sub-pixel)


class Method(Protocol):
    """What every contact-area method provides."""

    name: str

    def prepare(self, reference: np.ndarray | None) -> None:
        """Use the session's reference frame ``(H, W) uint8`` (or None)."""

    def measure(self, image: np.ndarray) -> AreaResult:
        """Measure one ``(H, W) uint8`` frame."""


class ClassicalMethod:
    """The published OpenCV routine (:mod:`contactcal.infer.classical`)."""

    name = "classical"

    def __init__(self, config: ClassicalConfig | None = None) -> None:
        self.config = config or ClassicalConfig()
        self.roi: Roi | None = None

    def prepare(self, reference: np.ndarray | None) -> None:
        """Take the ROI from the reference frame; without one, each frame finds its own."""
        self.roi = None if reference is None else find_roi(reference, self.config)

    def measure(self, image: np.ndarray) -> AreaResult:
        """Run the routine; the contour is the fitted ellipse."""
        res = measure_classical(image, self.roi, self.config)
        contour = None
        if res.ellipse is not None:
            (cx, cy), (w, h), ang = res.ellipse
            pts = cv2.ellipse2Poly(
                (round(cx), round(cy)), (round(w / 2), round(h / 2)), round(ang), 0, 360, 5
            )
            contour = pts.reshape(-1, 1, 2).astype(np.int32)
        return AreaResult(res.contact, res.area_px, res.reason, contour)


class UnetMethod:
    """The learned segmenter (:class:`contactcal.infer.segmenter.OnnxSegmenter`)."""

    name = "unet"

    def __init__(self, model: str | None = None, threads: int = 1, outline: bool = False) -> None:
        from contactcal.infer.segmenter import OnnxSegmenter

        self.segmenter = OnnxSegmenter(model, threads=threads)
        self.outline = outline  # map the mask back to input pixels for an outline (overlays)

    def prepare(self, reference: np.ndarray | None) -> None:
        """Fix the crop and the reference channel from the session's zero-pressure frame."""
        self.segmenter.set_reference(reference)

    def measure(self, image: np.ndarray) -> AreaResult:
        """Segment; the contour is the kept region's outline in input pixels."""
        seg = self.segmenter.predict(image)
        if not seg.contact:
            return AreaResult(False, 0.0, "no contact", None)
        if not self.outline:
            return AreaResult(True, seg.area_px, "", None, seg.soft_area_px)
        mask = self.segmenter.mask_in_input(seg, image.shape[:2]).astype(np.uint8)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        contour = max(contours, key=cv2.contourArea) if contours else None
        return AreaResult(True, seg.area_px, "", contour, seg.soft_area_px)


#: Method names; the first is the default of ``measure`` and ``calibrate``.
METHODS = ("unet", "classical")


def make_method(
    name: str, model: str | None = None, threads: int = 1, outline: bool = False
) -> Method:
    """Build a method by name.

    Args:
        name: ``"unet"`` or ``"classical"``.
        model: ONNX file for ``"unet"`` (None → the shipped model).
        threads: onnxruntime intra-op threads for ``"unet"``.
        outline: compute the U-Net's outline in input pixels (for overlays; costs a full-size
            warp per frame). The classical ellipse outline is always given.

    Raises:
        ValueError: unknown method name; ``ModelError`` for an unusable model file.
    """
    if name == "classical":
        return ClassicalMethod()
    if name == "unet":
        return UnetMethod(model, threads, outline)
    raise ValueError(f"unknown method {name!r}; expected one of {', '.join(METHODS)}")

"""The U-Net's decision: from a probability map to contact / no contact and an area.

One function for validation during training, threshold tuning, export checks and deployment, so
that the model is selected on the decision it ships with.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.infer.methods.unet.prepare import CropBox, from_network, valid_window
from contactcal.infer.methods.unet.spec import ModelSpec


@dataclass(frozen=True)
class Segmentation:
    """One frame's prediction. Areas in input pixels."""

    contact: bool
    area_px: float  # thresholded mask, largest connected region only (0.0 without contact)
    soft_area_px: float  # sum of probabilities over the same region's neighbourhood (sub-pixel)
    region_net_px: float  # network pixels of the largest region (before the minimum-area test)
    prob: np.ndarray  # (S, S) float32 probabilities in network pixels (0 outside the image)
    mask_net: np.ndarray  # (S, S) bool, the kept region in network pixels
    box: CropBox  # crop that maps network pixels to input pixels


def postprocess(
    prob: np.ndarray, box: CropBox, shape: tuple[int, int], spec: ModelSpec
) -> Segmentation:
    """Keep the largest connected region above the threshold; decide contact; measure it.

    Network pixels whose centres fall outside the image are ignored (a crop that barely overlaps
    the image may have none inside: then no contact, area 0). Ring reflections and
    sparkle give small or detached specks: only the largest region counts, and only if it covers
    at least ``spec.min_contact_area_px`` network pixels.

    Args:
        prob: ``(S, S)`` probabilities in network pixels.
        box: the crop the network input was made with.
        shape: input image ``(H, W)``.
        spec: threshold and minimum area.

    Returns:
        The segmentation; areas in input pixels (network pixels × the crop's scale²).
    """
    inside = np.zeros(prob.shape, bool)
    inside[valid_window(box, shape, prob.shape[0])] = True
    prob = np.where(inside, prob, 0.0).astype(np.float32)
    binary = (prob >= spec.threshold).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=8)
    px_per_net = box.scale(prob.shape[0]) ** 2  # input pixels per network pixel
    if n <= 1:
        keep = np.zeros_like(binary, dtype=bool)
    else:
        keep = labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    area_net = float(keep.sum())
    if area_net < spec.min_contact_area_px or area_net == 0.0:
        return Segmentation(False, 0.0, 0.0, area_net, prob, np.zeros_like(keep), box)
    near = cv2.dilate(keep.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    soft = float(prob[near].sum())
    return Segmentation(True, area_net * px_per_net, soft * px_per_net, area_net, prob, keep, box)


def mask_in_input(seg: Segmentation, shape: tuple[int, int]) -> np.ndarray:
    """``(H, W) bool`` contact mask in input pixels (for overlays and IoU against masks)."""
    return from_network(seg.mask_net.astype(np.float32), seg.box, shape) >= 0.5

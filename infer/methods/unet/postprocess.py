"""The U-Net's decision: from a probability map to contact / no contact, an area and its interval.

One function for validation during training, threshold tuning, export checks, interval
calibration and deployment, so that the model is selected on the decision it ships with. (The
contact decision, that is: training validates with the region as segmented, ``"largest"``; a
model's ``"convex"`` region, stated later by ``python -m contactcal.train.interval --region``,
changes its areas, never which frames are contact.)
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.infer.methods.unet.crop import CropBox, from_network, valid_window
from contactcal.infer.methods.unet.spec import IntervalSpec, ModelSpec


@dataclass(frozen=True)
class Band:
    """A frame's boundary band, in network pixels: what the area's interval is built from."""

    area: float  # the kept region (0 without contact)
    strict: float  # the kept region's pixels with p >= threshold_high (<= area)
    loose: float  # the region at p >= threshold_low around it (>= area); see boundary_band
    edge: float  # half the kept region's boundary pixels: ±½ pixel across its outline

    def interval(self, widen: float) -> tuple[float, float]:
        """``(lower, upper)`` network pixels; contains ``area`` for any ``widen >= 0``."""
        lower = max(0.0, self.area - widen * (self.area - self.strict + self.edge))
        return lower, self.area + widen * (self.loose - self.area + self.edge)


def convex_region(keep: np.ndarray) -> np.ndarray:
    """The pixels whose centres lie in the convex hull of a region's pixel centres (the
    ``"convex"`` region of :data:`~contactcal.infer.methods.unet.spec.REGIONS`).

    Exact, row by row: OpenCV's polygon fill also takes the pixels its outline passes through,
    ~2 % more than the hull holds on a 3500-px region, a bias as large as the errors it is for.

    Args:
        keep: ``(S, S) bool`` region (one connected component, or empty).

    Returns:
        ``(S, S) bool`` containing ``keep``; empty for an empty ``keep``.
    """
    out = np.zeros(keep.shape, bool)
    contours, _ = cv2.findContours(
        keep.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    if not contours:
        return out
    a = cv2.convexHull(np.concatenate(contours))[:, 0, :].astype(np.float64)  # (K, 2) x, y
    b = np.roll(a, -1, axis=0)  # each vertex's successor: the hull's edges a → b
    rows = np.arange(int(a[:, 1].min()), int(a[:, 1].max()) + 1)[:, None]  # (R, 1)
    dy = b[:, 1] - a[:, 1]
    on = (rows >= np.minimum(a[:, 1], b[:, 1])) & (rows <= np.maximum(a[:, 1], b[:, 1]))
    t = np.where(dy != 0.0, (rows - a[:, 1]) / np.where(dy != 0.0, dy, 1.0), 0.0)
    x = a[:, 0] + t * (b[:, 0] - a[:, 0])  # (R, K) where each edge meets each row
    lo = np.ceil(np.where(on, x, np.inf).min(axis=1) - 1e-9)[:, None]
    hi = np.floor(np.where(on, x, -np.inf).max(axis=1) + 1e-9)[:, None]
    cols = np.arange(keep.shape[1])[None, :]
    out[rows[:, 0]] = (cols >= lo) & (cols <= hi)
    return out | keep


def region_perimeter(keep: np.ndarray, convex: bool) -> float:
    """The outline length of a region counted in whole pixels, network pixels.

    The outline through the boundary pixels' centres (the convex hull's for a convex region, the
    traced contour's otherwise) lies half a pixel inside the counted pixels' edge; its parallel
    curve half a pixel out is ``2π · ½`` longer for a convex outline, which is added. For a
    non-convex region the traced contour, simplified to within 1 px (its pixel staircase
    would add ~6 %), is an estimate: within ~1-2 % on discs and ellipses of radius >= 20 px.

    Args:
        keep: ``(S, S) bool`` region (one connected component, or empty).
        convex: the region is the convex hull of its pixel centres (:func:`convex_region`).

    Returns:
        Length in network pixels; 0.0 for an empty region.
    """
    contours, _ = cv2.findContours(keep.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return 0.0
    if convex:
        return float(cv2.arcLength(cv2.convexHull(np.concatenate(contours)), True)) + np.pi
    outline = cv2.approxPolyDP(max(contours, key=cv2.contourArea), 1.0, True)  # no staircase
    return float(cv2.arcLength(outline, True)) + np.pi


def boundary_band(
    prob: np.ndarray, keep: np.ndarray, interval: IntervalSpec, min_area: float
) -> Band:
    """Measure the contact region at the interval's stricter and looser thresholds.

    Args:
        prob: ``(S, S) float32`` probabilities (0 outside the image).
        keep: ``(S, S) bool`` contact region, the kept region or its convex hull (empty: the
            frame is called "no contact").
        interval: the two thresholds.
        min_area: network pixels, the spec's minimum contact area.

    Returns:
        The band. With a contact region, ``loose`` is the union of that region and every
        connected region at ``threshold_low`` it touches, whole (for a region as segmented: the
        one that contains it; a hull may reach into further, detached ones). Without one (no
        contact, area 0), ``loose`` is the largest region at ``threshold_low`` if it covers at
        least ``min_area`` (and one pixel), else 0: the interval is then ``(0, widen·loose)``,
        i.e. ``(0, 0)`` when nothing looser is found.
    """
    n, labels, stats, _ = cv2.connectedComponentsWithStats(
        (prob >= interval.threshold_low).astype(np.uint8), connectivity=8
    )
    area = float(keep.sum())
    if area == 0.0:
        big = float(stats[1:, cv2.CC_STAT_AREA].max()) if n > 1 else 0.0
        return Band(0.0, 0.0, big if big >= max(min_area, 1.0) else 0.0, 0.0)
    # Components are disjoint: their areas add up, plus the region's pixels outside all of them.
    # The labels (>= 0) the region touches; bincount, not np.unique (which imports numpy.ma,
    # ~20 ms of every command's start-up).
    touched = np.flatnonzero(np.bincount(labels[keep], minlength=n))
    touched = touched[touched > 0]
    loose = float(stats[touched, cv2.CC_STAT_AREA].sum() + (keep & (labels == 0)).sum())
    strict = float((keep & (prob >= interval.threshold_high)).sum())
    inner = cv2.erode(keep.astype(np.uint8), np.ones((3, 3), np.uint8), borderValue=0)
    return Band(area, strict, max(loose, area), 0.5 * (area - float(inner.sum())))


@dataclass(frozen=True)
class Segmentation:
    """One frame's prediction. Areas in input pixels."""

    contact: bool
    area_px: float  # the contact region: the largest region above the threshold, or its convex
    #   hull (spec.region); 0.0 without contact
    soft_area_px: float  # probabilities summed around the region, hull pixels as 1 (sub-pixel)
    region_net_px: float  # network pixels of the largest region (before the minimum-area test)
    prob: np.ndarray  # (S, S) float32 probabilities in network pixels (0 outside the image)
    mask_net: np.ndarray  # (S, S) bool, the contact region in network pixels
    box: CropBox  # crop that maps network pixels to input pixels
    #: The stated interval of the area, input pixels (None when the spec has no interval).
    interval_px: tuple[float, float] | None = None
    #: The kept region's mean |frame − reference| (network input units; :func:`region_change`),
    #: None when not measured (no reference frame, or no region of the minimum area).
    change: float | None = None
    #: True when the change gate (``spec.min_change``) turned a kept region into "no contact".
    unchanged: bool = False
    #: The contact region's outline length, input pixels (:func:`region_perimeter`; 0.0
    #: without contact): what a boundary offset changes the area by, per pixel of offset.
    perimeter_px: float = 0.0
    #: False when the crop came from no window ring (neither the reference's nor the frame's:
    #: the image centre's fallback box); set by the runner, which knows the crop's source.
    ring_found: bool = True


def region_change(difference: np.ndarray, keep: np.ndarray) -> float:
    """The change of a region against the session's zero-pressure frame.

    Args:
        difference: ``(S, S) float32`` |frame channel − reference channel|, network input units.
        keep: ``(S, S) bool`` the kept region (non-empty).

    Returns:
        The mean of ``difference`` over ``keep`` (network input units, >= 0).
    """
    return float(difference[keep].mean())


def _gate(
    difference: np.ndarray | None, keep: np.ndarray, min_change: float
) -> tuple[float | None, bool]:
    """``(change, unchanged)`` of a kept region: its :func:`region_change` (None without a
    difference or a region) and whether that is below ``min_change`` (never, when None)."""
    change = None if difference is None or not keep.any() else region_change(difference, keep)
    return change, change is not None and change < min_change


def _largest_region(
    prob: np.ndarray, box: CropBox, shape: tuple[int, int], threshold: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(prob, keep)``: the ``(S, S) float32`` probabilities with the network pixels outside
    the image set to 0, and the ``(S, S) bool`` largest 8-connected region at or above
    ``threshold`` (all False when there is none)."""
    inside = np.zeros(prob.shape, bool)
    inside[valid_window(box, shape, prob.shape[0])] = True
    prob = np.where(inside, prob, 0.0).astype(np.float32)
    binary = (prob >= threshold).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=8)
    if n <= 1:
        return prob, np.zeros_like(binary, dtype=bool)
    return prob, labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))


def postprocess(
    prob: np.ndarray,
    box: CropBox,
    shape: tuple[int, int],
    spec: ModelSpec,
    difference: np.ndarray | None = None,
) -> Segmentation:
    """Keep the largest connected region above the threshold; decide contact; measure it.

    Network pixels whose centres fall outside the image are ignored (a crop that barely overlaps
    the image may have none inside: then no contact, area 0). Ring reflections and
    sparkle give small or detached specks: only the largest region counts, and only if it covers
    at least ``spec.min_contact_area_px`` network pixels and, when ``difference`` is given, only if
    its :func:`region_change` reaches ``spec.min_change`` (a region that looks as it did in the
    zero-pressure frame is not contact). With ``spec.region == "convex"`` the
    contact region is then that region's :func:`convex_region` (the contact decision is the same;
    the area, the mask, the soft area and the interval are the hull's). When the spec states an
    interval, the area's interval comes from the region's :func:`boundary_band` (``(0, upper)``
    or ``(0, 0)`` without contact).

    Args:
        prob: ``(S, S)`` probabilities in network pixels.
        box: the crop the network input was made with.
        shape: input image ``(H, W)``.
        spec: threshold, minimum area, minimum change, region and interval.
        difference: ``(S, S) float32`` |frame channel − reference channel| (network input units)
            when the session has a reference frame; None without one (no change gate).

    Returns:
        The segmentation; areas and interval in input pixels (network pixels × the crop's
        scale²).
    """
    prob, keep = _largest_region(prob, box, shape, spec.threshold)
    px_per_net = box.scale(prob.shape[0]) ** 2  # input pixels per network pixel
    region_net = float(keep.sum())
    if region_net < spec.min_contact_area_px or region_net == 0.0:
        keep = np.zeros_like(keep)
    change, unchanged = _gate(difference, keep, spec.min_change)
    if unchanged:
        keep = np.zeros_like(keep)
    segmented = keep
    if spec.region == "convex":
        keep = convex_region(keep)  # stays inside the (rectangular) valid window
    interval = None
    if spec.interval is not None:
        band = boundary_band(prob, keep, spec.interval, spec.min_contact_area_px)
        lower, upper = band.interval(spec.interval.widen)
        interval = (lower * px_per_net, upper * px_per_net)
    if not keep.any():
        return Segmentation(
            False, 0.0, 0.0, region_net, prob, keep, box, interval, change, unchanged
        )
    near = cv2.dilate(keep.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    soft = float(np.where(keep & ~segmented, 1.0, prob)[near].sum())  # hull pixels count whole
    scale = box.scale(prob.shape[0])  # input pixels per network pixel, along a side
    perimeter = region_perimeter(keep, spec.region == "convex") * scale
    sizes = (float(keep.sum()) * px_per_net, soft * px_per_net, region_net)
    return Segmentation(True, *sizes, prob, keep, box, interval, change, False, perimeter)


def mask_in_input(seg: Segmentation, shape: tuple[int, int]) -> np.ndarray:
    """``(H, W) bool`` contact mask in input pixels (for overlays and IoU against masks)."""
    return from_network(seg.mask_net.astype(np.float32), seg.box, shape) >= 0.5

"""A rig's boundary offset: where its contact edge lies relative to the U-Net's region, in mm.

Two generators of rig frames can agree on the contact region's shape and disagree on where its
edge lies against the inner ring: on the procedural cross-check frames the shipped U-Net's region
is a near-constant ~0.18 mm (equivalent radius) inside the drawn contact at every pressure, on
our renders within ±0.02 mm (``docs/evaluate.md``, "Boundary offset"). Which holds on a real
rig, only its own hand-labelled frames can tell. ``contactcal evaluate`` measures the offset
against them (:func:`fit_offset`); stored in the rig config with the model it was measured for,
``measure``, ``calibrate`` and ``evaluate`` apply it to that model's areas (:func:`apply_offset`).

The area of a convex region grown outward by ``d`` is ``A + P·d + π·d²`` (Steiner's formula,
``P`` its perimeter); shrunk inward by ``d`` (``d < 0``) the same formula holds while ``|d|`` is
below the outline's smallest radius of curvature (a contact patch's is millimetres, an offset's
tenths of one).
"""

from __future__ import annotations

import math
import numbers
import os
import re
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np

from contactcal.infer.methods.base import AreaResult
from contactcal.infer.pipeline.scale import MODEL_KEY, OFFSET_KEY, read_rig_json

#: Largest |offset| accepted, mm: ten times the generators' disagreement (~0.18 mm), and a
#: tenth of a contact patch's radius; a larger value is a unit or sign slip.
MAX_OFFSET_MM = 2.0
#: The start of the note of a frame whose region an inward offset removed (``calibrate`` looks for
#: it to name the offset when no contact is left).
GONE_NOTE = "no contact: the rig's boundary offset leaves no area"


class BoundaryOffsetError(ValueError):
    """A boundary offset that cannot be used; the message names the file and the fix."""


@dataclass(frozen=True)
class BoundaryOffset:
    """A rig's measured boundary offset, for one model."""

    mm: float  # signed, mm at the contact plane: > 0 moves the edge outward (larger areas)
    model_sha256: str  # the model file it was measured for (64 hex digits)
    source: str  # the rig config file it came from, for messages and records

    def __post_init__(self) -> None:
        m = self.mm
        if isinstance(m, bool) or not isinstance(m, numbers.Real) or not math.isfinite(m):
            raise BoundaryOffsetError(f"{self.source}: {OFFSET_KEY} must be a number, got {m!r}")
        if abs(m) > MAX_OFFSET_MM:
            raise BoundaryOffsetError(
                f"{self.source}: {OFFSET_KEY} {m:g} mm is outside ±{MAX_OFFSET_MM:g} mm; "
                "expected tenths of a mm (as `contactcal evaluate` prints it)"
            )
        if not re.fullmatch(r"[0-9a-f]{64}", str(self.model_sha256)):
            raise BoundaryOffsetError(
                f"{self.source}: {MODEL_KEY} must be the model's sha256 (64 lower-case hex "
                f"digits, as `contactcal evaluate` prints it), got {self.model_sha256!r}"
            )


def rig_boundary(data: dict[str, Any], source: str) -> BoundaryOffset | None:
    """The boundary offset a rig config's JSON object states (None when it states none);
    ``source`` names the file in errors.

    Raises:
        BoundaryOffsetError: only one of the two keys, or an invalid value.
    """
    if OFFSET_KEY not in data and MODEL_KEY not in data:
        return None
    if OFFSET_KEY not in data or MODEL_KEY not in data:
        raise BoundaryOffsetError(
            f"{source}: {OFFSET_KEY} and {MODEL_KEY} go together (the offset holds for one model); "
            "add the missing one as `contactcal evaluate` printed it, or remove both"
        )
    return BoundaryOffset(data[OFFSET_KEY], data[MODEL_KEY], source)


def load_boundary_offset(path: str | os.PathLike[str]) -> BoundaryOffset | None:
    """The boundary offset a rig config file states (None when it states none).

    Raises:
        RigConfigError: the file is missing, unreadable or not a JSON object.
        BoundaryOffsetError: only one of the two keys, or an invalid value.
    """
    return rig_boundary(read_rig_json(path), str(path))


def offset_area(area: float, perimeter: float, d: float) -> float:
    """Area of a convex region of ``area`` and ``perimeter`` moved ``d`` outward (Steiner).

    Units: any length unit ``u`` for ``perimeter`` and ``d``, ``u²`` for ``area``. An inward move
    to the formula's vertex ``−P/2π`` (a circle's radius) or beyond leaves nothing: 0.
    """
    if d <= -perimeter / (2.0 * math.pi):
        return 0.0
    return max(0.0, area + perimeter * d + math.pi * d * d)


def fit_offset(area: float, perimeter: float, target: float) -> float:
    """The outward move ``d`` that gives a region of ``area`` and ``perimeter`` the ``target``
    area (inverse of :func:`offset_area`; same units). A target below what the formula can reach
    (``A − P²/4π``) gives its vertex, ``−P/2π``."""
    disc = perimeter * perimeter + 4.0 * math.pi * (target - area)
    return (-perimeter + math.sqrt(max(disc, 0.0))) / (2.0 * math.pi)


def apply_offset(res: AreaResult, d_px: float, mm: float) -> AreaResult:
    """A frame's result with its contact boundary moved ``d_px`` input pixels outward.

    The area, the soft area and the interval's ends move by :func:`offset_area` (an end's
    perimeter scaled as the square root of its area: a similar shape); the note says so. A
    result without contact, or without a measured perimeter, is returned unchanged. The outline
    (``contour``: overlays, ``evaluate``'s IoU) moves too (:func:`offset_contour`), so that it
    bounds the region whose area is stated.

    An inward move that leaves no area makes the frame "no contact" (:data:`GONE_NOTE`): area
    and soft area 0, no outline, the interval ``(0, its moved upper end)``.

    Args:
        res: the method's result, input pixels.
        d_px: the offset in input pixels (mm ÷ mm per px at the frame's width).
        mm: the same offset in mm, for the note.
    """
    if not res.contact or res.perimeter_px is None or res.area_px <= 0.0:
        return res
    a, p = res.area_px, res.perimeter_px

    def moved(x: float) -> float:
        return offset_area(x, p * math.sqrt(max(x, 0.0) / a), d_px)

    area, iv = moved(a), res.area_interval_px
    interval = None if iv is None else (moved(iv[0]), moved(iv[1]))
    if area <= 0.0:
        note = f"{GONE_NOTE} ({mm:+.3f} mm; the region had {a:.0f} px)"
        upper = None if interval is None else (0.0, interval[1])
        return AreaResult(False, 0.0, note, None, 0.0, upper, 0.0)
    note = f"boundary moved {mm:+.3f} mm (rig's boundary offset): area {a:.0f} → {area:.0f} px"
    return replace(
        res,
        area_px=area,
        contour=None if res.contour is None else offset_contour(res.contour, d_px),
        note=f"{res.note}; {note}" if res.note else note,
        soft_area_px=None if res.soft_area_px is None else moved(res.soft_area_px),
        area_interval_px=interval,
        perimeter_px=p + 2.0 * math.pi * d_px,
    )


def offset_contour(contour: np.ndarray, d_px: float) -> np.ndarray | None:
    """The filled outline moved ``d_px`` outward (inward when negative), as an outline.

    Pixels within ``d_px`` of the filled region are added (``d_px > 0``), or those within
    ``|d_px|`` of its outside removed, by an exact Euclidean distance transform in the outline's
    bounding box; the largest outer boundary of what is left is returned.

    Args:
        contour: ``(N, 1, 2) int32`` outline, input pixels.
        d_px: the move, input pixels.

    Returns:
        ``(M, 1, 2) int32`` outline in the same pixels; None when an inward move leaves nothing.
    """
    x, y, w, h = cv2.boundingRect(contour)
    m = math.ceil(max(d_px, 0.0)) + 2  # room to grow, and a background border
    mask = np.zeros((h + 2 * m, w + 2 * m), np.uint8)
    shift = np.array([x - m, y - m], np.int32)
    cv2.drawContours(mask, [contour.astype(np.int32) - shift], -1, 1, thickness=-1)
    if d_px >= 0:  # distance of each outside pixel to the region
        dist = cv2.distanceTransform(1 - mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        moved = dist <= d_px
    else:  # distance of each inside pixel to the outside
        dist = cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        moved = dist > -d_px
    found, _ = cv2.findContours(moved.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not found:
        return None
    return max(found, key=cv2.contourArea).astype(np.int32) + shift

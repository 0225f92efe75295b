"""Network preprocessing shared by training and deployment (numpy + OpenCV only).

A frame is cropped to a square box centred on the bright outer (window/LGP) ring, resized to
``input_size`` and normalised; the network's probabilities are mapped back to input pixels with
the exact inverse of that crop/resize. Training (``contactcal.train.data``) and deployment use
these same functions, so they cannot drift.

The crop, its pixel convention and the way back to input pixels are
:mod:`~contactcal.infer.methods.unet.crop`.

Normalisation: ``u = clip(crop / P, 0, 1)`` with ``P`` the ``norm_percentile``-th percentile of
the crop's in-image pixels (exposure/gain invariance: the brightest structure, the outer ring,
is in every crop); with ``norm_floor_percentile`` > 0, ``u = clip((crop - F) / (P - F), 0, 1)``,
``F`` that lower percentile (black level and contrast invariance too); then
``x = (u - norm_mean) / norm_std`` with FIXED constants (not the image's own mean/std, which
would depend on the contact size, i.e. on the signal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from contactcal.infer.image.gray import to_gray_u8
from contactcal.infer.image.percentile import percentiles
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox, crop_box, crop_resize, valid_window
from contactcal.infer.methods.unet.ridge import ridge_energy
from contactcal.infer.methods.unet.ring import RingFit, locate_ring

T = TypeVar("T")


@dataclass(frozen=True)
class SessionReference:
    """A session's zero-pressure frame, preprocessed once for all of its frames."""

    gray: np.ndarray | None  # (H, W) uint8 reference frame; None: no reference
    ring: RingFit | None  # its ring (found or fallback); None without a reference
    box: CropBox | None  # the session's crop; None: each frame uses its own ring
    x: np.ndarray | None  # (S, S) float32 reference channel in ``box``; None when box is None


@dataclass(frozen=True)
class Prepared:
    """A frame ready for the network."""

    x: np.ndarray  # (C, S, S) float32; frame[, reference][, ridge energy] (``prepare``)
    box: CropBox
    ring: RingFit


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
    return _to_network(to_gray_u8(gray, name="to_network input"), box, config)[0]


def norm_levels(gray: np.ndarray, box: CropBox, config: PreprocessConfig) -> tuple[float, float]:
    """The grey levels ``(F, F + span)`` that :func:`to_network` maps to 0 and 1 in ``box``.

    Training's camera augmentation (``contactcal.train.augment``) maps its inputs back to grey
    levels with them, so that the floor is taken again after a brightness, contrast or gamma
    change, as deployment takes it on such a frame.

    Args:
        gray: ``(H, W) uint8`` frame.
        box: its crop.
        config: the normalisation.

    Returns:
        ``(F, F + span)``, grey levels 0-255: ``F`` the ``norm_floor_percentile``-th
        percentile (0 without a floor), ``span = max(P - F, 1)``.
    """
    crop = crop_resize(to_gray_u8(gray, name="frame"), box, config.input_size)
    floor, span = _levels(crop, box, gray.shape, config)
    return floor, floor + span


def _levels(
    crop: np.ndarray, box: CropBox, shape: tuple[int, ...], config: PreprocessConfig
) -> tuple[float, float]:
    """``(F, span)`` of a resized crop: percentiles of its in-image pixels."""
    inside = crop[valid_window(box, shape, config.input_size)]
    floor, level = 0.0, 1.0
    # No network pixel inside the image: nothing to normalise to; postprocess then reports no
    # contact (it ignores every network pixel outside the image), so the scale is immaterial.
    if inside.size and config.norm_floor_percentile > 0.0:
        qs = (config.norm_floor_percentile, config.norm_percentile)
        floor, level = (float(v) for v in percentiles(inside, qs))
    elif inside.size:
        level = float(percentiles(inside, (config.norm_percentile,))[0])
    return floor, max(level - floor, 1.0)


def _to_network(
    gray: np.ndarray, box: CropBox, config: PreprocessConfig
) -> tuple[np.ndarray, float]:
    """:func:`to_network` of a ``(H, W) uint8`` frame, and the span ``P - F`` it divided by
    (bright level less dark level; ``F`` is 0 without ``config.norm_floor_percentile``)."""
    crop = crop_resize(gray, box, config.input_size)
    floor, span = _levels(crop, box, gray.shape, config)
    # unit_to_network(clip((crop - F) / span, 0, 1)) in place on the crop (a new float32 array).
    if floor > 0.0:
        crop -= floor
    np.divide(crop, span, out=crop)
    np.clip(crop, 0.0, 1.0, out=crop)
    crop -= config.norm_mean
    crop /= config.norm_std
    return crop, span


def blank_reference(config: PreprocessConfig) -> np.ndarray:
    """``(S, S) float32`` placeholder reference channel: black, in network units.

    What a model trained with reference dropout sees when a session has no zero-pressure frame
    (``PreprocessConfig.no_reference == "blank"``); training substitutes the same plane.
    """
    s = config.input_size
    return np.full((s, s), unit_to_network(0.0, config), np.float32)


def session_reference(
    reference: np.ndarray | None, config: PreprocessConfig = PreprocessConfig()
) -> SessionReference:
    """What a session's zero-pressure frame fixes for all of its frames (computed once).

    Args:
        reference: ``(H, W) uint8`` zero-pressure frame, or None (each frame then finds its own
            ring, and a 2-channel model gets the frame itself as its reference channel).
        config: preprocessing.

    Returns:
        The reference's ring and, when the ring was found, the session's crop and reference
        channel.

    Raises:
        ValueError: not an image.
    """
    if reference is None:
        return SessionReference(None, None, None, None)
    gray = to_gray_u8(reference, name="reference frame")
    ring = locate_ring(gray, config)
    if not ring.found:
        return SessionReference(gray, ring, None, None)
    box = crop_box(ring, gray.shape, config)
    return SessionReference(gray, ring, box, to_network(gray, box, config))


def prepare(
    gray: np.ndarray,
    reference: SessionReference,
    config: PreprocessConfig,
    channels: int,
) -> Prepared:
    """Full preprocessing of one frame: the one path of training, validation and deployment.

    The crop comes from the reference's ring (fixed in a session; the reference has no contact
    to confuse the search). When the reference has no ring, or there is no reference, the
    frame's own ring is used (and if the frame has none either, the reference's fallback box).

    Args:
        gray: ``(H, W) uint8`` frame.
        reference: from :func:`session_reference` (same image size as ``gray``).
        config: preprocessing.
        channels: 1 (frame) or 2 (frame, reference; without a reference frame, the frame itself
            or :func:`blank_reference`, as ``config.no_reference`` says), plus 1 when
            ``config.ridge_work_px > 0``: the frame's ridge energy
            (:func:`~contactcal.infer.methods.unet.ridge.ridge_energy`), always last.

    Returns:
        :class:`Prepared` with ``x`` of shape ``(channels, S, S)``.

    Raises:
        ValueError: bad image, or a reference of a different size than the frame.
    """
    gray = to_gray_u8(gray, name="frame")
    if reference.gray is not None and reference.gray.shape != gray.shape:
        raise ValueError(
            f"reference frame size {reference.gray.shape[1]}×{reference.gray.shape[0]} differs "
            f"from the frame size {gray.shape[1]}×{gray.shape[0]}"
        )
    box, ring, ref_x = reference.box, reference.ring, reference.x
    if box is None or ring is None:
        own = locate_ring(gray, config)
        ring = own if own.found or ring is None else ring
        box = crop_box(ring, gray.shape, config)
    x, span = _to_network(gray, box, config)
    chans = [x]
    ridge = config.ridge_work_px > 0
    if channels - ridge not in (1, 2):
        raise ValueError(
            f"channels must be {1 + ridge} or {2 + ridge} with ridge_work_px "
            f"{config.ridge_work_px}, got {channels}"
        )
    if channels - ridge == 2:
        if ref_x is None and reference.gray is not None:
            ref_x = to_network(reference.gray, box, config)
        elif ref_x is None:
            ref_x = x if config.no_reference == "self" else blank_reference(config)
        chans.append(ref_x)
    if ridge:
        work = crop_resize(gray, box, config.ridge_work_px)
        chans.append(ridge_energy(work, config, span))
    return Prepared(np.stack(chans), box, ring)


def reference_difference(
    x: np.ndarray, reference: SessionReference, uses_reference: bool
) -> np.ndarray | None:
    """|frame channel − reference channel| of a prepared input, when there is a reference frame.

    What the change gate (``ModelSpec.min_change``, :func:`~contactcal.infer.methods.unet.
    postprocess.postprocess`) measures a kept region with.

    Args:
        x: ``(C, S, S)`` network input from :func:`prepare`.
        reference: the session's reference (:func:`session_reference`).
        uses_reference: whether channel 1 is a reference channel (``ModelSpec.uses_reference``).

    Returns:
        ``(S, S) float32`` in network input units, or None when the model has no reference
        channel or the session no reference frame (its reference channel is then the frame
        itself or a blank plane: nothing to compare with).
    """
    if not uses_reference or reference.gray is None:
        return None
    return np.abs(x[0] - x[1])

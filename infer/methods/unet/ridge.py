"""The ridge-energy channel: fingerprint-ridge contrast measured finer than the network input.

Fingerprint ridges are the evidence that defines contact, but at a 192² input they sit near the
sampling limit (period ~2.8 network pixels across 2.2 ring radii). This channel measures them at
``ridge_work_px`` (the crop resampled to that side, where the period is ~4-5 px), then shrinks
the result to the network input:

1. crop the frame on the session's box and resample it to ``W = ridge_work_px`` (INTER_AREA when
   shrinking a 2592-wide frame, linear when enlarging a 400-wide render), normalised by the
   same percentile as the frame channel (``norm_percentile``: exposure invariant);
2. band-pass at the ridge frequency: difference of Gaussians σ ``ridge_sigma_fine_px`` −
   ``ridge_sigma_coarse_px`` (work pixels; the DoG passes periods of ~3-7 px at W = 288);
3. local energy: square, Gaussian smoothing σ ``ridge_smooth_px`` (work px), square root (RMS
   ridge amplitude, in units of the crop's bright level);
4. area-resize to ``(S, S)`` and divide by ``ridge_norm`` (the typical RMS inside a contact, so
   values are ~1 on ridges and ~0 on a smooth membrane).

The window ring's edges and coating sparkle pass the band too; the network learns to tell them
apart, this channel only makes the ridges visible at its input size.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from contactcal.infer.methods.unet.config import PreprocessConfig


def ridge_energy(work: np.ndarray, config: PreprocessConfig, reference_level: float) -> np.ndarray:
    """The ridge-energy channel of one frame (steps 2-4; ``prepare`` does step 1).

    Args:
        work: ``(W, W) float32`` the frame's crop resampled to ``W = config.ridge_work_px``
            (``crop.crop_resize``), grey levels.
        config: ``ridge_work_px`` (> 0), the band and the normalisation.
        reference_level: the span the frame channel was divided by, grey levels: the crop's
            bright level ``P``, less its dark floor ``F`` with ``config.norm_floor_percentile``
            (``P − F``); energies are relative to it.

    Returns:
        ``(S, S) float32`` ridge energy in network units (≥ 0), ``S = config.input_size``.

    Raises:
        ValueError: the config has no ridge channel, or ``work`` is not ``(W, W)``.
    """
    w = config.ridge_work_px
    if w <= 0:
        raise ValueError("ridge_energy: config.ridge_work_px is 0 (no ridge channel)")
    if work.shape != (w, w):
        raise ValueError(f"ridge_energy: expected a ({w}, {w}) crop, got shape {work.shape}")
    # Three (W, W) buffers, reused in place: fresh arrays of this size cost page faults.
    work = np.divide(work, max(float(reference_level), 1.0), dtype=np.float32)
    fine = cv2.GaussianBlur(work, (0, 0), config.ridge_sigma_fine_px)
    coarse = cv2.GaussianBlur(work, (0, 0), config.ridge_sigma_coarse_px)
    band = np.subtract(fine, coarse, out=fine)
    np.multiply(band, band, out=band)
    energy = cv2.GaussianBlur(band, (0, 0), config.ridge_smooth_px, dst=coarse)
    np.sqrt(energy, out=energy)
    s = config.input_size
    interp = cv2.INTER_AREA if w > s else cv2.INTER_LINEAR
    small = cv2.resize(energy, (s, s), interpolation=interp)
    small /= config.ridge_norm
    return small


def ridge_band_frequency(config: PreprocessConfig) -> float:
    """Centre of the ridge band: the frequency where the difference of Gaussians peaks.

    The DoG ``exp(-a f²) - exp(-b f²)`` (``a, b = 2π² σ²`` of the fine and coarse σ) peaks at
    ``f² = ln(b / a) / (b - a)``; at the default σ 0.6 / 1.3 px that is 0.243 cycles per work px,
    a period of 4.1 px at ``ridge_work_px`` = 288 (2.7 px at a 192² input).

    Args:
        config: the ridge band (``ridge_sigma_fine_px`` < ``ridge_sigma_coarse_px``).

    Returns:
        Frequency in cycles per work pixel (> 0).
    """
    a = 2.0 * math.pi**2 * config.ridge_sigma_fine_px**2
    b = 2.0 * math.pi**2 * config.ridge_sigma_coarse_px**2
    return math.sqrt(math.log(b / a) / (b - a))

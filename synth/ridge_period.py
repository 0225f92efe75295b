"""Dominant ridge period of an image patch (measures fingerprint textures and rendered frames)."""

from __future__ import annotations

import math

import numpy as np


def _require(ok: bool, msg: str) -> None:
    """Raise ``ValueError`` naming this function and file unless ``ok``."""
    if not ok:
        raise ValueError(f"ridge_period_px (synth/ridge_period.py): {msg}")


def ridge_period_px(
    image: np.ndarray,
    min_period_px: float = 2.5,
    max_period_px: float | None = None,
    mask: np.ndarray | None = None,
) -> float:
    """Dominant ridge period of a 2D patch from its radially averaged power spectrum.

    The patch is de-trended (best-fit plane removed over ``mask``, so the mean and lighting
    gradients go), weighted by a Hann window (times ``mask``), zero-padded (finer frequency
    sampling) and Fourier transformed; the peak of the radially averaged power between
    ``min_period_px`` and ``max_period_px`` is located and the frequency is taken as the centroid
    of that peak's lobe above 30 % of its height (robust to lumpy spectra of curved ridges).

    Args:
        image: ``(H, W)`` real array, any dtype; ``H, W >= 8``.
        min_period_px: shortest period considered (px).
        max_period_px: longest period considered (px); default ``min(H, W) / 2``.
        mask: optional ``(H, W)`` bool/float weights, e.g. the contact region of a render.

    Returns:
        Period in pixels (float).

    Raises:
        ValueError: not a finite 2D patch of at least 8x8 px (or a mask of another shape), an
            empty band, or no texture in the band.
    """
    a = np.asarray(image, dtype=np.float64)
    ok = a.ndim == 2 and min(a.shape) >= 8 and bool(np.isfinite(a).all())
    _require(ok, f"expected a finite 2D patch >= 8x8 px, got shape {a.shape}")
    h, w = a.shape
    wt = np.ones((h, w)) if mask is None else np.asarray(mask, dtype=np.float64)
    _require(wt.shape == (h, w) and wt.sum() > 0, f"mask must be a non-empty {(h, w)}")
    hi = min(h, w) / 2 if max_period_px is None else max_period_px
    _require(0 < min_period_px < hi, f"need 0 < min < max period, got {min_period_px}, {hi}")
    yy, xx = np.mgrid[0:h, 0:w]
    design = np.stack([np.ones(h * w), xx.ravel(), yy.ravel()], axis=1)
    sw = np.sqrt(wt.ravel())
    coef = np.linalg.lstsq(design * sw[:, None], a.ravel() * sw, rcond=None)[0]
    a = (a - (design @ coef).reshape(h, w)) * wt * np.outer(np.hanning(h), np.hanning(w))
    size = 1 << max(9, math.ceil(math.log2(2 * max(h, w))))
    power = np.abs(np.fft.rfft2(a, s=(size, size))) ** 2
    fy, fx = np.fft.fftfreq(size)[:, None], np.fft.rfftfreq(size)[None, :]
    radius = np.rint(np.hypot(fx, fy) * size).astype(np.intp).ravel()
    prof = np.bincount(radius, power.ravel()) / np.maximum(np.bincount(radius), 1)
    k_lo, k_hi = max(1, math.ceil(size / hi)), min(len(prof) - 2, int(size / min_period_px))
    ok = k_hi > k_lo and prof[k_lo : k_hi + 1].max() > 1e-12 * power.sum()
    _require(bool(ok), "patch has no periodic texture in the period band")
    k = k_lo + int(np.argmax(prof[k_lo : k_hi + 1]))
    thr, i0, i1 = 0.3 * prof[k], k, k  # centroid of the peak's lobe above 30 % of its height
    while i0 > k_lo and prof[i0 - 1] >= thr:
        i0 -= 1
    while i1 < k_hi and prof[i1 + 1] >= thr:
        i1 += 1
    wts = prof[i0 : i1 + 1] - thr
    return float(size * wts.sum() / (np.arange(i0, i1 + 1) * wts).sum())

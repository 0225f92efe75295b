"""The camera: coating sparkle and grain, vignetting, blur, exposure, tone curve, colour,
sensor noise and a JPEG round trip.

Own camera model (not the renderer's): a soft exponential tone curve instead of a gamma, a fixed
sparkle of coating particles per session, Poisson-like shot noise plus Gaussian read noise in
8-bit units, then a JPEG encode/decode (the dataset stores PNG files holding JPEG artefacts).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from contactcal.synth.procedural.grid import Grid, smooth_field
from contactcal.synth.procedural.session import Finger

#: Tone curve steepness: ``out = (1 − e^(−k·L)) / (1 − e^(−k))``, clipped at white.
TONE_K = 2.2
#: Width the ``blur_px`` ranges refer to, px.
BLUR_REF_WIDTH = 400
#: Mean sparkle peak, linear intensity (exponentially distributed).
SPARKLE_MEAN = 0.35
#: Sparkle spot size (Gaussian sigma), output px.
SPARKLE_SIGMA_PX = 0.6


@dataclass(frozen=True)
class Optics:
    """A session's fixed image-plane layers, on the supersampled grid."""

    vignette: np.ndarray  # (H·ss, W·ss) float32 gain in (0, 1]
    sparkle: np.ndarray  # (H·ss, W·ss) float32 added intensity
    grain: np.ndarray  # (H·ss, W·ss) float32 multiplicative gain around 1
    tint: tuple[float, float, float]  # R, G, B gains


def session_optics(grid: Grid, finger: Finger) -> Optics:
    """The fixed layers of one session (from the finger's ``texture_seed``)."""
    rng = np.random.default_rng([finger.texture_seed, 2])
    v = finger.values
    corner = float(grid.r.max())
    vignette = 1.0 - v["vignetting"] * (grid.r / corner) ** 2
    inside = grid.r < v["window_radius_mm"]
    area_mm2 = float(inside.sum()) * grid.mm_per_sample**2
    n = int(rng.poisson(v["sparkle_per_mm2"] * area_mm2))
    sparkle = np.zeros(grid.x.shape, np.float32)
    ys, xs = np.nonzero(inside)
    if n and len(ys):
        pick = rng.integers(0, len(ys), n)
        sigma = SPARKLE_SIGMA_PX * grid.ss
        # A delta blurred by a Gaussian keeps its sum: scale it so the peak is the drawn value.
        sparkle[ys[pick], xs[pick]] = rng.exponential(SPARKLE_MEAN, n) * 2 * np.pi * sigma**2
        sparkle = cv2.GaussianBlur(sparkle, (0, 0), sigma)
    grain = 1.0 + v["grain"] * smooth_field(rng, grid.x.shape, 1.5)
    tint = (float(rng.uniform(0.97, 1.06)), 1.0, float(rng.uniform(0.9, 1.02)))
    return Optics(vignette.astype(np.float32), sparkle, grain.astype(np.float32), tint)


def expose(
    linear: np.ndarray, optics: Optics, finger: Finger, ss: int, rng: np.random.Generator
) -> np.ndarray:
    """Turn supersampled linear intensity into the saved frame.

    Args:
        linear: (H·ss, W·ss) float32 scene intensity, 1.0 = white.
        optics: the session's fixed layers.
        finger: the session (exposure, blur, noise, JPEG quality).
        ss: supersampling factor of ``linear``.
        rng: per-frame randomness (noise).

    Returns:
        (H, W, 3) uint8 RGB.
    """
    v = finger.values
    img = (linear * optics.vignette + optics.sparkle) * optics.grain
    h, w = img.shape[0] // ss, img.shape[1] // ss
    if ss > 1:
        img = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)
    sigma = v["blur_px"] * w / BLUR_REF_WIDTH
    if sigma > 0.05:
        img = cv2.GaussianBlur(img, (0, 0), sigma)
    tone = (1.0 - np.exp(-TONE_K * v["exposure"] * np.maximum(img, 0.0))) / (1.0 - np.exp(-TONE_K))
    dn = 255.0 * np.clip(tone, 0.0, 1.0)[:, :, None] * np.asarray(optics.tint, np.float32)
    noise = rng.standard_normal(dn.shape) * np.sqrt(
        (v["shot_noise"] ** 2) * dn + v["read_noise"] ** 2
    )
    rgb = np.clip(np.rint(dn + noise), 0, 255).astype(np.uint8)
    return jpeg_round_trip(rgb, round(v["jpeg_quality"]))


def jpeg_round_trip(rgb: np.ndarray, quality: int) -> np.ndarray:
    """(H, W, 3) uint8 RGB after JPEG encoding at ``quality`` and decoding."""
    ok, buf = cv2.imencode(".jpg", rgb[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise OSError("JPEG encoding failed")
    bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return np.ascontiguousarray(bgr[:, :, ::-1])

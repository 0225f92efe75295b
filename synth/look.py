"""Appearance beyond the nominal camera (synthetic world v2): image-space look effects.

Pure numpy/OpenCV functions on the linear frame (after the render, before the sensor noise) and
on the display-referred frame (after gamma, before quantisation). None of them touches the mask:
they change how the rig looks, never where the contact is. ``apply_camera`` (``camera.py``)
calls them in a physical order: optics on linear radiance first (vignetting, stray glare, dust,
motion blur next to the defocus), then sensor noise, white balance / colour cast, gamma, tone
curve, quantisation and JPEG. Ranges and their reasons: ``docs/synth.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

REFERENCE_WIDTH_PX = 400  # dust radii are given at this image width and scale with it


@dataclass(frozen=True)
class LookEffects:
    """One session's look effects (default: no effect; all sampled in ``randomize.py``)."""

    vignetting: float = 0.0  # k of the gain 1 - k r² (r = 1 at the half-diagonal); darkens the
    #   corners, so the window ring's outer part reads dimmer than its centre (0.4 → 60 %)
    vignette_centre: tuple[float, float] = (0.0, 0.0)  # falloff centre offset, × image width;
    #   lens decentring: the dark side differs from frame to frame of a rig, not within one
    wb_gains: tuple[float, float, float] = (1.0, 1.0, 1.0)  # × linear R, G, B after the noise;
    #   white balance / colour cast; ±25 % turns the white ring pink or cyan, hue is no cue
    tone_strength: float = 0.0  # 0-1 blend towards a smoothstep S-curve on the display values;
    #   more contrast in mid-tones, crushed shadows and highlights (faint ridges fade or pop)
    motion_blur_px: float = 0.0  # length of a linear blur kernel, px (at a 400-px-wide frame
    #   through ``CameraEffects.at_width``); smears ridges along one direction (period ~4 px at
    #   400 wide), so 3 px is a visible but not total loss
    motion_blur_deg: float = 0.0  # direction of the motion blur, degrees from the image x axis
    dust_count: int = 0  # small blurred specks on the window (80 % dark, 20 % bright); radius
    #   1-4 px at 400 px width; they mimic pores/scars, so the segmenter must ignore them
    stray_amplitude: float = 0.0  # peak of a soft bright glare streak, fraction of white;
    #   lifts the dark membrane locally (15 % ≈ half the routine's threshold margin)
    #: One bright speck on the window near the image centre, where the first contact appears
    #: (``DatasetConfig.speck_fraction``, opt-in): ``(strength, radius, x, y)`` = peak in
    #: fraction of white (0 = none), radius px at 400 px width, centre offset from the image
    #: centre × the image height. Uniformly placed dust is rarely there, and the shipped model
    #: takes such a speck for contact before contact (models/MODEL_CARD.md, "Limits").
    centre_speck: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    seed: int = 0  # places the dust and the glare; fixed per session (they sit on the window)

    def __post_init__(self) -> None:
        """Reject out-of-range settings (raises ``ValueError`` naming ``synth/look.py``)."""
        checks = [
            (0.0 <= self.vignetting < 1.0, "vignetting must be in [0, 1)"),
            (len(self.vignette_centre) == 2, "vignette_centre must be (x, y)"),
            (all(abs(c) <= 0.5 for c in self.vignette_centre), "vignette_centre within ±0.5"),
            (len(self.wb_gains) == 3, "wb_gains must be (r, g, b)"),
            (all(math.isfinite(g) and g > 0 for g in self.wb_gains), "wb_gains must be > 0"),
            (0.0 <= self.tone_strength <= 1.0, "tone_strength must be in [0, 1]"),
            (0.0 <= self.motion_blur_px <= 50.0, "motion_blur_px must be in [0, 50]"),
            (math.isfinite(self.motion_blur_deg), "motion_blur_deg must be finite"),
            (0 <= self.dust_count <= 1000, "dust_count must be in [0, 1000]"),
            (0.0 <= self.stray_amplitude <= 1.0, "stray_amplitude must be in [0, 1]"),
            (len(self.centre_speck) == 4, "centre_speck must be (strength, radius, x, y)"),
            (0.0 <= self.centre_speck[0] <= 1.0, "centre_speck strength must be in [0, 1]"),
            (0.0 <= self.centre_speck[1] <= 50.0, "centre_speck radius must be in [0, 50] px"),
            (all(abs(c) <= 0.5 for c in self.centre_speck[2:]), "centre_speck x, y within ±0.5"),
            (self.seed >= 0, "seed must be >= 0"),
        ]
        for ok, what in checks:
            if not ok:
                raise ValueError(f"synth/look.py: LookEffects.{what}, got {self!r}")


def vignette_gain(
    height: int, width: int, strength: float, centre: tuple[float, float] = (0.0, 0.0)
) -> np.ndarray:
    """Radial falloff ``max(1 - strength r², 0)``, r = 1 at the corner pixels' centres.

    Args:
        height, width: image size, px.
        strength: k of the falloff, 0 = none.
        centre: offset of the falloff centre from the image centre, × image width.

    Returns:
        ``(H, W, 1) float32`` gain in [0, 1].
    """
    cx = (width - 1) / 2 + centre[0] * width
    cy = (height - 1) / 2 + centre[1] * width
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    r2 = ((x - cx) ** 2 + (y - cy) ** 2) / max(0.25 * ((width - 1) ** 2 + (height - 1) ** 2), 1.0)
    return np.maximum(1.0 - strength * r2, 0.0)[:, :, None].astype(np.float32)


def _gaussian_blob(
    height: int, width: int, centre: tuple[float, float], sigmas: tuple[float, float], angle: float
) -> np.ndarray:
    """``(H, W) float32`` anisotropic Gaussian, peak 1, sigmas in px, angle in radians."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    dx, dy = x - centre[0], y - centre[1]
    u = dx * math.cos(angle) + dy * math.sin(angle)
    v = -dx * math.sin(angle) + dy * math.cos(angle)
    return np.exp(-0.5 * ((u / sigmas[0]) ** 2 + (v / sigmas[1]) ** 2)).astype(np.float32)


def add_stray_glare(img: np.ndarray, amplitude: float, rng: np.random.Generator) -> np.ndarray:
    """Add a faint soft bright streak (stray reflection) to a linear frame.

    Args:
        img: ``(H, W, 3) float32`` linear radiance, 1.0 = white.
        amplitude: peak added radiance, fraction of white.
        rng: places, sizes and turns the streak (3-6 generator calls).

    Returns:
        ``(H, W, 3) float32`` linear radiance (a new array).
    """
    h, w = img.shape[:2]
    centre = (rng.uniform(0.1, 0.9) * w, rng.uniform(0.1, 0.9) * h)
    sigmas = (rng.uniform(0.08, 0.25) * w, rng.uniform(0.02, 0.06) * w)
    blob = _gaussian_blob(h, w, centre, sigmas, rng.uniform(0.0, math.pi))
    return img + (amplitude * blob)[:, :, None]


def add_dust(img: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Add ``count`` small blurred specks (80 % dark, 20 % bright) to a linear frame.

    Radii are 1-4 px at 400 px width and scale with the width. Dark specks attenuate (dust
    shading the window) by 30-80 %; bright ones add 10-40 % of white (light scattered by it).

    Args:
        img: ``(H, W, 3) float32`` linear radiance, 1.0 = white.
        count: number of specks.
        rng: places and sizes the specks (5 generator calls per speck).

    Returns:
        ``(H, W, 3) float32`` linear radiance (a new array).
    """
    h, w = img.shape[:2]
    attenuation = np.zeros((h, w), np.float32)
    glow = np.zeros((h, w), np.float32)
    scale = w / REFERENCE_WIDTH_PX
    for _ in range(count):
        centre = (rng.uniform(0, w), rng.uniform(0, h))
        sigma = max(rng.uniform(1.0, 4.0) * scale, 0.3) / 1.5  # radius ≈ 1.5 sigma
        bright = rng.random() < 0.2
        strength = rng.uniform(0.1, 0.4) if bright else rng.uniform(0.3, 0.8)
        blob = strength * _gaussian_blob(h, w, centre, (sigma, sigma), 0.0)
        if bright:
            glow += blob
        else:
            attenuation = np.maximum(attenuation, blob)
    return img * (1.0 - attenuation)[:, :, None] + glow[:, :, None]


def add_centre_speck(img: np.ndarray, speck: tuple[float, float, float, float]) -> np.ndarray:
    """Add one bright speck (light scattered by dust on the window) near the image centre.

    Args:
        img: ``(H, W, 3) float32`` linear radiance, 1.0 = white.
        speck: ``LookEffects.centre_speck``: peak (fraction of white), radius (px at 400 px
            width, scaled with the width; ≈ 1.5 σ of the Gaussian, as ``add_dust``'s), centre
            offset from the image centre (× the image height).

    Returns:
        ``(H, W, 3) float32`` linear radiance (a new array; ``img`` itself when the peak is 0).
    """
    strength, radius, x, y = speck
    if strength <= 0.0:
        return img
    h, w = img.shape[:2]
    centre = ((w - 1) / 2.0 + x * h, (h - 1) / 2.0 + y * h)
    sigma = max(radius * w / REFERENCE_WIDTH_PX, 0.3) / 1.5
    blob = strength * _gaussian_blob(h, w, centre, (sigma, sigma), 0.0)
    return img + blob[:, :, None]


def motion_kernel(length_px: float, angle_deg: float) -> np.ndarray:
    """``(k, k) float32`` linear motion-blur kernel (sums to 1), anti-aliased.

    Args:
        length_px: length of the smear, px (0 → an identity kernel).
        angle_deg: its direction, degrees from the image x axis.
    """
    c = math.ceil(length_px / 2) + 1  # centre; a one-pixel margin keeps the splat inside
    kernel = np.zeros((2 * c + 1, 2 * c + 1), np.float32)
    a = math.radians(angle_deg)
    for t in np.linspace(-length_px / 2, length_px / 2, 8 * math.ceil(length_px) + 1):
        x, y = c + t * math.cos(a), c + t * math.sin(a)
        x0, y0 = math.floor(x), math.floor(y)
        fx, fy = x - x0, y - y0
        kernel[y0, x0] += (1 - fx) * (1 - fy)
        kernel[y0, x0 + 1] += fx * (1 - fy)
        kernel[y0 + 1, x0] += (1 - fx) * fy
        kernel[y0 + 1, x0 + 1] += fx * fy
    return kernel / kernel.sum()


def motion_blur(img: np.ndarray, length_px: float, angle_deg: float) -> np.ndarray:
    """Blur ``(H, W, 3) float32`` linear radiance along a line (see ``motion_kernel``)."""
    if length_px <= 0:
        return img
    k = motion_kernel(length_px, angle_deg)
    return cv2.filter2D(img, -1, k, borderType=cv2.BORDER_REFLECT)


def tone_curve(display: np.ndarray, strength: float) -> np.ndarray:
    """S-curve ``(1 - s) x + s (3x² - 2x³)``: monotone for s in [0, 1], fixes 0 and 1.

    Args:
        display: ``(H, W, 3) float32`` display-referred values in [0, 1] (after gamma).
        strength: s, 0 = identity.

    Returns:
        Same shape, in [0, 1].
    """
    x = np.clip(display, 0.0, 1.0)
    return (1.0 - strength) * x + strength * (x * x * (3.0 - 2.0 * x))


def apply_optics(img: np.ndarray, look: LookEffects) -> np.ndarray:
    """Vignetting, stray glare, dust and the centre speck on ``(H, W, 3) float32`` linear radiance.

    The dust and glare are placed by ``default_rng(look.seed)``: they sit on the window, so
    they stay put over a session's frames (the per-frame generator only drives the noise).
    """
    h, w = img.shape[:2]
    if look.vignetting > 0:
        img = img * vignette_gain(h, w, look.vignetting, look.vignette_centre)
    if look.stray_amplitude > 0 or look.dust_count > 0:
        rng = np.random.default_rng(look.seed)
        if look.stray_amplitude > 0:
            img = add_stray_glare(img, look.stray_amplitude, rng)
        if look.dust_count > 0:
            img = add_dust(img, look.dust_count, rng)
    img = add_centre_speck(img, look.centre_speck)
    return motion_blur(img, look.motion_blur_px, look.motion_blur_deg)


def apply_white_balance(img: np.ndarray, gains: tuple[float, float, float]) -> np.ndarray:
    """Scale ``(H, W, 3) float32`` linear R, G, B by ``gains`` (white balance / colour cast)."""
    if gains == (1.0, 1.0, 1.0):
        return img
    return img * np.asarray(gains, np.float32)

"""Image perturbations of the robustness suite (``contactcal bench --robustness``).

Each is a pure function ``(gray (H, W) uint8, level, rng) -> gray uint8``, deterministic for a
given ``numpy.random.Generator`` state, returning a new array (the input is never modified) and
the input's values unchanged at the perturbation's ``baseline`` level. Three need the session's
window ring (located by :func:`~contactcal.infer.methods.unet.ring.locate_ring` on the
unperturbed reference frame) as the keyword ``ring``. What each level means:

* **contrast** ``c``: ``128 + c·(g − 128)``, clipped (a camera contrast setting about mid grey).
* **gamma** ``γ``: ``255·(g/255)^γ`` (a different tone curve; the renderer's own display gamma
  already varies 1.8-2.4, i.e. a relative γ of 0.75-1.33).
* **exposure**, stops ``s``: the file is linearised with the renderer's display gamma 2.2,
  multiplied by ``2^s``, clipped at full scale (over-exposure saturates) and re-encoded.
* **blur** ``σ``: Gaussian blur of ``σ`` pixels of a 2592-px-wide frame (the rig's), scaled to
  the frame's width, so a level means the same optical blur at every resolution.
* **noise** ``sd``: additive Gaussian noise, ``sd`` grey levels, rounded and clipped.
* **JPEG** ``q``: encoded at quality ``q`` and decoded (libjpeg, 4:2:0 irrelevant: grey);
  ``0`` = not re-encoded (the lossless rendered original).
* **resolution** ``w'``: resampled to ``w'`` px wide, aspect kept (area filter down, bilinear
  up); ``0`` = the native size. Up-sampling adds no information: from native 400 px it checks
  only that the answer does not depend on the pixel count (kernels and crops that scale with
  the width); down-sampling also loses ridge detail.
* **dimmed sector** ``f``: the outer window ring (radii ``SECTOR_RADII`` × the ring's outer
  radius) dimmed by the fraction ``f`` over ``SECTOR_DEG`` degrees centred at an angle drawn
  from ``rng`` (a weak LED or a dirty light-guide sector).
* **offset** ``f``: the whole frame shifted by ``f`` × the ring radius, rounded to whole pixels,
  in a direction drawn from ``rng``; the uncovered border is black (the rig is dark outside the
  window). Whole pixels keep a shifted 0/255 mask exact.
* **no reference**: the frame unchanged, the method given no reference frame (the U-Net then
  finds the ring in the frame and uses the frame as its reference channel; the classical
  routine takes its ROI from the frame).
* **window speck** ``s``: a bright speck on the window near the centre, where the first contact
  appears: a Gaussian blob adding ``s`` of white in linear light (linearised with the display
  gamma 2.2, as for exposure), its centre drawn uniformly over a disc of ``SPECK_DISC`` × the
  ring radius about the ring's centre, its radius uniformly over ``SPECK_RADIUS_400`` px at
  400 px wide, scaled with the width. It copies the renderer's bright dust (``synth/look.py``,
  ``add_dust``: 10-40 % of white, radius 1-4 px at 400 wide, placed uniformly over the frame,
  so rarely near the centre), which adds it after the exposure and before the camera's defocus
  and noise; here it is added to the finished frame, so it is never blurred (a sharper speck
  than a defocused hard render's). The suite draws the same place and radius at every level.

The reference frame (:data:`REFERENCE_MODES`): camera settings are per session, so contrast,
gamma, exposure, blur, JPEG and resolution perturb it exactly as the frame; noise is drawn
independently for it (sensor noise differs between exposures); a dimmed sector is a property of
the rig (a weak LED), present from the 0 kPa frame on, so the reference gets the same sector, and
so is a speck on the window: the reference gets the same speck (identically seeded).
The offset leaves the reference as recorded: it is a misregistration between the frame and the
session's reference, and the ring moves with the frame. For the classical routine (ROI fixed
from the reference, the ring outside the ROI) that is what an off-centre finger does: the
contact moves within the ROI. For the U-Net it is harsher than a finger offset: its crop (from
the reference's ring) is off-centre on the frame's ring and its reference channel no longer
lines up; read it as camera or rig movement after the reference was taken. The true area of an
offset frame is its shifted mask's (contact pushed out of the frame is lost); of a resampled
frame the mask area × the pixel-count ratio ``(w'·h') / (w·h)``; of every other, the mask's.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from contactcal.infer.methods.unet.ring import RingFit

#: The rig's frame width, px: blur levels are in pixels at this width.
RIG_WIDTH_PX = 2592
#: Display gamma assumed to linearise a frame for an exposure change (the renderer's default).
DISPLAY_GAMMA = 2.2
#: Angular width of the dimmed ring sector, degrees.
SECTOR_DEG = 60.0
#: Radii of the dimmed annulus, × the ring's outer radius (the bright outer ring, not the
#: membrane inside it where the contact lies).
SECTOR_RADII = (0.85, 1.15)
#: Radius of the disc the window speck is placed in, × the ring's outer radius: the centre of
#: the window, where a contact starts (first contacts span ~0.1-0.3 ring radii).
SPECK_DISC = 0.3
#: Range of the speck's radius (≈ 1.5 σ of its Gaussian), px at 400 px wide: the renderer's dust.
SPECK_RADIUS_400 = (1.0, 4.0)


def _u8(values: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(values), 0, 255).astype(np.uint8)


def _linear(gray: np.ndarray) -> np.ndarray:
    """Grey levels → linear light in [0, 1] (float64), through :data:`DISPLAY_GAMMA`."""
    return (gray.astype(np.float64) / 255.0) ** DISPLAY_GAMMA


def _display(linear: np.ndarray) -> np.ndarray:
    """Linear light → grey levels (uint8), clipped at full scale: inverse of :func:`_linear`."""
    return _u8(255.0 * np.clip(linear, 0.0, 1.0) ** (1.0 / DISPLAY_GAMMA))


def _check(level: float, lo: float, hi: float, what: str) -> None:
    if not lo <= level <= hi:
        raise ValueError(f"{what} level must be in [{lo:g}, {hi:g}], got {level!r}")


def contrast(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Contrast factor ``level`` (1 = unchanged) about grey 128."""
    _check(level, 0.0, 10.0, "contrast")
    return _u8(128.0 + level * (gray.astype(np.float64) - 128.0))


def gamma(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Tone curve ``255·(g/255)^level`` (1 = unchanged)."""
    _check(level, 0.05, 20.0, "gamma")
    return _u8(255.0 * (gray.astype(np.float64) / 255.0) ** level)


def exposure(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Exposure change of ``level`` stops (0 = unchanged) in linear light, clipped."""
    _check(level, -8.0, 8.0, "exposure")
    return _display(_linear(gray) * 2.0**level)


def blur(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Gaussian blur, ``level`` = σ in pixels of a 2592-px-wide frame (0 = unchanged)."""
    _check(level, 0.0, 500.0, "blur")
    if level == 0:
        return gray.copy()
    sigma = level * gray.shape[1] / RIG_WIDTH_PX
    return cv2.GaussianBlur(gray, (0, 0), sigma, borderType=cv2.BORDER_REFLECT)


def noise(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Additive Gaussian noise of ``level`` grey levels standard deviation (0 = unchanged)."""
    _check(level, 0.0, 255.0, "noise")
    if level == 0:
        return gray.copy()
    return _u8(gray + rng.normal(0.0, level, gray.shape))


def jpeg(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """JPEG round trip at quality ``level`` (1-100; 0 = not re-encoded)."""
    _check(level, 0.0, 100.0, "JPEG quality")
    if level == 0:
        return gray.copy()
    ok, data = cv2.imencode(".jpg", gray, [cv2.IMWRITE_JPEG_QUALITY, max(1, round(level))])
    if not ok:
        raise ValueError(f"JPEG encoding at quality {level:g} failed")
    return cv2.imdecode(data, cv2.IMREAD_GRAYSCALE)


def resolution(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """Resampled to ``level`` px wide, aspect kept (0 = native size)."""
    _check(level, 0.0, 20000.0, "resolution")
    h, w = gray.shape
    width = round(level)
    if width in (0, w):
        return gray.copy()
    if width < 8:
        raise ValueError(f"resolution level must be 0 or >= 8 px wide, got {level!r}")
    size = (width, max(1, round(h * width / w)))
    interp = cv2.INTER_AREA if width < w else cv2.INTER_LINEAR
    return cv2.resize(gray, size, interpolation=interp)


def dim_sector(
    gray: np.ndarray, level: float, rng: np.random.Generator, *, ring: RingFit
) -> np.ndarray:
    """The outer ring dimmed by the fraction ``level`` over a ``SECTOR_DEG`` sector (0 = none).

    Args:
        gray: ``(H, W) uint8`` frame.
        level: fraction of the brightness removed, 0-1.
        rng: draws the sector's centre angle (uniform over the circle).
        ring: the session's window ring (input pixels).
    """
    _check(level, 0.0, 1.0, "dimmed sector")
    centre = rng.uniform(-math.pi, math.pi)
    yy, xx = np.mgrid[0 : gray.shape[0], 0 : gray.shape[1]]
    dx, dy = xx - ring.cx, yy - ring.cy
    r = np.hypot(dx, dy) / ring.radius
    off = np.angle(np.exp(1j * (np.arctan2(dy, dx) - centre)))  # wrapped to (-π, π]
    sector = (
        (r >= SECTOR_RADII[0])
        & (r <= SECTOR_RADII[1])
        & (np.abs(off) <= math.radians(SECTOR_DEG) / 2)
    )
    return _u8(np.where(sector, (1.0 - level) * gray, gray))


def offset(
    gray: np.ndarray, level: float, rng: np.random.Generator, *, ring: RingFit
) -> np.ndarray:
    """The frame shifted by ``level`` × the ring radius, whole pixels, black border (0 = none).

    Args:
        gray: ``(H, W) uint8`` frame (or a 0/255 mask: the same rng state gives the same shift).
        level: shift, fraction of ``ring.radius``, 0-1.
        rng: draws the direction (uniform over the circle).
        ring: the session's window ring (input pixels).
    """
    _check(level, 0.0, 1.0, "offset")
    angle = rng.uniform(-math.pi, math.pi)
    h, w = gray.shape
    dx = int(np.clip(round(level * ring.radius * math.cos(angle)), -w, w))
    dy = int(np.clip(round(level * ring.radius * math.sin(angle)), -h, h))
    out = np.zeros_like(gray)
    out[max(dy, 0) : h + min(dy, 0), max(dx, 0) : w + min(dx, 0)] = gray[
        max(-dy, 0) : h + min(-dy, 0), max(-dx, 0) : w + min(-dx, 0)
    ]
    return out


def speck(gray: np.ndarray, level: float, rng: np.random.Generator, *, ring: RingFit) -> np.ndarray:
    """A bright speck on the window near the ring's centre, adding ``level`` of white (0 = none).

    Args:
        gray: ``(H, W) uint8`` frame.
        level: peak of the added linear radiance, fraction of white (0-1).
        rng: draws the speck's place (2 draws) and radius (1 draw), in that order.
        ring: the session's window ring (input pixels).
    """
    _check(level, 0.0, 1.0, "window speck")
    out = gray.copy()
    if level == 0.0:
        return out
    dist = SPECK_DISC * ring.radius * math.sqrt(rng.random())
    angle = rng.uniform(-math.pi, math.pi)
    cx, cy = ring.cx + dist * math.cos(angle), ring.cy + dist * math.sin(angle)
    sigma = max(rng.uniform(*SPECK_RADIUS_400) * gray.shape[1] / 400.0, 0.3) / 1.5
    reach = 6.0 * sigma  # the blob is < 2e-8 of its peak beyond: no visible edge after gamma
    x0, y0 = max(math.floor(cx - reach), 0), max(math.floor(cy - reach), 0)
    x1 = min(math.ceil(cx + reach) + 1, gray.shape[1])
    y1 = min(math.ceil(cy + reach) + 1, gray.shape[0])
    if x1 <= x0 or y1 <= y0:
        return out
    yy, xx = np.mgrid[y0:y1, x0:x1]
    blob = level * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2.0 * sigma**2))
    out[y0:y1, x0:x1] = _display(_linear(out[y0:y1, x0:x1]) + blob)
    return out


def unchanged(gray: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    """The frame as it is (the "no reference" case changes the reference, not the frame)."""
    _check(level, 0.0, 1.0, "no reference")
    return gray.copy()

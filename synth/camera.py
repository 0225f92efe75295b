"""The camera after the optics: exposure, defocus, sensor noise, tone curve, JPEG, small tilt.

The v2 look effects (vignetting, glare, dust, motion blur, white balance, S-curve) live in
``look.py`` and are carried by ``CameraEffects.look`` (default: none).

Pure numpy/OpenCV. Works on the renderer's linear radiance and turns it into the ``uint8`` frame
a real rig camera would save. A small camera tilt/offset is applied as an image homography to
the frame and its mask together (a camera rotation is exactly a homography; the sub-millimetre
offsets sampled here are nearly so for this shallow scene), so the mask stays exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from contactcal.synth.look import (
    REFERENCE_WIDTH_PX,
    LookEffects,
    apply_optics,
    apply_white_balance,
    tone_curve,
)


@dataclass(frozen=True)
class CameraEffects:
    """One frame's camera settings (all sampled per session, with small per-frame jitter)."""

    exposure: float = 1.0  # × linear radiance; <1 underexposes (faint ridges), >1 clips rings
    defocus_sigma_px: float = 0.0  # Gaussian blur sigma, px at a 400-px-wide frame (scaled with
    #   the width: ``at_width``); blurs ridges (period ~4 px at 400 wide, ~28 px at 2592)
    full_well: float = 2000.0  # photo-electrons at white; lower → more shot (Poisson) noise
    read_noise: float = 0.004  # Gaussian read noise, fraction of white
    gamma: float = 2.2  # display gamma of the saved file
    jpeg_quality: int = 0  # 0 → PNG-like lossless; 60-95 → JPEG round trip artefacts
    tilt_deg: tuple[float, float] = (0.0, 0.0)  # camera rotation about x, y; shifts/keystones
    shift_px: tuple[float, float] = (0.0, 0.0)  # image offset of the optical axis, px at a
    #   400-px-wide frame (scaled with the width)
    look: LookEffects = field(default_factory=LookEffects)  # v2 appearance (look.py); none

    def __post_init__(self) -> None:
        if not self.exposure > 0:
            raise ValueError(f"exposure must be > 0, got {self.exposure}")
        if self.defocus_sigma_px < 0 or self.read_noise < 0 or not self.full_well > 0:
            raise ValueError("defocus_sigma_px and read_noise must be >= 0, full_well > 0")
        if self.jpeg_quality and not 1 <= self.jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be 0 (off) or 1-100, got {self.jpeg_quality}")
        if not isinstance(self.look, LookEffects):
            raise ValueError(f"synth/camera.py: look must be a LookEffects, got {self.look!r}")

    def at_width(self, width_px: int) -> CameraEffects:
        """These settings with every pixel length in pixels of a ``width_px``-wide frame.

        Defocus, axis offset and motion blur are given at ``REFERENCE_WIDTH_PX`` (400) and mean
        the same optics at every render size (as the dust radii do): a 1296-wide render gets
        3.24 × the pixels of blur, so its ridges lose what a 400-wide render's lose.
        """
        k = width_px / REFERENCE_WIDTH_PX
        return replace(
            self,
            defocus_sigma_px=self.defocus_sigma_px * k,
            shift_px=(self.shift_px[0] * k, self.shift_px[1] * k),
            look=replace(self.look, motion_blur_px=self.look.motion_blur_px * k),
        )


def tilt_homography(
    width: int,
    height: int,
    tilt_deg: tuple[float, float],
    shift_px: tuple[float, float],
    focal_px: float,
) -> np.ndarray:
    """``(3, 3)`` homography of a camera rotated by ``tilt_deg`` (about x, y) and shifted.

    Args:
        width, height: image size, px.
        tilt_deg: rotation about the image x and y axes, degrees.
        shift_px: extra translation of the image, px.
        focal_px: focal length in pixels (``0.5 * height / tan(fov_y / 2)``).
    """
    ax, ay = np.radians(tilt_deg)
    rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    k = np.array([[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1]])
    t = np.array([[1, 0, shift_px[0]], [0, 1, shift_px[1]], [0, 0, 1]])
    return t @ k @ (rx @ ry) @ np.linalg.inv(k)


def apply_camera(
    linear_rgb: np.ndarray,
    mask: np.ndarray,
    fx: CameraEffects,
    rng: np.random.Generator,
    focal_px: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Turn a linear render and its exact mask into the saved frame and the matching mask.

    Args:
        linear_rgb: ``(H, W, 3) float32`` linear radiance, 1.0 ≈ white at exposure 1.
        mask: ``(H, W) bool`` exact contact mask of the same camera.
        fx: camera settings, pixel lengths at 400 px wide (scaled here to the frame's width by
            ``CameraEffects.at_width``: pass them unscaled).
        rng: generator for the sensor noise (the look's dust/glare use ``fx.look.seed``).
        focal_px: focal length in pixels (for the tilt homography).

    Returns:
        ``(H, W, 3) uint8`` RGB frame and ``(H, W) bool`` mask after the same geometric warp.
    """
    if linear_rgb.ndim != 3 or linear_rgb.shape[2] != 3:
        raise ValueError(f"expected (H, W, 3) linear RGB, got {linear_rgb.shape}")
    if mask.shape != linear_rgb.shape[:2]:
        raise ValueError(f"mask {mask.shape} does not match frame {linear_rgb.shape[:2]}")
    if not np.all(np.isfinite(linear_rgb)):
        raise ValueError("linear render contains NaN or inf")
    h, w = mask.shape
    fx = fx.at_width(w)
    img = np.maximum(linear_rgb.astype(np.float32), 0.0) * fx.exposure
    m = mask.astype(np.uint8)
    if any(fx.tilt_deg) or any(fx.shift_px):
        hmat = tilt_homography(w, h, fx.tilt_deg, fx.shift_px, focal_px)
        img = cv2.warpPerspective(img, hmat, (w, h), flags=cv2.INTER_LINEAR)
        m = cv2.warpPerspective(m, hmat, (w, h), flags=cv2.INTER_NEAREST)
    img = apply_optics(img, fx.look)  # vignetting, glare, dust, motion blur (never the mask)
    if fx.defocus_sigma_px > 0:
        img = cv2.GaussianBlur(img, (0, 0), fx.defocus_sigma_px)
    electrons = rng.poisson(np.clip(img, 0.0, 4.0) * fx.full_well).astype(np.float32)
    img = electrons / fx.full_well + rng.normal(0.0, fx.read_noise, img.shape).astype(np.float32)
    img = apply_white_balance(img, fx.look.wb_gains)
    img = np.clip(img, 0.0, 1.0) ** (1.0 / fx.gamma)
    if fx.look.tone_strength > 0:
        img = tone_curve(img, fx.look.tone_strength)
    out = np.rint(img * 255.0).astype(np.uint8)
    if fx.jpeg_quality:
        ok, buf = cv2.imencode(".jpg", out[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, fx.jpeg_quality])
        if not ok:
            raise RuntimeError("JPEG encoding failed")
        out = cv2.imdecode(buf, cv2.IMREAD_COLOR)[:, :, ::-1]
    return np.ascontiguousarray(out), m.astype(bool)

"""Procedurally drawn rig frames (no renderer) for fast unit tests of the image pipeline.

A frame is: a bright peripheral window ring, optionally an inner (membrane) ring around the
contact patch, and an ellipse filled with a ridge texture. The exact contact area is known.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np


@dataclass(frozen=True)
class DrawnFrame:
    """A drawn frame and its truth."""

    image: np.ndarray  # (H, W) uint8
    mask: np.ndarray  # (H, W) bool, exact contact region (pixel centres inside the ellipse)
    area_px: float  # analytic ellipse area π·a·b, px²


def draw_frame(
    rng: np.random.Generator,
    width: int = 648,
    height: int = 486,
    semi_axes_px: tuple[float, float] | None = (60.0, 45.0),
    angle_deg: float = 20.0,
    centre_offset_px: tuple[float, float] = (0.0, 0.0),
    ridge_period_px: float = 5.0,
    inner_ring: bool = True,
    noise_sd: float = 3.0,
    background: float = 20.0,
) -> DrawnFrame:
    """Draw one frame; ``semi_axes_px=None`` draws a ring-only (no contact) frame."""
    cy, cx = (height - 1) / 2.0, (width - 1) / 2.0
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float64)
    r = np.hypot(xx - cx, yy - cy)
    ring_r = 0.42 * height
    img = background + 200.0 * np.exp(-(((r - ring_r) / (0.012 * height)) ** 2))
    mask = np.zeros((height, width), bool)
    area = 0.0
    if semi_axes_px is not None:
        a, b = semi_axes_px
        ex, ey = cx + centre_offset_px[0], cy + centre_offset_px[1]
        t = math.radians(angle_deg)
        u = (xx - ex) * math.cos(t) + (yy - ey) * math.sin(t)
        v = -(xx - ex) * math.sin(t) + (yy - ey) * math.cos(t)
        rho = np.sqrt((u / a) ** 2 + (v / b) ** 2)
        mask = rho <= 1.0
        area = math.pi * a * b
        ridges = 0.5 + 0.5 * np.cos(2 * math.pi * (u + 0.3 * v) / ridge_period_px)
        img = np.where(mask, 60.0 + 120.0 * ridges, img)
        if inner_ring:
            img += 90.0 * np.exp(-(((rho - 1.08) / 0.05) ** 2))
    img = img + rng.normal(0.0, noise_sd, img.shape)
    image = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return DrawnFrame(image=image, mask=mask, area_px=area)


def write_png(path: str, image: np.ndarray) -> None:
    """Write an image (format from the suffix; JPEG at quality 90), failing loudly."""
    if not cv2.imwrite(path, image, [cv2.IMWRITE_JPEG_QUALITY, 90]):
        raise OSError(f"could not write {path}")


#: Contact ellipse semi-axes (px at 64×48) per pressure, kPa; None = below the onset.
AXES = {0.0: None, 2.0: None, 4.0: (5.0, 4.0), 8.0: (8.0, 6.0), 14.0: (11.0, 8.0)}


def write_dataset(root: Path, fingers: int = 4, seed: int = 0, w: int = 64, h: int = 48) -> Path:
    """A tiny dataset in the ``contactcal synth`` layout, drawn procedurally."""
    rng = np.random.default_rng(seed)
    root.mkdir(parents=True, exist_ok=True)
    rows = []
    for f in range(fingers):
        session = f"finger_{f:04d}"
        (root / session / "frames").mkdir(parents=True)
        (root / session / "masks").mkdir()
        angle = float(rng.uniform(0, 180))
        for p, axes in AXES.items():
            d = draw_frame(rng, w, h, axes, angle, ridge_period_px=3.0, noise_sd=2.0)
            name = f"p{p:04.1f}kpa.png"
            write_png(str(root / session / "frames" / name), np.repeat(d.image[:, :, None], 3, 2))
            write_png(str(root / session / "masks" / name), d.mask.astype(np.uint8) * 255)
            rows.append(
                {
                    "finger": f,
                    "session": session,
                    "frame": f"{session}/frames/{name}",
                    "mask": f"{session}/masks/{name}",
                    "pressure_kpa": p,
                    "contact": int(axes is not None),
                    "area_px": int(d.mask.sum()),
                    "mm_per_px": 0.1,
                    "onset_kpa": 3.0,
                    "hard": int(f % 2 == 1),
                    "width": w,
                    "height": h,
                }
            )
    with open(root / "index.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return root

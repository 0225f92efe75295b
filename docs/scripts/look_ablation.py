"""Make ``docs/ablation_look.png``: one frame, each v2 look element alone at its hard extreme.

No Mitsuba: a saved synthetic frame is turned back into a plausible linear render
(``(png / 255) ** 2.2``) and sent through ``apply_camera`` once per element, with the same
noise generator seed, so the panels differ only by the element named above them.

    .venv/bin/python docs/scripts/look_ablation.py
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np

from contactcal.synth.camera import CameraEffects, apply_camera
from contactcal.synth.look import LookEffects

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "data/interval_check/finger_0000/frames/p10.0kpa.png"
OUT = ROOT / "docs/ablation_look.png"
WIDTH = 320  # px; the figure stays small (< 400 KB)

BASE = CameraEffects(exposure=1.0, full_well=2000.0, read_noise=0.004, gamma=2.2)
LOOK = LookEffects()
PANELS: list[tuple[str, CameraEffects]] = [
    ("nominal camera (no look)", BASE),
    ("exposure -2 stops", dataclasses.replace(BASE, exposure=0.25)),
    ("exposure +2 stops", dataclasses.replace(BASE, exposure=4.0)),
    ("S-curve 0.5", dataclasses.replace(BASE, look=dataclasses.replace(LOOK, tone_strength=0.5))),
    (
        "white balance R+25 % B-25 %",
        dataclasses.replace(BASE, look=dataclasses.replace(LOOK, wb_gains=(1.25, 1.0, 0.75))),
    ),
    (
        "vignetting 0.4, off-axis",
        dataclasses.replace(
            BASE, look=dataclasses.replace(LOOK, vignetting=0.4, vignette_centre=(0.06, -0.04))
        ),
    ),
    (
        "motion blur 3 px at 30°",
        dataclasses.replace(
            BASE,  # 3 px at this 320-px width: pixel lengths are given at 400 px wide
            look=dataclasses.replace(LOOK, motion_blur_px=3.75, motion_blur_deg=30.0),
        ),
    ),
    (
        "15 dust specks",
        dataclasses.replace(BASE, look=dataclasses.replace(LOOK, dust_count=15, seed=3)),
    ),
    (
        "stray reflection 15 %",
        dataclasses.replace(BASE, look=dataclasses.replace(LOOK, stray_amplitude=0.15, seed=1)),
    ),
    ("JPEG q50", dataclasses.replace(BASE, jpeg_quality=50)),
]


def source_png() -> Path:
    """The frame to start from: the interval-check frame, else any PNG under ``examples/``."""
    if SOURCE.exists():
        return SOURCE
    found = sorted((ROOT / "examples").rglob("*.png"))
    if not found:
        raise FileNotFoundError(f"docs/scripts/look_ablation.py: no {SOURCE} and no examples PNG")
    return found[0]


def linear_frame(path: Path, width: int = WIDTH) -> np.ndarray:
    """``(H, W, 3) float32`` linear radiance, 1.0 = white, from an sRGB-ish PNG."""
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise FileNotFoundError(f"docs/scripts/look_ablation.py: cannot read {path}")
    h = round(bgr.shape[0] * width / bgr.shape[1])
    rgb = cv2.resize(bgr, (width, h), interpolation=cv2.INTER_AREA)[:, :, ::-1]
    return ((rgb.astype(np.float32) / 255.0) ** 2.2).astype(np.float32)


def panels(linear: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Every panel's ``(H, W, 3) uint8`` frame, same noise seed for all."""
    mask = np.zeros(linear.shape[:2], bool)
    out = []
    for label, fx in PANELS:
        frame, _ = apply_camera(linear, mask, fx, np.random.default_rng(0), focal_px=500.0)
        out.append((label, frame))
    return out


def main() -> None:
    """Render the grid to ``docs/ablation_look.png``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    images = panels(linear_frame(source_png()))
    cols = 5
    rows = -(-len(images) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 2.3 * rows), dpi=90)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (label, img) in zip(axes.ravel(), images, strict=False):
        ax.imshow(img)
        ax.set_title(label, fontsize=8)
    fig.tight_layout()
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    from PIL import Image  # matplotlib's own dependency; a 256-colour palette keeps it small

    Image.fromarray(rgba[:, :, :3]).quantize(256).save(OUT, optimize=True)
    print(f"wrote {OUT} ({OUT.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()

"""Overlays of contact outlines on frames, and montages of them (like the paper's comparison)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.atomic import atomic_path

#: Outline colours (BGR) per method.
COLOURS = {"unet": (60, 220, 60), "classical": (40, 40, 255), "truth": (255, 200, 0)}


def draw_overlay(
    gray: np.ndarray, contours: Mapping[str, np.ndarray | None], title: str = ""
) -> np.ndarray:
    """Draw each method's outline on a frame.

    Args:
        gray: ``(H, W) uint8`` frame.
        contours: method name → ``(N, 1, 2) int32`` outline in input pixels (None: no contact).
        title: text written in the top-left corner (e.g. the pressure).

    Returns:
        ``(H, W, 3) uint8`` BGR image.
    """
    img = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    h = img.shape[0]
    thick = max(1, round(h / 300))
    scale = max(0.35, h / 900)
    y = round(18 * scale / 0.5)
    if title:
        cv2.putText(img, title, (5, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), thick)
    for k, (name, contour) in enumerate(contours.items()):
        colour = COLOURS.get(name, (255, 255, 255))
        if contour is not None and len(contour) >= 2:
            cv2.drawContours(img, [contour], -1, colour, thick, cv2.LINE_AA)
        label = name if contour is not None else f"{name}: no contact"
        cv2.putText(img, label, (5, h - 8 - round(k * 2.2 * y / 2)), cv2.FONT_HERSHEY_SIMPLEX,
                    scale, colour, thick)  # fmt: skip
    return img


def montage(images: Sequence[np.ndarray], columns: int, width: int = 400) -> np.ndarray:
    """Tile BGR images (resized to ``width`` px wide, same aspect as the first) into a grid."""
    if not images:
        raise ValueError("montage: no images")
    h0, w0 = images[0].shape[:2]
    height = round(width * h0 / w0)
    tiles = [cv2.resize(im, (width, height), interpolation=cv2.INTER_AREA) for im in images]
    rows = -(-len(tiles) // columns)
    blank = np.zeros_like(tiles[0])
    tiles += [blank] * (rows * columns - len(tiles))
    return np.vstack([np.hstack(tiles[r * columns : (r + 1) * columns]) for r in range(rows)])


def write_image(path: str | os.PathLike[str], image: np.ndarray) -> Path:
    """Write a PNG/JPEG atomically; raises ``OSError`` naming the file on failure."""
    path = Path(path)
    ok, buf = cv2.imencode(path.suffix or ".png", image)
    if not ok:
        raise OSError(f"{path}: could not encode image")
    with atomic_path(path) as tmp:
        tmp.write_bytes(buf.tobytes())
    return path

"""Overlays of contact outlines on frames, and montages of them (like the paper's comparison)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.image.read import load_image
from contactcal.infer.pipeline.measure import Measured

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
        at = (5, h - 8 - round(k * 2.2 * y / 2))
        cv2.putText(img, label, at, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick)
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


def write_overlays(
    runs: dict[str, list[Measured]],
    out_dir: str | os.PathLike[str],
    titles: Sequence[str] | None = None,
) -> list[Path]:
    """Draw every method's outline on each frame and write ``<stem>_overlay.png`` files.

    Args:
        runs: method name → its measurements of the same files (same order).
        out_dir: folder for the overlays.
        titles: per-file caption (e.g. ``"8.0 kPa"``); default the file name.

    Returns:
        The written paths, in file order.
    """
    from contactcal.infer.image.write import write_image
    from contactcal.infer.pipeline.overlay import draw_overlay

    first = next(iter(runs.values()))
    paths: list[Path] = []
    for k, m in enumerate(first):
        gray = load_image(m.file)
        contours = {name: ms[k].result.contour for name, ms in runs.items()}
        title = titles[k] if titles is not None else m.file.name
        img = draw_overlay(gray, contours, title)
        paths.append(write_image(Path(out_dir) / f"{m.file.stem}_overlay.png", img))
    return paths

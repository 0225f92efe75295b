"""The drawing grid (pixel centres in millimetres) and smooth random fields."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Grid:
    """Sample positions of one frame, drawn ``ss`` × finer than the saved frame.

    ``x`` to the right and ``y`` down, origin at the frame centre (the rig axis), mm.
    """

    x: np.ndarray  # (H·ss, W·ss) float64, mm
    y: np.ndarray  # (H·ss, W·ss) float64, mm
    mm_per_sample: float  # mm between neighbouring samples
    ss: int  # supersampling factor

    @property
    def r(self) -> np.ndarray:
        """(H·ss, W·ss) distance from the rig axis, mm."""
        return np.hypot(self.x, self.y)

    @property
    def theta(self) -> np.ndarray:
        """(H·ss, W·ss) angle about the rig axis, rad."""
        return np.arctan2(self.y, self.x)


def make_grid(width: int, height: int, mm_per_px: float, ss: int = 1) -> Grid:
    """Sample centres of a ``width``×``height`` px frame, ``ss``×``ss`` samples per pixel."""
    step = mm_per_px / ss
    xs = (np.arange(width * ss) + 0.5) * step - width * mm_per_px / 2
    ys = (np.arange(height * ss) + 0.5) * step - height * mm_per_px / 2
    y, x = np.meshgrid(ys, xs, indexing="ij")
    return Grid(x=x, y=y, mm_per_sample=step, ss=ss)


def smooth_field(rng: np.random.Generator, shape: tuple[int, int], cell: float) -> np.ndarray:
    """Zero-mean, unit-sd smooth random field: Gaussian noise on a coarse lattice, bicubic.

    Args:
        rng: randomness.
        shape: ``(H, W)`` of the output.
        cell: lattice spacing, in output samples (>= 1); the field varies over ~``cell``.

    Returns:
        (H, W) float32.
    """
    h, w = shape
    gh, gw = max(2, int(np.ceil(h / cell)) + 2), max(2, int(np.ceil(w / cell)) + 2)
    coarse = rng.standard_normal((gh, gw)).astype(np.float32)
    big = cv2.resize(coarse, (int(gw * cell), int(gh * cell)), interpolation=cv2.INTER_CUBIC)
    out = big[:h, :w]
    sd = float(out.std())
    return (out - out.mean()) / (sd if sd > 0 else 1.0)

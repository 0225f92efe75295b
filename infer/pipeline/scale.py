"""Pixel scale (mm per pixel) of the rig's camera at the membrane's contact plane.

A rig config is a small JSON file, e.g. written next to a rendered session by ``contactcal synth``::

    {"mm_per_px": 0.0118, "image_width_px": 2592}

``mm_per_px`` holds for images ``image_width_px`` wide; other widths (downscaled frames) scale
inversely with the width. Areas scale with its square.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path


class RigConfigError(ValueError):
    """A rig config file that cannot be used; the message names the file."""


@dataclass(frozen=True)
class PixelScale:
    """Camera scale at the contact plane."""

    mm_per_px: float  # mm per pixel at image_width_px
    image_width_px: int | None  # width the scale was measured at; None = any width (as given)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mm_per_px) and self.mm_per_px > 0):
            raise ValueError(f"mm_per_px must be a positive number, got {self.mm_per_px}")
        if self.image_width_px is not None and self.image_width_px <= 0:
            raise ValueError(f"image_width_px must be positive, got {self.image_width_px}")

    def at_width(self, width_px: int) -> float:
        """mm per pixel for an image ``width_px`` wide."""
        if self.image_width_px is None:
            return self.mm_per_px
        return self.mm_per_px * self.image_width_px / width_px

    def area_mm2(self, area_px: float, width_px: int) -> float:
        """Convert an area in pixels of an image ``width_px`` wide to mm²."""
        return area_px * self.at_width(width_px) ** 2


def load_rig_config(path: str | os.PathLike[str]) -> PixelScale:
    """Read a rig config JSON (``mm_per_px`` and ``image_width_px``).

    Raises:
        RigConfigError: missing file, invalid JSON, missing or invalid fields.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise RigConfigError(f"{p}: no such rig config file") from exc
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RigConfigError(f"{p}: not a readable JSON rig config ({exc})") from exc
    if not isinstance(data, dict) or "mm_per_px" not in data or "image_width_px" not in data:
        raise RigConfigError(
            f"{p}: expected a JSON object with 'mm_per_px' and 'image_width_px', e.g. "
            '{"mm_per_px": 0.0118, "image_width_px": 2592}'
        )
    try:
        return PixelScale(float(data["mm_per_px"]), int(data["image_width_px"]))
    except (TypeError, ValueError) as exc:
        raise RigConfigError(f"{p}: {exc}") from exc

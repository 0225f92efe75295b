"""Pixel scale (mm per pixel) of the rig's camera at the membrane's contact plane.

A rig config is a small JSON file, e.g. written next to a rendered session by ``contactcal synth``::

    {"mm_per_px": 0.0118, "image_width_px": 2592}

``mm_per_px`` holds for images ``image_width_px`` wide; other widths (downscaled frames) scale
inversely with the width. Areas scale with its square.
"""

from __future__ import annotations

import json
import math
import numbers
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.files.regular import parse_input_json, read_input_bytes

#: Plausible mm per pixel at the contact plane. The rig's camera gives ~0.012 mm/px on a
#: 2592 px frame (a ~30 mm field); 1e-4 mm/px (a 0.26 mm field) is finer than any camera's view
#: of a fingertip and 10 mm/px (a 16 px frame spans 16 cm) coarser than any frame of one. The
#: bounds keep every area conversion finite.
MM_PER_PX_RANGE = (1e-4, 10.0)
#: Plausible width (px) a scale was measured at: a rig frame is >= 16 px wide and no camera
#: sensor has more than 100,000 px per row.
IMAGE_WIDTH_RANGE_PX = (16, 100_000)
_EXAMPLE = '{"mm_per_px": 0.0118, "image_width_px": 2592}'
#: The boundary offset's keys (:mod:`.boundary`; both or neither).
OFFSET_KEY, MODEL_KEY = "boundary_offset_mm", "boundary_offset_model_sha256"
#: Every key a rig config may hold: a misspelt one would otherwise drop its value silently.
RIG_KEYS = ("mm_per_px", "image_width_px", OFFSET_KEY, MODEL_KEY)


class RigConfigError(ValueError):
    """A rig config file that cannot be used; the message names the file."""


@dataclass(frozen=True)
class PixelScale:
    """Camera scale at the contact plane."""

    mm_per_px: float  # mm per pixel at image_width_px, within MM_PER_PX_RANGE
    image_width_px: int | None  # width the scale was measured at; None = any width (as given)

    def __post_init__(self) -> None:
        lo, hi = MM_PER_PX_RANGE
        m = self.mm_per_px
        if isinstance(m, bool) or not isinstance(m, numbers.Real) or not lo <= m <= hi:
            raise ValueError(
                f"mm_per_px must be a number of mm per pixel in [{lo:g}, {hi:g}] "
                f"(the rig: ~0.012 at 2592 px wide), got {m!r}"
            )
        w, (wlo, whi) = self.image_width_px, IMAGE_WIDTH_RANGE_PX
        if w is not None and (
            isinstance(w, bool) or not isinstance(w, numbers.Integral) or not wlo <= w <= whi
        ):
            raise ValueError(
                f"image_width_px must be a whole number of pixels in [{wlo}, {whi}], got {w!r}"
            )

    def at_width(self, width_px: int) -> float:
        """mm per pixel for an image ``width_px`` (>= 1) wide."""
        if width_px < 1:
            raise ValueError(f"image width must be >= 1 px, got {width_px}")
        if self.image_width_px is None:
            return self.mm_per_px
        return self.mm_per_px * self.image_width_px / width_px

    def area_mm2(self, area_px: float, width_px: int) -> float:
        """Convert an area in pixels of an image ``width_px`` wide to mm².

        Finite for any finite area: the scale's bounds keep ``at_width`` <= 1e6 mm/px.
        """
        if not (math.isfinite(area_px) and area_px >= 0.0):
            raise ValueError(f"area must be a finite number of pixels >= 0, got {area_px}")
        return area_px * self.at_width(width_px) ** 2


def _width(value: object) -> object:
    """A JSON width as an int when it is a whole number (2592.0 → 2592); else unchanged."""
    if isinstance(value, float) and math.isfinite(value) and value.is_integer():
        return int(value)
    return value


def read_rig_json(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The JSON object of a rig config file (read once; the scale and the boundary offset are
    parsed from it).

    Raises:
        RigConfigError: missing file, a folder, unreadable or invalid JSON, not a JSON object, a key
            given twice, or a key not in :data:`RIG_KEYS`.
    """
    p = Path(path)
    try:
        raw = read_input_bytes(p, "the rig config JSON file (rig.json)", RigConfigError)
        text = raw.decode("utf-8-sig")  # a BOM (Notepad) is fine
        data = parse_input_json(text, object_pairs_hook=_pairs_once)
    except FileNotFoundError as exc:
        raise RigConfigError(f"{p}: no such rig config file") from exc
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RigConfigError(f"{p}: not a readable JSON rig config ({exc})") from exc
    except _DuplicateKey as exc:
        raise RigConfigError(f"{p}: key {exc} is given twice; keep one value") from exc
    if not isinstance(data, dict):
        raise RigConfigError(f"{p}: expected a JSON object, e.g. {_EXAMPLE}")
    unknown = [k for k in data if k not in RIG_KEYS]
    if unknown:
        raise RigConfigError(
            f"{p}: unknown key {unknown[0]!r}; expected only {', '.join(RIG_KEYS)} "
            "(check the spelling)"
        )
    return data


class _DuplicateKey(Exception):
    """A JSON object with a key twice (``json`` would keep the last value silently)."""


def _pairs_once(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``object_pairs_hook`` of :func:`read_rig_json`: a dict, refusing repeated keys."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(repr(key))
        out[key] = value
    return out


def rig_scale(data: dict[str, Any], path: str | os.PathLike[str]) -> PixelScale:
    """The pixel scale a rig config's JSON object states (``path`` names it in errors).

    Raises:
        RigConfigError: missing or invalid (non-numeric, non-finite, out-of-range, fractional
            width) fields.
    """
    p = Path(path)
    if "mm_per_px" not in data or "image_width_px" not in data:
        raise RigConfigError(
            f"{p}: expected a JSON object with 'mm_per_px' and 'image_width_px', e.g. {_EXAMPLE}"
        )
    try:
        return PixelScale(data["mm_per_px"], _width(data["image_width_px"]))
    except ValueError as exc:
        raise RigConfigError(f"{p}: {exc}") from exc


def load_rig_config(path: str | os.PathLike[str]) -> PixelScale:
    """Read a rig config JSON (``mm_per_px`` and ``image_width_px``).

    Raises:
        RigConfigError: missing file, invalid JSON, missing or invalid (non-numeric,
            non-finite, out-of-range, fractional width) fields.
    """
    return rig_scale(read_rig_json(path), path)

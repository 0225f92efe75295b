"""Measuring image files and calibrating a session: the work behind ``measure`` and ``calibrate``.

Thin wrappers around pure functions: image loading (:mod:`.io`), a method (:mod:`.methods`), the
monotone curve (:mod:`.curve`) and atomic outputs (:mod:`.calibration_io`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.image.read import load_image
from contactcal.infer.methods.base import AreaResult, Method
from contactcal.infer.pipeline.scale import PixelScale


@dataclass(frozen=True)
class Measured:
    """A measured file: the method's result plus its scale."""

    file: Path
    width: int
    height: int
    result: AreaResult
    area_mm2: float | None

    def to_json(self, method: str) -> dict[str, Any]:
        """The CLI contract's per-image object."""
        return {
            "file": str(self.file),
            "contact": self.result.contact,
            "area_px": float(self.result.area_px),
            "area_mm2": self.area_mm2,
            "method": method,
            "width": self.width,
            "height": self.height,
            "note": self.result.note,
        }


def measure_files(
    files: Sequence[str | os.PathLike[str]],
    method: Method,
    reference: str | os.PathLike[str] | None = None,
    scale: PixelScale | None = None,
    progress: bool = False,
) -> list[Measured]:
    """Measure each image file with ``method``.

    Args:
        files: image paths.
        method: a prepared-on-demand method (:func:`contactcal.infer.methods.make_method`).
        reference: the session's zero-pressure frame; None → each frame is its own reference.
        scale: pixel scale for mm² (None → ``area_mm2`` is None).
        progress: show a progress bar on stderr.

    Returns:
        One :class:`Measured` per file, in order.

    Raises:
        contactcal.infer.io.ImageError: any unreadable file (nothing is measured after it).
    """
    images = [Path(f) for f in files]
    k = method.start(images, None if reference is None else Path(reference))
    out: list[Measured] = []
    it: Any = images
    if progress:
        from tqdm import tqdm

        it = tqdm(images, desc=f"measure ({method.name})", unit="frame", leave=False)
    for path in it:
        img = load_image(path, reduce=k)
        res = method.measure(img)  # in the file's pixels
        w, h = img.shape[1] * k, img.shape[0] * k
        mm2 = None if scale is None else scale.area_mm2(res.area_px, w)
        out.append(Measured(path, w, h, res, mm2))
    return out

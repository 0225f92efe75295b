"""Measuring image files and calibrating a session: the work behind ``measure`` and ``calibrate``.

Thin wrappers around pure functions: image loading (:mod:`.io`), a method (:mod:`.methods`), the
monotone curve (:mod:`.curve`) and atomic outputs (:mod:`.calibration_io`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from contactcal.infer.io import jpeg_size, load_image
from contactcal.infer.methods import AreaResult, Method
from contactcal.infer.scale import PixelScale


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
    k = decode_reduction(method, images, None if reference is None else Path(reference))
    method.prepare(None if reference is None else load_image(reference, reduce=k))
    out: list[Measured] = []
    it: Any = images
    if progress:
        from tqdm import tqdm

        it = tqdm(images, desc=f"measure ({method.name})", unit="frame", leave=False)
    for path in it:
        img = load_image(path, reduce=k)
        res = method.measure(img)
        if k > 1:  # back to the file's pixels: the reduced decode is exactly 1/k per side
            contour = None if res.contour is None else res.contour * k
            res = replace(res, area_px=res.area_px * k * k, contour=contour,
                          soft_area_px=None if res.soft_area_px is None
                          else res.soft_area_px * k * k)  # fmt: skip
        w, h = img.shape[1] * k, img.shape[0] * k
        mm2 = None if scale is None else scale.area_mm2(res.area_px, w)
        out.append(Measured(path, w, h, res, mm2))
    return out


def decode_reduction(method: Method, files: Sequence[Path], reference: Path | None) -> int:
    """The cheapest correct JPEG decoding for ``method``: 1, 2, 4 or 8 (1/k per side).

    Only the U-Net benefits: it resizes a crop around the window ring to its input size anyway,
    so decoding a JPEG at 1/k (libjpeg's DCT scaling, several times cheaper) changes nothing as
    long as the crop stays at least the network's input size. Used only when every file is a
    JPEG whose width and height are divisible by k (so areas scale back exactly by k²).
    """
    seg = getattr(method, "segmenter", None)
    paths = [*files, *([reference] if reference is not None else [])]
    if seg is None or not all(p.suffix.lower() in (".jpg", ".jpeg") for p in paths):
        return 1
    from contactcal.infer.preprocess import crop_box, locate_ring

    cfg = seg.spec.preprocess
    sizes = {jpeg_size(p) for p in paths}
    if len(sizes) != 1:
        return 1  # frames of several sizes: decode fully
    h, w = sizes.pop()
    ring = locate_ring(load_image(paths[-1], reduce=8), cfg)
    if not ring.found:
        return 1
    side = crop_box(ring, (h // 8, w // 8), cfg).side * 8  # crop side in file pixels
    for k in (8, 4, 2):
        if side / k >= cfg.input_size and h % k == 0 and w % k == 0:
            return k
    return 1


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
    from contactcal.infer.overlay import draw_overlay, write_image

    first = next(iter(runs.values()))
    paths: list[Path] = []
    for k, m in enumerate(first):
        gray = load_image(m.file)
        contours = {name: ms[k].result.contour for name, ms in runs.items()}
        title = titles[k] if titles is not None else m.file.name
        img = draw_overlay(gray, contours, title)
        paths.append(write_image(Path(out_dir) / f"{m.file.stem}_overlay.png", img))
    return paths

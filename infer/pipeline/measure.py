"""Measuring image files: the work behind ``measure`` (and the frames of ``calibrate``).

Image loading (:mod:`contactcal.infer.image.read`), a method (:mod:`contactcal.infer.methods`),
the pixel scale, and the check that every frame matches the session's reference frame.
"""

from __future__ import annotations

import filecmp
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from contactcal.infer.image.gray import ImageError
from contactcal.infer.image.read import ImageFile
from contactcal.infer.methods.base import UNCHANGED_NOTE, AreaResult, Method
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.ring import RingFit, locate_ring
from contactcal.infer.pipeline.boundary import BoundaryOffset, BoundaryOffsetError, apply_offset
from contactcal.infer.pipeline.scale import PixelScale

#: A frame's ring centre may lie this far from the reference's, as a fraction of the reference
#: ring's radius. Frames of one session agree within 0.5 % (example session, also under noise,
#: blur and 0.3-2.5× exposure); a bumped rig or another crop moves it further.
RING_CENTRE_TOLERANCE = 0.05
#: A frame's ring radius may differ from the reference's by this fraction. The fit on a frame in
#: contact is ~3 % larger than on the 0 kPa reference (the inflated membrane's glow joins the
#: ring's outline), so 5 % would leave too little margin; another zoom or scale differs more.
RING_RADIUS_TOLERANCE = 0.10
#: Longest side (px) the ring check works at (an integer-factor area reduction of the decoded
#: frame). Its cost per 2592×1944 frame, ~1.7 ms fully decoded (the classical path, ~40 ms a
#: frame) and ~0.25 ms at the U-Net's 1/8 decode (~15 ms a frame), is small enough to check
#: every frame rather than a sample; the fit is still within 0.3 % of the radius.
RING_CHECK_PX = 160


#: Appended to the note of a frame the change gate called unchanged that is the reference frame
#: itself (``measure --reference X X``; ``{how}``: "path" or "bytes").
SELF_REFERENCE_NOTE = (
    "this file is the reference frame itself (same {how}): compared with itself nothing has "
    "changed, so the change gate cannot show contact here; for a frame under pressure give the "
    "session's 0 kPa frame as --reference (or measure with --no-change-gate)"
)


@dataclass(frozen=True)
class Measured:
    """A measured file: the method's result plus its scale."""

    file: Path
    width: int
    height: int
    result: AreaResult
    area_mm2: float | None
    reference: Path | None = None  # the session's reference frame (None: measured without one)
    boundary_offset_mm: float | None = None  # the rig's boundary offset applied (None: none)
    #: sha256 of the file's content as decoded and measured (None: not asked for)
    sha256: str | None = None
    #: sha256 of the reference's content it was measured against (None: none, or not asked for)
    reference_sha256: str | None = None

    def to_json(self, method: str) -> dict[str, Any]:
        """The CLI contract's per-image object (``area_interval_px``: ``[lower, upper]`` input
        pixels, the method's stated interval of the area, or None when it states none)."""
        iv = self.result.area_interval_px
        return {
            "file": str(self.file),
            "contact": self.result.contact,
            "area_px": float(self.result.area_px),
            "area_interval_px": None if iv is None else [float(iv[0]), float(iv[1])],
            "area_mm2": self.area_mm2,
            "method": method,
            "width": self.width,
            "height": self.height,
            "note": self.result.note,
            "reference": None if self.reference is None else str(self.reference),
            "boundary_offset_mm": self.boundary_offset_mm,
        }


@dataclass(frozen=True)
class _Reference:
    """What every frame of a session is checked against."""

    path: Path
    size: tuple[int, int]  # (width, height) of the file, px
    ring: RingFit  # at the check's working size (found=False: position not checked)
    image: np.ndarray  # the method's decode of it at 1/k: measured as is where it is a frame
    sha256: str | None  # of the content read once, that the method decoded (None: not asked)


def _file_size(img: np.ndarray, k: int) -> tuple[int, int]:
    """``(width, height)`` of the file decoded at 1/k into ``img``: exactly k times its size,
    since a method chooses k > 1 only when every file's sides divide by k (:meth:`Method.start`,
    which read every file's header to choose it)."""
    return img.shape[1] * k, img.shape[0] * k


def _coarse_ring(img: np.ndarray) -> RingFit:
    """The ring of ``img`` reduced by an integer factor to <= :data:`RING_CHECK_PX` (cheap)."""
    f = math.ceil(max(img.shape) / RING_CHECK_PX)
    if f > 1:
        img = cv2.resize(img, None, fx=1.0 / f, fy=1.0 / f, interpolation=cv2.INTER_AREA)
    return locate_ring(img, PreprocessConfig(ring_work_px=max(img.shape)))


def _check_frame(ref: _Reference, path: Path, img: np.ndarray, size: tuple[int, int]) -> str:
    """Raise unless the frame matches the reference (size and ring; a reference without a ring
    while the frame has one is a dark reference); return a note when unchecked, else ""."""
    what = ""
    if size != ref.size:
        what = f"{size[0]}×{size[1]} px, the reference {ref.size[0]}×{ref.size[1]} px"
    elif not ref.ring.found:
        if _coarse_ring(img).found:  # the rig was lit, its reference frame was not
            raise ImageError(
                f"{ref.path}: the reference frame shows no window ring while {path.name} does "
                "(a dark reference: lights off, lens cap?); expected the session's 0 kPa frame "
                "of the lit rig, framed as its other frames"
            )
        return f"ring position not checked: no ring found in the reference {ref.path.name}"
    else:
        ring = _coarse_ring(img)
        if not ring.found:
            return "ring position not checked: no ring found in this frame"
        moved = math.hypot(ring.cx - ref.ring.cx, ring.cy - ref.ring.cy) / ref.ring.radius
        grown = abs(ring.radius / ref.ring.radius - 1.0)
        if moved > RING_CENTRE_TOLERANCE:
            what = (
                f"its ring centre is {moved:.0%} of the ring radius away from the reference's "
                f"(tolerance {RING_CENTRE_TOLERANCE:.0%})"
            )
        elif grown > RING_RADIUS_TOLERANCE:
            what = (
                f"its ring radius differs from the reference's by {grown:.0%} "
                f"(tolerance {RING_RADIUS_TOLERANCE:.0%})"
            )
    if what:
        raise ImageError(
            f"{path}: does not match the reference frame {ref.path}: {what}; a session's "
            "frames and its reference must come from one camera set-up, same size and framing"
        )
    return ""


def _start(
    method: Method, images: list[Path], reference: Path | None, bit_depth: int | None, digest: bool
) -> tuple[int, _Reference | None]:
    """Start the method; the decode reduction k and the reference the frames must match (the
    method's own decode of it at 1/k, of its content read here once: the frame check and its
    measurement as a frame decode nothing more)."""
    content = None if reference is None else ImageFile.read(reference)
    started = method.start(images, content, bit_depth)
    k, img = started.reduction, started.reference
    if content is None:
        return k, None
    if img is None:  # a method breaking the protocol, not bad input
        raise TypeError(
            f"{method.name}: start() returned no reference image for {reference}; expected "
            "the reference decoded at 1/k (Started.reference)"
        )
    size = _file_size(img, k)
    sha = content.sha256() if digest else None
    return k, _Reference(content.path, size, _coarse_ring(img), img, sha)


def _decoded(
    path: Path, k: int, bit_depth: int | None, ref: _Reference | None, digest: bool
) -> tuple[np.ndarray, str | None]:
    """A frame decoded at 1/k and, with ``digest``, the sha256 of the content decoded (the
    reference's own decode where the frame is the reference: read and decoded once)."""
    if ref is not None and path == ref.path:
        return ref.image, ref.sha256
    content = ImageFile.read(path)
    return content.decode(k, bit_depth), content.sha256() if digest else None


def offset_for(
    method: Method, boundary: BoundaryOffset | None, scale: PixelScale | None
) -> BoundaryOffset | None:
    """The rig's boundary offset if it applies to ``method``: it was measured for this very
    model (None: no offset, or a method without a model, e.g. the classical routine).

    Raises:
        BoundaryOffsetError: the offset was measured for another model (stale), or no pixel
            scale converts it to pixels.
    """
    if boundary is None:
        return None
    sha = method.describe().get("model_sha256")  # hashes the model file: only when needed
    if sha is None:
        return None
    if sha != boundary.model_sha256:
        raise BoundaryOffsetError(
            f"{boundary.source}: its boundary offset was measured for the model with sha256 "
            f"{boundary.model_sha256[:12]}…, this run's model has {sha[:12]}…; measure it again "
            "for this model (`contactcal evaluate … --rig`) or remove the two boundary_offset keys"
        )
    if scale is None:
        raise BoundaryOffsetError(
            f"{boundary.source}: a boundary offset in mm needs the rig's pixel scale "
            "(mm_per_px and image_width_px in the same file)"
        )
    return boundary


def measure_files(
    files: Sequence[str | os.PathLike[str]],
    method: Method,
    reference: str | os.PathLike[str] | None = None,
    scale: PixelScale | None = None,
    progress: bool = False,
    bit_depth: int | None = None,
    boundary: BoundaryOffset | None = None,
    digest: bool = False,
) -> list[Measured]:
    """Measure each image file with ``method``.

    Every frame must match the reference: the same size, and (when the reference's ring is
    found) the ring within :data:`RING_CENTRE_TOLERANCE` and :data:`RING_RADIUS_TOLERANCE`.
    Every frame is checked (the check costs a few % of a frame's measurement); an unchecked
    position is said in the result's note.

    Args:
        files: image paths.
        method: a prepared-on-demand method (:func:`contactcal.infer.methods.registry.make_method`).
        reference: the session's zero-pressure frame; None → each frame is its own reference.
        scale: pixel scale for mm² (None → ``area_mm2`` is None).
        progress: show a progress bar on stderr.
        bit_depth: significant bits of 16-bit files (:func:`load_image`); None → from the file.
        boundary: the rig's boundary offset; applied to the areas of the model it was measured
            for (:func:`offset_for`, :func:`~contactcal.infer.pipeline.boundary.apply_offset`),
            not to another method's.
        digest: take each file's sha256 (:attr:`Measured.sha256`, ``reference_sha256``) from
            the content read and measured, for a record of the inputs (~1 ms per MB).

    Returns:
        One :class:`Measured` per file, in order.

    Raises:
        ImageError: an unreadable file, or a frame that does not match the reference (naming
            both; nothing is measured after it).
        BoundaryOffsetError: an offset measured for another model, or without a scale.
    """
    active = offset_for(method, boundary, scale)
    images = [Path(f) for f in files]
    reference = None if reference is None else Path(reference)
    k, ref = _start(method, images, reference, bit_depth, digest)
    out: list[Measured] = []
    it: Any = images
    if progress:
        from tqdm import tqdm

        it = tqdm(images, desc=f"measure ({method.name})", unit="frame", leave=False)
    for path in it:
        img, sha = _decoded(path, k, bit_depth, ref, digest)
        w, h = _file_size(img, k)
        note = method.NO_REFERENCE if ref is None else _check_frame(ref, path, img, (w, h))
        res = method.measure(img)  # in the file's pixels
        if active is not None and scale is not None:
            res = apply_offset(res, active.mm / scale.at_width(w), active.mm)
        if note:
            res = replace(res, note=f"{res.note}; {note}" if res.note else note)
        mm2 = None if scale is None else scale.area_mm2(res.area_px, w)
        applied = None if active is None else active.mm
        against = (None, None) if ref is None else (ref.path, ref.sha256)
        out.append(Measured(path, w, h, res, mm2, against[0], applied, sha, against[1]))
    return out


def same_file(path: Path, reference: Path) -> str | None:
    """How ``path`` is the ``reference`` file: ``"path"`` (the same file, also through another
    name or a link), ``"bytes"`` (a byte-identical copy), or None (another file)."""
    try:
        if os.path.samefile(path, reference):  # one file, under any name or link
            return "path"
        return "bytes" if filecmp.cmp(path, reference, shallow=False) else None
    except OSError:
        return None


def note_self_reference(
    measured: Sequence[Measured], reference: Path | None
) -> tuple[list[Measured], list[str]]:
    """Note the frames the change gate called unchanged that are the reference file itself.

    Compared with itself a frame never changes, so its "no contact" says nothing about contact
    (:data:`SELF_REFERENCE_NOTE`); the result (contact, area) stays as measured.

    Args:
        measured: the frames as measured against ``reference``.
        reference: the reference frame (None: nothing to note).

    Returns:
        ``(measured, warnings)``: every frame, those noted with the note appended; one
        ``warning: FILE: …`` line per noted frame, for the command to print.
    """
    out: list[Measured] = []
    warnings: list[str] = []
    for m in measured:
        how = None
        if reference is not None and m.result.note.startswith(UNCHANGED_NOTE):
            how = same_file(m.file, reference)
        if how is not None:
            said = SELF_REFERENCE_NOTE.format(how=how)
            m = replace(m, result=replace(m.result, note=f"{m.result.note}; {said}"))
            warnings.append(f"warning: {m.file}: {said}")
        out.append(m)
    return out, warnings

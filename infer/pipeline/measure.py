"""Measuring image files: the work behind ``measure`` (and the frames of ``calibrate``).

Image loading (:mod:`contactcal.infer.image.read`), a method (:mod:`contactcal.infer.methods`),
the pixel scale, and the check that every frame matches the session's reference frame.
"""

from __future__ import annotations

import filecmp
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.files.regular import refuse_non_file
from contactcal.infer.image.gray import ImageError
from contactcal.infer.image.read import (
    ImageFile,
    ImageSource,
    source_content,
    source_path,
    sources_of,
)
from contactcal.infer.methods.base import UNCHANGED_NOTE, AreaResult, Method, model_identity
from contactcal.infer.pipeline.boundary import BoundaryOffset, BoundaryOffsetError, apply_offset
from contactcal.infer.pipeline.frame_check import (
    FrameReference,
    check_frame,
    coarse_ring,
    file_size,
)
from contactcal.infer.pipeline.scale import PixelScale

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


def _start(
    method: Method,
    images: Sequence[ImageSource],
    reference: ImageSource | None,
    bit_depth: int | None,
    digest: bool,
) -> tuple[int, FrameReference | None]:
    """Start the method; the decode reduction k and the reference the frames must match (the
    method's own decode of it at 1/k, of its content read here once: the method's look at the
    frames, the frame check and its measurement as a frame read and decode nothing more)."""
    content = None if reference is None else source_content(reference)
    if content is not None:
        images = [content if source_path(f) == content.path else f for f in images]
    started = method.start(images, content, bit_depth)
    k, img = started.reduction, started.reference
    if content is None:
        return k, None
    if img is None:  # a method breaking the protocol, not bad input
        raise TypeError(
            f"{method.name}: start() returned no reference image for {reference}; expected "
            "the reference decoded at 1/k (Started.reference)"
        )
    size = file_size(img, k)
    sha = content.sha256() if digest else None
    return k, FrameReference(content.path, size, coarse_ring(img), img, sha)


def _decoded(
    source: ImageSource, k: int, bit_depth: int | None, ref: FrameReference | None, digest: bool
) -> tuple[np.ndarray, str | None]:
    """A frame decoded at 1/k and, with ``digest``, the sha256 of the content decoded (the
    reference's own decode where the frame is the reference: read and decoded once)."""
    if ref is not None and source_path(source) == ref.path:
        return ref.image, ref.sha256
    content = source_content(source)
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
    sha = model_identity(method)["model_sha256"]
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
    files: Sequence[ImageSource],
    method: Method,
    reference: ImageSource | None = None,
    scale: PixelScale | None = None,
    progress: bool = False,
    bit_depth: int | None = None,
    boundary: BoundaryOffset | None = None,
    digest: bool = False,
    contents: dict[Path, ImageFile] | None = None,
) -> list[Measured]:
    """Measure each image file with ``method``.

    Every frame must match the reference: the same size, and (when the reference's ring is
    found) the ring within :data:`~contactcal.infer.pipeline.frame_check.RING_CENTRE_TOLERANCE` and
    :data:`~contactcal.infer.pipeline.frame_check.RING_RADIUS_TOLERANCE`.
    Every frame is checked (the check costs a few % of a frame's measurement); an unchecked
    position is said in the result's note.

    Args:
        files: image paths (each read when it is measured), or their contents read already
            (:class:`~contactcal.infer.image.read.ImageFile`: a run that reads a frame for
            more than its measurement measures the content it read).
        method: a prepared-on-demand method (:func:`contactcal.infer.methods.registry.make_method`).
        reference: the session's zero-pressure frame (a path or its content, as ``files``);
            None → each frame is its own reference.
        scale: pixel scale for mm² (None → ``area_mm2`` is None).
        progress: show a progress bar on stderr.
        bit_depth: significant bits of 16-bit files (:func:`load_image`); None → from the file.
        boundary: the rig's boundary offset; applied to the areas of the model it was measured
            for (:func:`offset_for`, :func:`~contactcal.infer.pipeline.boundary.apply_offset`),
            not to another method's.
        digest: take each file's sha256 (:attr:`Measured.sha256`, ``reference_sha256``) from
            the content read and measured, for a record of the inputs (~1 ms per MB).
        contents: the contents the run holds, to use them for more than this measurement
            (None: none): the reference and then each of ``files`` not in it yet are read into
            it (:func:`~contactcal.infer.image.read.sources_of`) after the boundary offset's
            check, before the method starts, and measured from it.

    Returns:
        One :class:`Measured` per file, in order.

    Raises:
        ImageError: an unreadable file, or a frame that does not match the reference (naming
            both; nothing is measured after it).
        BoundaryOffsetError: an offset measured for another model, or without a scale.
    """
    active = offset_for(method, boundary, scale)
    if reference is not None and not isinstance(reference, ImageFile):  # not a frame's wording
        expected = "the session's zero-pressure frame (an image file)"
        refuse_non_file(reference, expected, ImageError)
    if contents is not None:  # read now: after the checks a run that holds none makes first
        reference = None if reference is None else sources_of([source_path(reference)], contents)[0]
        files = sources_of([source_path(f) for f in files], contents)
    images = [source_path(f) for f in files]
    k, ref = _start(method, files, reference, bit_depth, digest)
    out: list[Measured] = []
    it: Any = zip(images, files, strict=True)
    if progress:
        from tqdm import tqdm

        it = tqdm(it, desc=f"measure ({method.name})", total=len(images), unit="frame", leave=False)
    for path, source in it:
        img, sha = _decoded(source, k, bit_depth, ref, digest)
        w, h = file_size(img, k)
        note = method.NO_REFERENCE if ref is None else check_frame(ref, path, img, (w, h))
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


def same_file(
    path: Path, reference: Path, digests: tuple[str | None, str | None] = (None, None)
) -> str | None:
    """How ``path`` is the ``reference`` file: ``"path"`` (the same file, also through another
    name or a link), ``"bytes"`` (a byte-identical copy: by the sha256 ``digests`` of the two
    contents as measured where both are known, the files not read again; else by comparing
    the files), or None (another file)."""
    try:
        if os.path.samefile(path, reference):  # one file, under any name or link
            return "path"
        if None not in digests:
            return "bytes" if digests[0] == digests[1] else None
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
            how = same_file(m.file, reference, (m.sha256, m.reference_sha256))
        if how is not None:
            said = SELF_REFERENCE_NOTE.format(how=how)
            m = replace(m, result=replace(m.result, note=f"{m.result.note}; {said}"))
            warnings.append(f"warning: {m.file}: {said}")
        out.append(m)
    return out, warnings

"""The learned segmenter as a :class:`~contactcal.infer.methods.base.Method`.

It chooses its own JPEG decode: the U-Net resizes a crop around the window ring to its input size
anyway, so decoding at 1/k (libjpeg's DCT scaling, several times cheaper) changes nothing as long
as the crop stays at least the network's input size.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from types import MappingProxyType
from typing import Any

import cv2
import numpy as np

from contactcal.infer.image.frame import as_frame
from contactcal.infer.image.gray import reduce_area
from contactcal.infer.image.read import (
    ImageFile,
    ImageSource,
    source_content,
    source_jpeg_size,
    source_path,
)
from contactcal.infer.methods.base import UNCHANGED_NOTE, AreaResult, Started, load_reference
from contactcal.infer.methods.unet.postprocess import Segmentation, mask_in_input
from contactcal.infer.methods.unet.prepare import session_reference
from contactcal.infer.methods.unet.runner import OnnxSegmenter
from contactcal.infer.methods.unet.shrink import (
    deployed_shrink,
    fitting_reduction,
    shrunk_reference,
)

#: The note of a frame measured without a reference frame, by what the model does then.
NO_REFERENCE_NOTES = MappingProxyType(
    {
        "self": "no reference frame: the frame served as its own reference (the model expects "
        "the session's 0 kPa frame; expect larger errors)",
        "blank": "no reference frame: the blank placeholder stood in for it (the model was "
        "trained for this with reference dropout); crop around the frame's own ring if found",
        "none": "no reference frame: crop around the frame's own ring if found (a single-frame "
        "model)",
    }
)


#: Said of a frame cropped without any window ring found (the image centre's fallback box).
NO_RING_NOTE = (
    "no window ring found in this frame (nor in its reference, if any): cropped around the "
    "image centre instead (is this a rig frame?)"
)


class UnetMethod:
    """The ONNX U-Net (:class:`~contactcal.infer.methods.unet.runner.OnnxSegmenter`).

    Args:
        model: ONNX file (None → the shipped model).
        threads: onnxruntime intra-op threads.
        outline: map the mask back to input pixels for an outline (overlays; costs a full-size
            warp per frame).
        change_gate: apply the model's change gate (metadata ``min_change``); False turns it
            off (``--no-change-gate``: for a rig whose contacts change the image less than the
            validation renders' did), which ``describe()`` records.
        content: the model file's content, already read (see
            :class:`~contactcal.infer.methods.unet.runner.OnnxSegmenter`); None reads it.
    """

    name = "unet"

    def __init__(
        self,
        model: str | os.PathLike[str] | None = None,
        threads: int = 1,
        outline: bool = False,
        change_gate: bool = True,
        content: bytes | None = None,
    ) -> None:
        self.segmenter = OnnxSegmenter(model, threads=threads, content=content)
        spec = self.segmenter.spec
        self.model_min_change = spec.min_change
        self.change_gate = change_gate and spec.min_change > 0.0
        if not change_gate:
            spec = dataclasses.replace(spec, min_change=0.0)
            self.segmenter.spec = spec
        mode = spec.preprocess.no_reference if spec.uses_reference else "none"
        self.NO_REFERENCE = NO_REFERENCE_NOTES[mode]
        self.outline = outline
        self.reference = session_reference(None)
        self.reduction = 1  # the frames arrive decoded at 1/reduction (reduced JPEG decode)
        self.shrink: int | None = None  # the method shrinks them further (None: not decided)

    def start(
        self,
        files: Sequence[ImageSource],
        reference: ImageFile | None,
        bit_depth: int | None = None,
    ) -> Started:
        """Choose the decode reduction from the ring's size, then prepare the reference.

        A reduction k > 1 is used only when every file is a JPEG of one size divisible by k (so
        areas scale back exactly by k²) and the ring crop stays >= the network input at 1/k
        (:func:`fitting_reduction`). The ring is searched on the 1/8 decode; at k = 8 that
        search is the session's, and that decode is the reference returned (at k < 8 the
        reference's content, read once, is decoded again at 1/k).
        """
        sources = [*files, *([reference] if reference is not None else [])]
        jpegs = bool(sources) and all(
            source_path(s).suffix.lower() in (".jpg", ".jpeg") for s in sources
        )
        sizes = {source_jpeg_size(s) for s in sources} if jpegs else set()
        if len(sizes) != 1:  # not all JPEG, or JPEGs of several sizes: decode fully
            ref = load_reference(reference, bit_depth=bit_depth)
            self.set_reference(ref)
            return Started(1, ref)
        (h, w), cfg = sizes.pop(), self.segmenter.spec.preprocess
        first = reference if reference is not None else source_content(files[-1])
        coarse = session_reference(first.decode(8, bit_depth), cfg)
        k = 1
        if coarse.box is not None:  # the ring was found
            k = fitting_reduction(coarse.box.side * 8, (h, w), cfg)
        if k == 8 and reference is not None:
            self.reference, self.reduction, self.shrink = coarse, 8, 1
            return Started(8, coarse.gray)
        ref = load_reference(reference, k, bit_depth)
        self.set_reference(ref, k)
        return Started(k, ref)

    def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
        """Fix the crop and the reference channel from the session's zero-pressure frame.

        Frames decoded at full size (``reduction`` 1 and no reduced JPEG decode) are shrunk by
        the method itself, by the integer factor the reduced JPEG decode would have used
        (:func:`fitting_reduction`, :func:`~contactcal.infer.image.gray.reduce_area`): what
        the network sees then does not depend on how the frame was decoded, and two
        full-resolution resizes of the crop (~9 ms each at 2592×1944) become one cheap
        integer one. Without a reference the first measured frame's ring decides.
        """
        cfg = self.segmenter.spec.preprocess
        self.reduction, self.shrink = reduction, None
        if reference is None:
            self.reference = session_reference(None, cfg)
            return
        gray = as_frame(reference, "reference frame")
        self.reference, self.shrink = shrunk_reference(gray, cfg)

    def _shrunk(self, image: np.ndarray) -> tuple[np.ndarray, int]:
        """The frame at the session's shrink factor, and that factor (decided here when there
        is no reference; a frame whose sides it does not divide is not shrunk)."""
        gray = as_frame(image, "frame")
        if self.shrink is None:
            self.shrink = deployed_shrink(gray, self.segmenter.spec.preprocess)
        k, full = self.shrink, self.reference.gray
        if k > 1 and full is not None and gray.shape != (full.shape[0] * k, full.shape[1] * k):
            raise ValueError(
                f"frame size {gray.shape[1]}×{gray.shape[0]} differs from the reference "
                f"frame size {full.shape[1] * k}×{full.shape[0] * k}"
            )
        if gray.shape[0] % k or gray.shape[1] % k:
            return gray, 1
        return reduce_area(gray, k), k

    def measure(self, image: np.ndarray) -> AreaResult:
        """Segment; the contour is the kept region's outline in input pixels.

        The result carries the model's stated interval of the area (``area_interval_px``,
        :func:`~contactcal.infer.methods.unet.postprocess.boundary_band`).
        """
        image, shrink = self._shrunk(image)
        k = self.reduction * shrink
        seg = self.segmenter.segment(image, self.reference)
        if not seg.contact:
            res = AreaResult(False, 0.0, self._note(seg), None, area_interval_px=seg.interval_px)
            return res.upscaled(k)
        contour = None
        if self.outline:
            mask = mask_in_input(seg, image.shape[:2]).astype(np.uint8)
            contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            contour = max(contours, key=cv2.contourArea) if contours else None
        note = self._note(seg)
        res = AreaResult(
            True, seg.area_px, note, contour, seg.soft_area_px, seg.interval_px, seg.perimeter_px
        )
        return res.upscaled(k)

    def _note(self, seg: Segmentation) -> str:
        """Why a frame has no contact ("no contact", or the change gate's numbers); for a contact
        that only ``--no-change-gate`` kept, that it did (otherwise a contact's note is "")."""
        limit = f"{self.model_min_change:.3f}"
        ring = "" if seg.ring_found else f"; {NO_RING_NOTE}"
        if seg.unchanged:
            return f"{UNCHANGED_NOTE} (change {seg.change:.3f} < {limit}){ring}"
        if not seg.contact:
            return f"no contact{ring}"
        if seg.change is not None and seg.change < self.model_min_change:  # the gate is off
            return f"kept by --no-change-gate: change {seg.change:.3f} < {limit}{ring}"
        return ring[2:]

    def describe(self) -> dict[str, Any]:
        """The model file, its sha256, its training ``data_digest``, its deployment spec (as the
        model states it) and whether its change gate is enabled (``on``, ``off
        (--no-change-gate)`` or ``none in the model``; it acts only on frames measured with a
        reference frame)."""
        seg, spec = self.segmenter, self.segmenter.spec
        gate = "on" if self.change_gate else "off (--no-change-gate)"
        return {
            "name": self.name,
            "model": str(seg.path.resolve()),
            "model_sha256": seg.sha256,  # of the content loaded, not read again
            "data_digest": seg.metadata.get("data_digest"),
            "spec": {
                "channels": spec.channels,
                "preprocess": dataclasses.asdict(spec.preprocess),
                "threshold": spec.threshold,
                "min_contact_area_px": spec.min_contact_area_px,
                "interval": None if spec.interval is None else dataclasses.asdict(spec.interval),
                "region": spec.region,
                "min_change": self.model_min_change,
            },
            "change_gate": gate if self.model_min_change > 0.0 else "none in the model",
        }

"""What every contact-area method provides, so the pipeline and the benchmark treat them alike.

A method is started once per session (it decodes the session's zero-pressure frame, as its caller
read it, and says at which JPEG decode reduction the frames are to be loaded), then measures
frames. Areas and outlines are always in pixels of the input FILE, whatever reduction the method
chose.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from contactcal.infer.image.read import ImageFile, ImageSource

#: The start of a frame's note when a method's change gate found its region unchanged from the
#: reference frame (the U-Net's ``min_change``); ``calibrate`` looks for it to name the gate.
UNCHANGED_NOTE = "no contact: the region is unchanged from the reference frame"


@dataclass(frozen=True)
class AreaResult:
    """One frame's outcome.

    ``area_interval_px`` is the method's stated interval of the contact area (input pixels; for
    the U-Net a 90 % interval calibrated on validation data, level in the model's metadata). It
    always contains ``area_px``; without contact it is ``(0, upper)``. None when the method states
    none (the classical routine states none).
    """

    contact: bool
    area_px: float  # in pixels of the input file; 0.0 when no contact
    note: str  # "" or why there is no contact
    contour: np.ndarray | None  # (N, 1, 2) int32 outline in input pixels, for overlays
    soft_area_px: float | None = None  # U-Net: probabilities summed around the region, hull px as 1
    area_interval_px: tuple[float, float] | None = None  # (lower, upper) px; None: none stated
    perimeter_px: float | None = None  # px, the contact region's outline length (the U-Net's;
    #   None: not measured); a boundary offset of d px changes the area by about d·perimeter

    def upscaled(self, k: int) -> AreaResult:
        """The same result for an image ``k`` times larger per side (areas and interval × k²)."""
        if k == 1:
            return self
        soft = None if self.soft_area_px is None else self.soft_area_px * k * k
        perimeter = None if self.perimeter_px is None else self.perimeter_px * k
        contour = None if self.contour is None else self.contour * k
        iv = self.area_interval_px
        interval = None if iv is None else (iv[0] * k * k, iv[1] * k * k)
        return replace(
            self,
            area_px=self.area_px * k * k,
            contour=contour,
            soft_area_px=soft,
            area_interval_px=interval,
            perimeter_px=perimeter,
        )


@dataclass(frozen=True)
class Started:
    """What :meth:`Method.start` decided for a session of image files."""

    reduction: int  # k: load the frames with ``load_image(path, reduce=k)`` (1: full decode)
    #: The session's reference frame as the method decoded it, ``(H/k, W/k) uint8`` (None
    #: without one): the pipeline checks every frame against it without decoding it again.
    #: Not compared (``==`` compares the reduction only; arrays have no truth value).
    reference: np.ndarray | None = field(compare=False)


class Method(Protocol):
    """What every contact-area method provides."""

    name: str

    def start(
        self,
        files: Sequence[ImageSource],
        reference: ImageFile | None,
        bit_depth: int | None = None,
    ) -> Started:
        """Begin a session of image files: decode the reference, choose the decode reduction k.

        The frames are then to be loaded with ``load_image(path, reduce=k, bit_depth=...)``;
        k > 1 only when every file (frames and reference) has one size whose sides divide by
        k, so a frame decoded at 1/k is exactly k times smaller per side.
        ``bit_depth`` is the significant bits of 16-bit files (None: from the file). The
        reference is decoded from the content the caller read (whose digest it records), and
        returned decoded at 1/k with k, so that nothing decodes it again. ``files`` are the
        frames' paths, or their contents where the caller read them already (what the method
        needs of them, e.g. a JPEG's header, is then taken from that content).
        """

    def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
        """Use the session's reference frame ``(H, W) uint8`` (or None), decoded at 1/reduction."""

    def measure(self, image: np.ndarray) -> AreaResult:
        """Measure one ``(H, W) uint8`` frame; areas in pixels of the undecimated file."""

    def describe(self) -> dict[str, Any]:
        """The method's configuration as plain JSON values, for records (``calibration.json``);
        a method with a model file states it as :data:`MODEL_KEYS`."""

    #: What the method does without the session's reference frame: the pipeline (``measure``,
    #: ``calibrate``) notes it in every result then; ``measure()`` itself does not.
    NO_REFERENCE: str


#: The keys of ``describe()`` that name a method's model: its file (absolute path) and the
#: sha256 of the content loaded (the U-Net's; a method without a model states neither).
MODEL_KEYS = ("model", "model_sha256")


def model_identity(method: Method) -> dict[str, str | None]:
    """The model ``method`` measures with, as its ``describe()`` states it (``calibration.json``
    ``method_config``): ``{"model": path, "model_sha256": sha256}``, both None for a method
    without a model (the classical routine)."""
    described = method.describe()
    return {key: described.get(key) for key in MODEL_KEYS}


def load_reference(
    reference: ImageFile | None, reduction: int = 1, bit_depth: int | None = None
) -> np.ndarray | None:
    """The session's reference frame decoded at 1/reduction, or None."""
    return None if reference is None else reference.decode(reduction, bit_depth)

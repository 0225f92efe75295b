"""How a run measures its frames: one frozen config, built once per run and passed whole.

``measure``, ``calibrate`` (frames and video), ``evaluate`` and the overlays all measure frames
the same way: a method by name, and what it is given (the model, the rig's scale and boundary
offset, the frames' bit depth, the change gate, threads, outlines). The command line builds it
in one place (:func:`~contactcal.infer.pipeline.args.measure_options`).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from contactcal.infer.image.read import ImageFile, ImageSource
    from contactcal.infer.methods.base import Method
    from contactcal.infer.pipeline.boundary import BoundaryOffset
    from contactcal.infer.pipeline.measure import Measured
    from contactcal.infer.pipeline.scale import PixelScale


@dataclass(frozen=True)
class MeasureOptions:
    """What a run's methods are given (every field has the command line's default).

    The method's name is not part of it: ``evaluate`` and the overlays measure with several.
    """

    #: ONNX file of the U-Net (``--model``); None: the shipped one. Ignored by the classical
    #: routine.
    model: str | os.PathLike[str] | None = None
    #: The rig's pixel scale (``--mm-per-px`` / ``--rig`` / ``rig.json``); None: areas in px
    #: only (``area_mm2`` null).
    scale: PixelScale | None = None
    #: The rig's boundary offset (rig config), applied to the U-Net model it was measured for;
    #: None: none.
    boundary: BoundaryOffset | None = None
    #: Significant bits of 16-bit frames (``--bit-depth``); None: read from each file.
    bit_depth: int | None = None
    #: Apply the U-Net model's change gate; False: ``--no-change-gate`` (recorded).
    change_gate: bool = True
    #: onnxruntime intra-op threads (``--threads``): 1 is the benchmarked default.
    threads: int = 1
    #: Keep each frame's outline in input pixels (overlays; costs a full-size warp per frame).
    outline: bool = False
    #: The U-Net model file's content, read once (:meth:`read_model`): every method built from
    #: these options loads it, the file not read again; None: each :meth:`method` reads the file.
    model_content: bytes | None = field(default=None, repr=False)

    def read_model(self) -> MeasureOptions:
        """These options with the U-Net's model file (:attr:`model`, None: the shipped one)
        read once into :attr:`model_content`, for a run that builds its methods from one read.

        Raises:
            ValueError: a missing or unreadable :attr:`model` file, named as the option that
                gave it (``--model MODEL: ...``); ``ModelError``: an unreadable shipped model.
        """
        from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, read_model

        with self._model_refused():
            content = read_model(DEFAULT_MODEL if self.model is None else Path(self.model))
        return replace(self, model_content=content)

    def method(self, name: str, outline: bool | None = None) -> Method:
        """The method ``name`` (``"unet"`` / ``"classical"``) as these options configure it.

        Args:
            name: method name (:data:`~contactcal.infer.methods.registry.METHODS`).
            outline: overrides :attr:`outline` (None: keep it).

        Raises:
            ValueError: unknown method; an unusable :attr:`model` file, named as the option
                that gave it (``--model MODEL: ...``); ``ModelError``: an unusable shipped model.
        """
        from contactcal.infer.methods.registry import make_method

        keep = self.outline if outline is None else outline
        with self._model_refused():
            return make_method(
                name,
                self.model,
                self.threads,
                keep,
                change_gate=self.change_gate,
                content=self.model_content,
            )

    @contextmanager
    def _model_refused(self) -> Iterator[None]:
        """An unusable :attr:`model` file's ``ModelError`` as the ``ValueError`` naming the
        option that gave it (``--model MODEL: ...``); the shipped model's as it is."""
        from contactcal.infer.methods.unet.spec import ModelError, by_model_option

        try:
            yield
        except ModelError as exc:
            if self.model is None:
                raise
            raise by_model_option("--model", self.model, self.model, exc) from None

    def measure(
        self,
        files: Sequence[ImageSource],
        method: Method,
        reference: ImageSource | None,
        digest: bool = False,
        contents: dict[Path, ImageFile] | None = None,
    ) -> list[Measured]:
        """``files`` (paths or contents read already) measured with ``method`` against
        ``reference``, with this run's scale, bit depth and boundary offset
        (:func:`~contactcal.infer.pipeline.measure.measure_files`; ``digest``: with the sha256
        of each file's content measured, for a record; ``contents``: the contents the run
        holds, each file read into it once)."""
        from contactcal.infer.pipeline.measure import measure_files

        return measure_files(
            files,
            method,
            reference,
            self.scale,
            bit_depth=self.bit_depth,
            boundary=self.boundary,
            digest=digest,
            contents=contents,
        )

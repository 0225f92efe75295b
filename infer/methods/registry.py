"""Methods by name: what ``--method`` chooses."""

from __future__ import annotations

import os

from contactcal.infer.methods.base import Method
from contactcal.infer.methods.classical import ClassicalMethod

#: Method names; the first is the default of ``measure`` and ``calibrate``.
METHODS = ("unet", "classical")


def make_method(
    name: str,
    model: str | os.PathLike[str] | None = None,
    threads: int = 1,
    outline: bool = False,
    change_gate: bool = True,
    content: bytes | None = None,
) -> Method:
    """Build a method by name.

    Args:
        name: ``"unet"`` or ``"classical"``.
        model: ONNX file for ``"unet"`` (None → the shipped model).
        threads: onnxruntime intra-op threads for ``"unet"``.
        outline: compute the U-Net's outline in input pixels (for overlays; costs a full-size
            warp per frame). The classical ellipse outline is always given.
        change_gate: apply the U-Net model's change gate (``min_change``); False measures every
            kept region as contact (``--no-change-gate``), recorded in ``describe()``.
        content: for ``"unet"``, the model file's content already read (see
            :class:`~contactcal.infer.methods.unet.runner.OnnxSegmenter`); None reads it.

    Raises:
        ValueError: unknown method name; ``ModelError`` for an unusable model file.
    """
    if name == "classical":
        return ClassicalMethod()
    if name == "unet":
        from contactcal.infer.methods.unet.method import UnetMethod

        return UnetMethod(model, threads, outline, change_gate, content)
    raise ValueError(f"unknown method {name!r}; expected one of {', '.join(METHODS)}")

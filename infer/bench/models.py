"""The U-Net models ``contactcal bench`` scores, each file read once before any work.

Every session bench builds from a model (the error tables, the timing, the robustness suite,
each cross-check set) and the sha256 ``results.json`` records of it (``models``) come from that
one read: a model re-exported into the same path while bench runs is neither scored as half one
model and half another nor recorded as another than the one scored.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from contactcal.infer.bench.accuracy import variant_name
from contactcal.infer.methods.base import Method
from contactcal.infer.methods.registry import make_method
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter, read_model
from contactcal.infer.methods.unet.spec import ModelError, by_model_option


@dataclass(frozen=True)
class BenchModel:
    """A U-Net model file as bench read it (:func:`load_models`)."""

    name: str  # the method name of its rows: "unet" (--model, or the shipped one) or "unet[LABEL]"
    path: Path  # the file (without --model, the installed shipped model's)
    given: str  # how it was named, for messages ("--model PATH", "--variant LABEL=PATH", ...)
    content: bytes = field(repr=False)  # the file's content, read once: all is built from it
    sha256: str  # of ``content`` (OnnxSegmenter.sha256 of the load that checked it)

    def method(self, name: str = "unet", threads: int = 1, outline: bool = False) -> Method:
        """Method ``name`` (see :func:`~contactcal.infer.methods.registry.make_method`) with
        this model as its U-Net, built from ``content`` (the file is not read again)."""
        return make_method(name, self.path, threads, outline, content=self.content)


def load_models(
    model: str | os.PathLike[str] | None, variants: Sequence[tuple[str, str]] = ()
) -> list[BenchModel]:
    """Read ``model`` (None: the shipped one) and each variant's file once, and check each loads.

    Args:
        model: the U-Net's ONNX file (``--model``; None: the shipped model).
        variants: further models ``(label, path)`` (``--variant LABEL=PATH``).

    Returns:
        The U-Net's model first, then the variants' in order.

    Raises:
        ValueError: a missing or unusable ``model`` or variant file, its option named
            (``--variant LABEL=PATH: ...``); ``ModelError`` for an unusable shipped model.
    """
    shipped = f"the shipped model {DEFAULT_MODEL}, which bench scores without --model"
    named = [("unet", DEFAULT_MODEL, shipped, None)]
    if model is not None:
        named = [("unet", Path(model), f"--model {model}", ("--model", model))]
    for label, path in variants:
        given = ("--variant", f"{label}={path}")
        named.append((variant_name(label), Path(path), " ".join(given), given))
    out = []
    for name, path, given, option in named:
        try:
            content = read_model(path)
            sha256 = OnnxSegmenter(path, content=content).sha256
        except ModelError as exc:
            if option is None:
                raise
            raise by_model_option(*option, path, exc) from None
        out.append(BenchModel(name, path, given, content, sha256))
    return out

"""The learned contact segmenter at deployment: an ONNX model run with onnxruntime only.

Reads as prepare → run → postprocess: :func:`~contactcal.infer.methods.unet.prepare.prepare`
(the same code as training), the network, and
:func:`~contactcal.infer.methods.unet.postprocess.postprocess` (the same decision as model
selection). Everything about the model's input and output comes from its metadata
(:mod:`contactcal.infer.methods.unet.spec`).
"""

from __future__ import annotations

import dataclasses
import os
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.files.regular import read_input_bytes
from contactcal.infer.methods.unet.postprocess import Segmentation, postprocess
from contactcal.infer.methods.unet.prepare import (
    SessionReference,
    prepare,
    reference_difference,
)
from contactcal.infer.methods.unet.spec import ModelError, ModelSpec, read_spec

if TYPE_CHECKING:
    from onnxruntime import InferenceSession, SessionOptions

#: The shipped model: package data of ``contactcal.models`` (the repository's ``models/``), in
#: wheels and editable installs alike (pip installs packages as folders, so this is a real path).
DEFAULT_MODEL = Path(str(resources.files("contactcal.models").joinpath("contact_unet.onnx")))


def _dims(shape: list[object]) -> str:
    return "(" + ", ".join(str(d) for d in shape) + ")"


def check_graph_io(ort_session: InferenceSession, spec: ModelSpec, path: Path) -> None:
    """Check that the graph takes and gives what the metadata promises.

    Expected: one float input ``(N, C, S, S)`` with ``C == spec.channels`` (and ``N == 1``,
    ``S == input_size`` where static) and a float output ``(N, 1, S, S)`` of logits (dynamic
    dimensions are accepted).

    Args:
        ort_session: the ``onnxruntime.InferenceSession``.
        spec: the model's metadata.
        path: the model file, for messages.

    Raises:
        ModelError: another input or output; the message names the file and what was expected.
    """
    s = spec.preprocess.input_size
    inputs, outputs = ort_session.get_inputs(), ort_session.get_outputs()
    checks = (
        ("input", inputs, (1, spec.channels, s, s)),
        ("output", outputs, (1, 1, s, s)),
    )
    for role, args, want in checks:
        shape = list(args[0].shape) if len(args) == 1 else []
        if (
            len(args) == 1
            and args[0].type == "tensor(float)"
            and len(shape) == 4
            and all(not isinstance(d, int) or d == w for d, w in zip(shape, want, strict=True))
        ):
            continue
        got = ", ".join(f"{a.type} {_dims(a.shape)}" for a in args) or "none"
        raise ModelError(
            f"{path}: expected one float {role} of shape {_dims(['N', want[1], s, s])} "
            f"(as its metadata says), got {got}; use a model written by `contactcal export`"
        )


def check_output_shape(got: tuple[int, ...], spec: ModelSpec, path: Path) -> None:
    """A run's output must be ``(1, 1, S, S)`` logits for the ``(1, C, S, S)`` input.

    :func:`check_graph_io` accepts dynamic output dimensions, which only a run resolves: a graph
    that gives two channels, another spatial size or another rank would otherwise measure a
    wrong map. Checked on every run (a tuple comparison), so that no extra run is paid.

    Args:
        got: the output's shape.
        spec: the model's metadata (channels, input size).
        path: the model file, for messages.

    Raises:
        ModelError: another shape; the message names the file and both shapes.
    """
    s = spec.preprocess.input_size
    if got != (1, 1, s, s):
        raise ModelError(
            f"{path}: expected an output of shape {_dims([1, 1, s, s])} for a "
            f"{_dims([1, spec.channels, s, s])} input (as its metadata says), got "
            f"{_dims(list(got))}; use a model written by `contactcal export`"
        )


def static_dims(shape: list[object], spec: ModelSpec) -> dict[str, int]:
    """Values for the input's named free dimensions: deployment runs one ``(1, C, S, S)`` input.

    Fixing them when the session is built lets onnxruntime optimise for the known shape (among
    other things it folds the graph's Shape → Resize size arithmetic into constants): on one
    thread the shipped model took 2.6-3.0 ms instead of 3.4-3.8 ms in side-by-side runs, with
    the same logits to float rounding. Static or unnamed dimensions stay as they are.

    Args:
        shape: the graph input's shape as onnxruntime reports it (ints, names or None).
        spec: the model's metadata (channels, input size).

    Returns:
        ``{dimension name: value}`` for each named dimension (empty when there is none).
    """
    s = spec.preprocess.input_size
    want = (1, spec.channels, s, s)
    return {d: w for d, w in zip(shape, want, strict=False) if isinstance(d, str) and d}


def _session(path: Path, data: bytes, opts: SessionOptions) -> InferenceSession:
    """``onnxruntime.InferenceSession`` of the model ``data`` read from ``path``, on the CPU;
    ModelError (naming ``path``) when unloadable."""
    import onnxruntime as ort

    try:
        return ort.InferenceSession(data, opts, providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises its own exception types
        raise ModelError(f"{path}: not a loadable ONNX model ({exc})") from exc


def read_model(path: Path) -> bytes:
    """The content of model file ``path``, read once for everything built from it (pass it as
    :class:`OnnxSegmenter`'s ``content``); ModelError (naming it) when missing, a folder or
    unreadable."""
    try:
        return read_input_bytes(path, "the ONNX model file (e.g. contact_unet.onnx)", ModelError)
    except (FileNotFoundError, NotADirectoryError):  # also a link to nothing, a path under a file
        raise ModelError(f"{path}: no such model file") from None
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the model ({exc.strerror})") from None


def sigmoid(logits: np.ndarray) -> np.ndarray:
    """``1 / (1 + exp(-clip(logits, ±30)))`` in float32: probabilities without overflow.

    One new array, updated in place; logits of another dtype are cast to float32 first (the
    network's are float32).
    """
    p = np.clip(logits, -30.0, 30.0, dtype=np.float32)
    np.negative(p, out=p)
    np.exp(p, out=p)
    p += np.float32(1.0)
    return np.reciprocal(p, out=p)


class OnnxSegmenter:
    """Runs the exported U-Net with onnxruntime.

    Args:
        path: ONNX file (default: the shipped ``models/contact_unet.onnx``).
        threads: intra-op threads (1 is the benchmarked default: the model is small, and
            calibration runs beside other work).
        content: the model file's content, already read from ``path`` by the caller (a tool
            that also rewrites the model); None reads it here.

    Raises:
        ModelError: missing, unloadable, without valid contactcal metadata, or with a graph
            input/output that does not match it (an output shape only a run resolves is
            checked on each run).
    """

    def __init__(
        self,
        path: str | os.PathLike[str] | None = None,
        threads: int = 1,
        content: bytes | None = None,
    ) -> None:
        import onnxruntime as ort

        self.path = Path(path) if path is not None else DEFAULT_MODEL
        # read once: both sessions and the recorded sha256 are of this content
        data = read_model(self.path) if content is None else content
        #: sha256 of the model content loaded (lower-case hex)
        self.sha256 = sha256_bytes(data)
        # A cheap unoptimised session reads the metadata; the one that runs is built with the
        # input's free dimensions fixed to what deployment feeds it (static_dims).
        cheap = ort.SessionOptions()
        cheap.intra_op_num_threads = 1
        cheap.graph_optimization_level = ort.GraphOptimizationLevel.ORT_DISABLE_ALL
        probe = _session(self.path, data, cheap)
        self.metadata = dict(probe.get_modelmeta().custom_metadata_map)
        self.spec = read_spec(self.metadata, self.path)
        check_graph_io(probe, self.spec, self.path)
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads
        opts.inter_op_num_threads = 1
        opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        # Measured on the shipped model at its fixed shape: without the memory pattern a run
        # still takes ~2.7 ms, and the session skips a second slow (~10 ms) first-use run.
        opts.enable_mem_pattern = False
        for name, value in static_dims(probe.get_inputs()[0].shape, self.spec).items():
            opts.add_free_dimension_override_by_name(name, value)
        self.ort_session = _session(self.path, data, opts)  # checked above: same graph, fixed dims
        self.input_name = self.ort_session.get_inputs()[0].name

    def probabilities(self, x: np.ndarray) -> np.ndarray:
        """Run the network on a ``(C, S, S)`` input; returns ``(S, S) float32`` probabilities."""
        feed = np.ascontiguousarray(x[None], dtype=np.float32)  # no copy when already so
        logits = self.ort_session.run(None, {self.input_name: feed})[0]
        check_output_shape(logits.shape, self.spec, self.path)
        return sigmoid(logits[0, 0])

    def segment(self, gray: np.ndarray, reference: SessionReference) -> Segmentation:
        """Segment one ``(H, W) uint8`` frame of a session (see :func:`session_reference`)."""
        cfg = self.spec.preprocess
        prep = prepare(gray, reference, cfg, self.spec.channels)
        prob = self.probabilities(prep.x)
        diff = reference_difference(prep.x, reference, self.spec.uses_reference)
        seg = postprocess(prob, prep.box, gray.shape[:2], self.spec, diff)
        return seg if prep.ring.found else dataclasses.replace(seg, ring_found=False)

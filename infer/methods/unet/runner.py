"""The learned contact segmenter at deployment: an ONNX model run with onnxruntime only.

Reads as prepare → run → postprocess: :func:`~contactcal.infer.methods.unet.prepare.prepare`
(the same code as training), the network, and
:func:`~contactcal.infer.methods.unet.postprocess.postprocess` (the same decision as model
selection). Everything about the model's input and output comes from its metadata
(:mod:`contactcal.infer.methods.unet.spec`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from contactcal.infer.methods.unet.postprocess import Segmentation, postprocess
from contactcal.infer.methods.unet.prepare import SessionReference, prepare
from contactcal.infer.methods.unet.spec import ModelError, read_spec

#: The shipped model (source tree; present in editable installs and the repository).
DEFAULT_MODEL = Path(__file__).resolve().parents[3] / "models" / "contact_unet.onnx"


def sigmoid(logits: np.ndarray) -> np.ndarray:
    """Probabilities from logits, float32, without overflow."""
    return (1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))).astype(np.float32)


class OnnxSegmenter:
    """Runs the exported U-Net with onnxruntime.

    Args:
        path: ONNX file (default: the shipped ``models/contact_unet.onnx``).
        threads: intra-op threads (1 is the benchmarked default: the model is small, and
            calibration runs beside other work).

    Raises:
        ModelError: missing, unloadable, or without valid contactcal metadata.
    """

    def __init__(self, path: str | os.PathLike[str] | None = None, threads: int = 1) -> None:
        import onnxruntime as ort

        self.path = Path(path) if path is not None else DEFAULT_MODEL
        if not self.path.is_file():
            raise ModelError(f"{self.path}: no such model file")
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads
        opts.inter_op_num_threads = 1
        opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        try:
            self.ort_session = ort.InferenceSession(
                str(self.path), opts, providers=["CPUExecutionProvider"]
            )
        except Exception as exc:  # onnxruntime raises its own exception types
            raise ModelError(f"{self.path}: not a loadable ONNX model ({exc})") from exc
        self.metadata = dict(self.ort_session.get_modelmeta().custom_metadata_map)
        self.spec = read_spec(self.metadata, self.path)
        self.input_name = self.ort_session.get_inputs()[0].name

    def probabilities(self, x: np.ndarray) -> np.ndarray:
        """Run the network on a ``(C, S, S)`` input; returns ``(S, S) float32`` probabilities."""
        logits = self.ort_session.run(None, {self.input_name: x[None].astype(np.float32)})[0]
        return sigmoid(logits[0, 0])

    def segment(self, gray: np.ndarray, reference: SessionReference) -> Segmentation:
        """Segment one ``(H, W) uint8`` frame of a session (see :func:`session_reference`)."""
        cfg = self.spec.preprocess
        prep = prepare(gray, reference, cfg, self.spec.channels)
        prob = self.probabilities(prep.x)
        return postprocess(prob, prep.box, gray.shape[:2], self.spec)

"""The learned contact segmenter at deployment: an ONNX model run with onnxruntime only.

The model's metadata (written by ``contactcal export``) carries everything needed to feed it: the
network input size, the channels (frame, and the session's zero-pressure frame when the model was
trained with it), the preprocessing config, the probability threshold and the minimum contact
area. Pre-processing is the same code as in training (:mod:`contactcal.infer.preprocess`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, fields
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.preprocess import (
    CropBox,
    PreprocessConfig,
    crop_box,
    from_network,
    locate_ring,
    to_network,
    valid_window,
)

#: The shipped model (source tree; present in editable installs and the repository).
DEFAULT_MODEL = Path(__file__).resolve().parents[1] / "models" / "contact_unet.onnx"


class ModelError(ValueError):
    """A model file that cannot be used; the message names the file."""


@dataclass(frozen=True)
class ModelSpec:
    """What the model's metadata says about its input and output."""

    channels: int  # 1 = frame only, 2 = frame + the session's zero-pressure frame
    preprocess: PreprocessConfig  # crop, input size and normalisation used in training
    threshold: float  # probability above which a network pixel is contact
    min_contact_area_px: float  # network pixels; smaller predicted regions are "no contact"


@dataclass(frozen=True)
class Segmentation:
    """One frame's prediction. Areas in input pixels."""

    contact: bool
    area_px: float  # thresholded mask, largest connected region only (0.0 without contact)
    soft_area_px: float  # sum of probabilities over the same region's neighbourhood (sub-pixel)
    prob: np.ndarray  # (S, S) float32 probabilities in network pixels
    mask_net: np.ndarray  # (S, S) bool, the kept region in network pixels
    box: CropBox  # crop that maps network pixels to input pixels


def read_spec(meta: dict[str, str], path: Path) -> ModelSpec:
    """Parse and check the metadata written by ``contactcal export``."""
    try:
        pre = json.loads(meta["preprocess"])
        names = {f.name for f in fields(PreprocessConfig)}
        spec = ModelSpec(
            channels=int(meta["channels"]),
            preprocess=PreprocessConfig(**{k: v for k, v in pre.items() if k in names}),
            threshold=float(meta["threshold"]),
            min_contact_area_px=float(meta["min_contact_area_px"]),
        )
    except (KeyError, ValueError, TypeError) as exc:
        raise ModelError(
            f"{path}: missing or invalid contactcal metadata ({exc}); export the model with "
            "`contactcal export`"
        ) from exc
    if spec.channels not in (1, 2) or not 0.0 < spec.threshold < 1.0:
        raise ModelError(f"{path}: unsupported metadata {spec}")
    return spec


class OnnxSegmenter:
    """Runs the exported U-Net on frames of one session at a time.

    Args:
        path: ONNX file (default: the shipped ``models/contact_unet.onnx``).
        threads: intra-op threads (1 is the benchmarked default: the model is small, and
            calibration runs beside other work).
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
            self.session = ort.InferenceSession(
                str(self.path), opts, providers=["CPUExecutionProvider"]
            )
        except Exception as exc:  # onnxruntime raises its own exception types
            raise ModelError(f"{self.path}: not a loadable ONNX model ({exc})") from exc
        meta = self.session.get_modelmeta().custom_metadata_map
        self.spec = read_spec(meta, self.path)
        self.input_name = self.session.get_inputs()[0].name
        self._box: CropBox | None = None
        self._ref_x: np.ndarray | None = None

    def set_reference(self, reference: np.ndarray | None) -> None:
        """Fix the session's crop (and reference channel) from its zero-pressure frame.

        Args:
            reference: ``(H, W) uint8`` zero-pressure frame, or None (each frame then finds its
                own ring; a 2-channel model then gets the frame itself as reference).
        """
        if reference is None:
            self._box, self._ref_x = None, None
            return
        cfg = self.spec.preprocess
        self._box = crop_box(locate_ring(reference, cfg), reference.shape, cfg)
        self._ref_x = to_network(reference, self._box, cfg)

    def predict(self, gray: np.ndarray) -> Segmentation:
        """Segment one ``(H, W) uint8`` frame (same size as the reference, if one is set)."""
        cfg = self.spec.preprocess
        box = self._box
        if box is None:
            box = crop_box(locate_ring(gray, cfg), gray.shape, cfg)
        x = to_network(gray, box, cfg)
        chans = [x]
        if self.spec.channels == 2:
            chans.append(self._ref_x if self._ref_x is not None else x)
        batch = np.stack(chans)[None].astype(np.float32)
        logits = self.session.run(None, {self.input_name: batch})[0][0, 0]
        prob = 1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))
        inside = np.zeros(prob.shape, bool)  # network pixels that map into the image
        inside[valid_window(box, gray.shape, prob.shape[0])] = True
        return postprocess(np.where(inside, prob, 0.0).astype(np.float32), box, self.spec)

    def mask_in_input(self, seg: Segmentation, shape: tuple[int, int]) -> np.ndarray:
        """``(H, W) bool`` contact mask in input pixels (for overlays)."""
        full = from_network(seg.mask_net.astype(np.float32), seg.box, shape)
        return full >= 0.5


def postprocess(prob: np.ndarray, box: CropBox, spec: ModelSpec) -> Segmentation:
    """Keep the largest connected region above the threshold; decide contact; measure it.

    Ring reflections and sparkle give small or detached specks: only the largest region counts,
    and only if it covers at least ``min_contact_area_px`` network pixels.
    """
    binary = (prob >= spec.threshold).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=8)
    px_per_net = box.scale(prob.shape[0]) ** 2  # input pixels per network pixel
    if n <= 1:
        keep = np.zeros_like(binary, dtype=bool)
    else:
        largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
        keep = labels == largest
    area_net = float(keep.sum())
    if area_net < spec.min_contact_area_px:
        empty = np.zeros_like(keep)
        return Segmentation(False, 0.0, 0.0, prob, empty, box)
    near = cv2.dilate(keep.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    soft = float(prob[near].sum())
    return Segmentation(True, area_net * px_per_net, soft * px_per_net, prob, keep, box)

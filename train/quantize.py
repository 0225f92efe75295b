"""INT8 variant of an exported model (onnxruntime static quantization, QDQ format).

Calibration inputs come from the one preprocessing (``session_inputs`` → ``prepare``) on
frames of the given datasets, so the activation ranges are those deployment will see; the
caller must pass data that is neither a benchmark nor a cross-check set (validation renders).
The metadata is copied unchanged from the float model (the strict spec of
``contactcal.infer.methods.unet.spec`` reads both alike), then the file is checked: it loads,
reads as a spec, and its decisions are compared with the float model's on as many further
frames, interleaved with the calibration frames and never used to calibrate (an agreement measured
on the calibration frames themselves would be in-sample).
"""

from __future__ import annotations

import contextlib
import logging
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from contactcal.infer.bench.dataset import read_datasets, sessions_of, spread
from contactcal.infer.errors import RunError
from contactcal.infer.files.atomic import atomic_path
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.prepare import SessionReference, prepare
from contactcal.infer.methods.unet.runner import OnnxSegmenter, read_model
from contactcal.train.sessions import session_inputs

__all__ = ["calibration_frames", "quantize_model"]


def calibration_frames(
    preprocess: PreprocessConfig, data: Sequence[str | os.PathLike[str]], frames: int
) -> list[tuple[np.ndarray, SessionReference]]:
    """Up to ``frames`` ``(frame (H, W) uint8, session reference)`` pairs, spread evenly over
    the frames of all sessions (first and last included); :func:`quantize_model` calibrates on
    every other one and checks on the rest."""
    groups = sessions_of(read_datasets([Path(d) for d in data]))
    pairs = [r for rows in groups.values() for r in rows]
    picks = [pairs[i] for i in spread(len(pairs), frames)]
    used = {r.session_key for r in picks}
    sessions = session_inputs([r for r in pairs if r.session_key in used], preprocess)
    return [
        (sessions[r.session_key].frame(r.frame), sessions[r.session_key].reference) for r in picks
    ]


class _Reader:
    """onnxruntime ``CalibrationDataReader`` over prepared inputs."""

    def __init__(self, name: str, inputs: list[np.ndarray]) -> None:
        self._it: Iterator[np.ndarray] = iter(inputs)
        self._name = name

    def get_next(self) -> dict[str, np.ndarray] | None:
        x = next(self._it, None)
        return None if x is None else {self._name: x}


def quantize_model(
    model: str | os.PathLike[str],
    out: str | os.PathLike[str],
    data: Sequence[str | os.PathLike[str]],
    frames: int = 64,
) -> dict[str, float | None]:
    """Write the INT8 (QDQ, per-channel weights) variant of ``model`` to ``out``, atomically.

    Args:
        model: float ONNX model exported by ``contactcal export``.
        out: destination (never ``model`` itself).
        data: dataset folders for calibration (validation renders, not benchmark data).
        frames: calibration frames; as many further frames, interleaved with them over the
            data, check the INT8 model (fewer of each when the data holds fewer than twice that).

    Returns:
        ``{"frames", "check_frames", "contact_agreement", "median_area_ratio"}``: the number of
        calibration frames and, on the check frames (never used to calibrate), their number,
        the share where both models make the same contact decision, and the median of INT8
        area / float area over those both call contact (None if there are none).

    Raises:
        ValueError: ``out`` is the input, ``model`` is already quantized, ``frames`` < 1, or
            fewer than two frames in ``data`` (one to calibrate, one to check).
    """
    from onnx import load, load_from_string, save
    from onnxruntime.quantization import QuantFormat, QuantType, quantize_static

    if Path(out).resolve() == Path(model).resolve():
        raise ValueError(f"{out}: would overwrite the float model; choose another --out")
    # read once: the float model checked, calibrated and copied is this content
    content = read_model(Path(model))
    float_seg = OnnxSegmenter(model, threads=1, content=content)
    fm = load_from_string(content)
    if any(n.op_type in QDQ_OPS for n in fm.graph.node):
        raise ValueError(
            f"{model}: already quantized (it holds QuantizeLinear/DequantizeLinear nodes); "
            "expected the float model that `contactcal export` wrote"
        )
    if frames < 1:
        raise ValueError(f"frames must be >= 1 (calibration frames), got {frames}")
    spec = float_seg.spec
    pairs = calibration_frames(spec.preprocess, data, 2 * frames)
    calibrate, held = pairs[0::2], pairs[1::2]
    if not held:
        raise ValueError(
            f"{len(pairs)} frame(s) in {', '.join(map(str, data))}; expected at least 2 (one to "
            "calibrate the INT8 model, one to check it on)"
        )
    inputs = [prepare(g, r, spec.preprocess, spec.channels).x[None] for g, r in calibrate]
    with tempfile.TemporaryDirectory() as tmp:
        q = Path(tmp) / "q.onnx"
        with _quiet_root_warnings():
            quantize_static(
                load_from_string(content),  # a copy: fm keeps the metadata copied below
                str(q),
                _Reader(float_seg.input_name, inputs),
                quant_format=QuantFormat.QDQ,
                activation_type=QuantType.QUInt8,
                weight_type=QuantType.QInt8,
                per_channel=True,
            )
        qm = load(str(q))
        del qm.metadata_props[:]
        qm.metadata_props.extend(fm.metadata_props)
        with atomic_path(out, protect=[model]) as tmp_out:
            save(qm, str(tmp_out))
            try:  # before it replaces anything: it loads and reads as a spec; agreement measured
                check = {
                    "frames": float(len(calibrate)),
                    **_agreement(float_seg, OnnxSegmenter(tmp_out, threads=1), held),
                }
            except ValueError as exc:
                msg = " ".join(str(exc).split())
                raise RunError(f"{out}: the INT8 model fails its check ({msg})") from exc
            _check_agreement(out, check)
            return check


#: Least share of check frames on which the INT8 model must make the float model's contact
#: decision. Lower lets a quantization that flips decisions through; higher refuses INT8 models
#: whose few flips are frames near the onset, where the float model itself is unsure.
MIN_CONTACT_AGREEMENT = 0.9
#: Largest departure of the median INT8/float area ratio from 1 (over frames both call contact).
#: A percent or two is the rounding of int8 activations; more is a bias the calibration would carry.
MAX_AREA_RATIO_DEPARTURE = 0.05


def _check_agreement(out: str | os.PathLike[str], check: dict[str, float | None]) -> None:
    """Refuse an INT8 model that departs from the float model (RunError: nothing is written).

    Args:
        out: the requested output, for the message.
        check: :func:`_agreement`'s result.
    """
    agree, ratio = check["contact_agreement"], check["median_area_ratio"]
    n = f"{check['check_frames']:.0f} frames not used to calibrate it"
    if agree is not None and agree < MIN_CONTACT_AGREEMENT:
        raise RunError(
            f"{out}: not written: the INT8 model makes the float model's contact decision on "
            f"{100 * agree:.1f} % of {n}, expected >= {100 * MIN_CONTACT_AGREEMENT:.0f} %; "
            "deploy the float model, or calibrate on other validation renders (--data, --frames)"
        )
    if ratio is not None and abs(ratio - 1.0) > MAX_AREA_RATIO_DEPARTURE:
        raise RunError(
            f"{out}: not written: the INT8 model's median area is {ratio:.3f}× the float model's "
            f"on {n}, expected within {MAX_AREA_RATIO_DEPARTURE:.0%} of 1; deploy the float "
            "model, or calibrate on other validation renders (--data, --frames)"
        )


#: Operators of a quantized (QDQ) graph: a model holding them is not quantized again.
QDQ_OPS = frozenset({"QuantizeLinear", "DequantizeLinear"})


@contextlib.contextmanager
def _quiet_root_warnings() -> Iterator[None]:
    """Hold back onnxruntime's advice on the root logger ("consider pre-processing") while
    quantizing, so the command prints its one line; the logging state is restored after."""
    before = logging.root.manager.disable
    logging.disable(logging.WARNING)
    try:
        yield
    finally:
        logging.disable(before)


def _agreement(
    a: OnnxSegmenter, b: OnnxSegmenter, pairs: list[tuple[np.ndarray, SessionReference]]
) -> dict[str, float | None]:
    """Contact agreement and area ratio of two segmenters, each making the deployed decision."""
    same, ratios = 0, []
    for gray, ref in pairs:
        sa, sb = a.segment(gray, ref), b.segment(gray, ref)
        same += sa.contact == sb.contact
        if sa.contact and sb.contact:
            ratios.append(sb.area_px / sa.area_px)
    return {
        "check_frames": float(len(pairs)),
        "contact_agreement": same / len(pairs),
        "median_area_ratio": float(np.median(ratios)) if ratios else None,
    }

"""Export a trained run's ``best.pt`` to ONNX with its preprocessing metadata, and verify it.

The graph takes ``input`` ``(N, C, H, W) float32`` (dynamic N, H, W) and returns ``logits``
``(N, 1, H, W) float32``. Metadata (``metadata_props``, all strings):

* ``input_size`` (px), ``channels`` (1 or 2), ``reference`` ("true": channel 1 is the session's
  zero-pressure frame preprocessed with the frame's box),
* ``preprocess``: JSON of :class:`contactcal.infer.preprocess.PreprocessConfig`,
* ``threshold`` (probability), ``min_contact_area_px`` (network pixels), ``output`` ("logits"),
* ``data_digest`` (sha256 of the training index.csv files), ``contactcal_version``, ``created``
  (UTC ISO 8601), ``train_config`` (JSON), ``best_epoch``, ``val_metrics`` (JSON).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import io
import json
import os
import warnings
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort
import torch

from contactcal.infer import __version__
from contactcal.infer.atomic import atomic_open
from contactcal.train.checkpoint import config_from_dict, load_checkpoint
from contactcal.train.loop import TrainConfig
from contactcal.train.model import UNet

#: torch vs onnxruntime tolerance on logits (float32; BN folding and kernel order differ).
PARITY_ATOL = 1e-4
PARITY_RTOL = 1e-4
#: Batch, height, width of the parity check; deliberately unlike the export shape.
PARITY_SHAPE = (2, 96, 80)


def load_run(run_dir: str | os.PathLike[str]) -> tuple[TrainConfig, dict, dict]:
    """Read a run's ``config.json`` and ``best.pt``.

    Returns:
        ``(train config, config.json content, best checkpoint)``.

    Raises:
        ValueError: missing or unreadable files.
    """
    run = Path(run_dir)
    path = run / "config.json"
    if not path.is_file():
        raise ValueError(f"{path}: missing run config (is {run} a `contactcal train` run folder?)")
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: unreadable run config ({exc})") from exc
    cfg = config_from_dict(TrainConfig, info.get("train"), str(path))
    return cfg, info, load_checkpoint(run / "best.pt")


def _metadata(cfg: TrainConfig, info: dict, ckpt: dict) -> dict[str, str]:
    metrics = {k: v for k, v in ckpt.get("metrics", {}).items() if v is not None}
    return {
        "input_size": str(cfg.input_size),
        "channels": str(cfg.model.in_channels),
        "reference": "true" if cfg.use_reference else "false",
        "preprocess": json.dumps(dataclasses.asdict(cfg.preprocess)),
        "threshold": repr(cfg.prob_threshold),
        "min_contact_area_px": repr(cfg.min_contact_area_px),
        "output": "logits",
        "data_digest": str(info.get("data_digest", "")),
        "contactcal_version": __version__,
        "created": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "train_config": json.dumps(info.get("train")),
        "best_epoch": str(int(ckpt.get("epoch", -1)) + 1),
        "val_metrics": json.dumps(metrics),
    }


def check_parity(model: torch.nn.Module, onnx_bytes: bytes, channels: int, seed: int = 0) -> float:
    """Compare torch and onnxruntime logits on a random input of :data:`PARITY_SHAPE`.

    Returns:
        The maximum absolute difference.

    Raises:
        RuntimeError: outside the tolerances.
    """
    n, h, w = PARITY_SHAPE
    g = torch.Generator().manual_seed(seed)
    x = torch.randn((n, channels, h, w), generator=g)
    with torch.no_grad():
        ref = model(x).numpy()
    opts = ort.SessionOptions()
    opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    sess = ort.InferenceSession(onnx_bytes, opts, providers=["CPUExecutionProvider"])
    got = sess.run(None, {"input": x.numpy()})[0]
    if got.shape != ref.shape:
        raise RuntimeError(f"ONNX output shape {got.shape} != torch {ref.shape}")
    err = float(np.max(np.abs(got - ref)))
    if not np.allclose(got, ref, atol=PARITY_ATOL, rtol=PARITY_RTOL):
        raise RuntimeError(f"ONNX/torch parity failed: max |Δlogit| = {err:.3g} > {PARITY_ATOL}")
    return err


def export_onnx(
    run_dir: str | os.PathLike[str],
    out_path: str | os.PathLike[str],
    opset: int = 17,
    min_contact_area_px: float | None = None,
) -> Path:
    """Export ``run_dir/best.pt`` to ``out_path`` (atomic), checked and parity-tested.

    Args:
        run_dir: a ``contactcal train`` run folder (``config.json``, ``best.pt``).
        out_path: destination ``.onnx`` file.
        opset: ONNX opset version.
        min_contact_area_px: network pixels; overrides the run's value in the metadata (e.g.
            from :func:`contactcal.train.threshold.tune_min_area`).

    Returns:
        ``out_path`` as a Path.

    Raises:
        ValueError: bad run folder or output name.
        RuntimeError: the exported model fails the checker or the parity test.
    """
    out = Path(out_path)
    if out.suffix.lower() != ".onnx":
        raise ValueError(f"{out}: expected an output file name ending in .onnx")
    cfg, info, ckpt = load_run(run_dir)
    if min_contact_area_px is not None:
        if not min_contact_area_px >= 0:
            raise ValueError(f"min_contact_area_px must be >= 0, got {min_contact_area_px}")
        cfg = dataclasses.replace(cfg, min_contact_area_px=float(min_contact_area_px))
    model = UNet(cfg.model)
    model.load_state_dict(ckpt["model"])
    model.eval()
    c, s = cfg.model.in_channels, cfg.input_size
    axes = {0: "batch", 2: "height", 3: "width"}
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the TorchScript exporter's deprecation notice
        torch.onnx.export(
            model,
            (torch.zeros((1, c, s, s)),),
            buf,
            dynamo=False,
            input_names=["input"],
            output_names=["logits"],
            dynamic_axes={"input": axes, "logits": axes},
            opset_version=opset,
            do_constant_folding=True,
        )
    proto = onnx.load_from_string(buf.getvalue())
    proto.producer_name = "contactcal"
    proto.producer_version = __version__
    onnx.helper.set_model_props(proto, _metadata(cfg, info, ckpt))
    try:
        onnx.checker.check_model(proto, full_check=True)
    except onnx.checker.ValidationError as exc:
        raise RuntimeError(f"exported model fails onnx.checker: {exc}") from exc
    data = proto.SerializeToString()
    check_parity(model, data, c)
    with atomic_open(out, "wb") as fh:
        fh.write(data)
    return out

"""Export a trained run's ``best.pt`` to ONNX with its preprocessing metadata, and verify it.

The graph takes ``input`` ``(N, C, H, W) float32`` (dynamic N, H, W) and returns ``logits``
``(N, 1, H, W) float32``. Metadata (``metadata_props``, all strings) has exactly the keys
deployment's :func:`contactcal.infer.methods.unet.spec.read_spec` accepts:

* the spec (:data:`~contactcal.infer.methods.unet.spec.SPEC_KEYS`, written by
  :meth:`ModelSpec.to_metadata`): ``channels`` (1, or 2 = frame + the session's zero-pressure
  frame), ``preprocess`` (JSON of :class:`~contactcal.infer.methods.unet.config.PreprocessConfig`,
  incl. ``input_size``), ``threshold`` (probability), ``min_contact_area_px`` (network pixels),
  ``output`` ("logits"), ``interval`` (JSON of
  :class:`~contactcal.infer.methods.unet.spec.IntervalSpec`: the stated 90 % interval of a frame's
  area, ALWAYS calibrated here on the run's validation fingers (as its ``config.json`` records
  them: :func:`contactcal.train.split.validation_rows`) by
  :func:`contactcal.train.interval.calibrate_run`; a run without validation fingers cannot be
  exported), and the optional ``region`` (:data:`~contactcal.infer.methods.unet.spec.REGIONS`),
  written as ``"largest"`` here; ``python -m contactcal.train.interval --region convex`` restates
  it with the interval recalibrated for the hull; and the optional ``min_change`` (the change
  gate), written as 0.0 (none) here; ``python -m contactcal.train.change_gate`` calibrates it;
* provenance (:data:`~contactcal.infer.methods.unet.spec.PROVENANCE_KEYS`): ``data_digest``
  (sha256 of the training index.csv files), ``contactcal_version``, ``created`` (UTC ISO 8601),
  ``train_config`` (JSON), ``best_epoch``, ``val_metrics`` (JSON).

Before the file is written: ``onnx.checker``, logit parity at another shape
(:func:`check_parity`), the same contact decisions as torch on the run's validation frames through
the one prepare and postprocess (:func:`contactcal.train.export_check.check_decisions`), and the
serialised metadata read back through ``read_spec`` (deployment accepts it, reads the run's spec).
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
from contactcal.infer.files.atomic import atomic_open
from contactcal.infer.methods.unet.spec import ModelSpec, read_spec
from contactcal.train.checkpoint import load_checkpoint
from contactcal.train.config import TrainConfig, saved_train_config
from contactcal.train.digest import dataset_digest, render_digest
from contactcal.train.export_check import ExportCheckError, check_decisions
from contactcal.train.interval import calibrate_run
from contactcal.train.model import UNet
from contactcal.train.run_folder import read_run_info
from contactcal.train.split import validation_rows

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
        ValueError: missing or unreadable files, or dataset folders of the run (``data_dirs``,
            which export calibrates and checks on) that cannot be found from here.
    """
    run = Path(run_dir)
    path = run / "config.json"
    info = read_run_info(run)
    cfg = saved_train_config(info.get("train"), str(path))
    check_data_dirs(info.get("data_dirs"), path, info.get("data_digest"), info.get("render_digest"))
    return cfg, info, load_checkpoint(run / "best.pt")


def check_data_dirs(
    dirs: object, config_path: Path, digest: object = None, render: object = None
) -> None:
    """Refuse a run whose ``data_dirs`` are missing, not found, or not the data it trained on.

    Args:
        dirs: the config's ``data_dirs`` (absolute since runs record them resolved; a run
            written before reads its relative ones from the current folder).
        config_path: the run's ``config.json``, for the message.
        digest: the config's ``data_digest`` (:func:`~contactcal.train.digest.dataset_digest`
            of the folders at training time); None or absent: not compared.
        render: the config's ``render_digest`` (:func:`~contactcal.train.digest.render_digest`:
            how the folders were rendered); None or absent (runs before it): not compared.

    Raises:
        ValueError: naming the config, the folder and how to fix it.
    """
    if not isinstance(dirs, list) or not dirs or not all(isinstance(d, str) for d in dirs):
        raise ValueError(f"{config_path}: expected data_dirs, a list of the run's dataset folders")
    for d in dirs:
        if not (Path(d) / "index.csv").is_file():
            raise ValueError(
                f"{config_path}: the run's dataset folder {d} (data_dirs) has no index.csv as "
                f"seen from {Path.cwd()}; run from the folder the run was trained in (relative "
                "data_dirs are read from there) or put the data back"
            )
    if isinstance(digest, str) and digest and dataset_digest(dirs) != digest:
        raise ValueError(
            f"{config_path}: the run's dataset folders {', '.join(dirs)} (data_dirs) no longer "
            "hold the data it was trained on (their index.csv digest differs from data_digest); "
            "the export calibrates and checks on the run's validation fingers, so put the "
            "original data back (a re-render with the same command and seed is identical)"
        )
    if isinstance(render, str) and render and render_digest(dirs) != render:
        raise ValueError(
            f"{config_path}: the run's dataset folders {', '.join(dirs)} (data_dirs) were "
            "rendered otherwise than the data it was trained on (their config.json digest "
            "differs from render_digest: another size, spp, seed or Mitsuba variant); put the "
            "original renders back (the same command, seed and variant)"
        )


def metadata(spec: ModelSpec, info: dict, ckpt: dict) -> dict[str, str]:
    """The model's ``metadata_props``: ``spec.to_metadata()`` + the ``PROVENANCE_KEYS``.

    Args:
        spec: the deployment spec (:meth:`TrainConfig.spec`).
        info: the run's ``config.json``.
        ckpt: the exported checkpoint (``epoch``, ``metrics``).
    """
    metrics = {k: v for k, v in ckpt.get("metrics", {}).items() if v is not None}
    provenance = {
        "data_digest": str(info.get("data_digest", "")),
        "contactcal_version": __version__,
        "created": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "train_config": json.dumps(info.get("train")),
        "best_epoch": str(int(ckpt.get("epoch", -1)) + 1),
        "val_metrics": json.dumps(metrics),
    }
    return {**spec.to_metadata(), **provenance}


def self_check(data: bytes, spec: ModelSpec, out: Path) -> None:
    """Load the serialised model's metadata back through deployment's ``read_spec``.

    Raises:
        RuntimeError: ``read_spec`` rejects it or reads another spec than the one exported.
    """
    meta = {p.key: p.value for p in onnx.load_from_string(data).metadata_props}
    try:
        back = read_spec(meta, out)
    except ValueError as exc:
        raise ExportCheckError(f"exported metadata rejected by read_spec: {exc}") from exc
    if back != spec:
        raise ExportCheckError(f"{out}: metadata reads back as {back}, expected {spec}")


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
        raise ExportCheckError(f"ONNX output shape {got.shape} != torch {ref.shape}")
    err = float(np.max(np.abs(got - ref)))
    if not np.allclose(got, ref, atol=PARITY_ATOL, rtol=PARITY_RTOL):
        raise ExportCheckError(
            f"ONNX/torch parity failed: max |Δlogit| = {err:.3g} > {PARITY_ATOL}"
        )
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
        ValueError: bad run folder or output name, or no validation fingers to calibrate the
            area interval on (or a recorded split that the data contradicts:
            :func:`~contactcal.train.split.validation_rows`).
        RuntimeError: the exported model fails the checker, the parity test or the metadata
            self-check (nothing is written then).
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
    proto = to_onnx(model, cfg.model.in_channels, cfg.input_size, opset)
    val = validation_rows(run_dir, info, cfg.val_fraction, cfg.seed)  # as the run recorded them
    interval, _ = calibrate_run(model, cfg.spec(), val)
    spec = dataclasses.replace(cfg.spec(), interval=interval)
    onnx.helper.set_model_props(proto, metadata(spec, info, ckpt))
    try:
        onnx.checker.check_model(proto, full_check=True)
    except onnx.checker.ValidationError as exc:
        raise ExportCheckError(f"exported model fails onnx.checker: {exc}") from exc
    data = proto.SerializeToString()
    check_parity(model, data, cfg.model.in_channels)
    check_decisions(model, data, spec, val)
    self_check(data, spec, out)  # the bytes about to be written, read back as deployment does
    with atomic_open(out, "wb") as fh:
        fh.write(data)
    return out


def to_onnx(model: torch.nn.Module, channels: int, size: int, opset: int) -> onnx.ModelProto:
    """TorchScript-based export with dynamic batch, height and width (no metadata yet)."""
    axes = {0: "batch", 2: "height", 3: "width"}
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the TorchScript exporter's deprecation notice
        torch.onnx.export(
            model,
            (torch.zeros((1, channels, size, size)),),
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
    return proto

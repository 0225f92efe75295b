"""``contactcal evaluate``: measure a session's hand-labelled frames and score every method.

Outputs (all or nothing, never replacing an input): ``evaluation.json`` and ``evaluation.png``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.bench.scoring import PRESSURE_BINS, bin_table
from contactcal.infer.evaluate.labels import Label, LabelError, label_mask, read_labels
from contactcal.infer.evaluate.offset import current_offset, offset_line, unet_offset
from contactcal.infer.evaluate.plots import plot_evaluation
from contactcal.infer.evaluate.report import format_table
from contactcal.infer.evaluate.score import frame_records, onset_summary, score_frames
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_synced
from contactcal.infer.files.jsonable import json_text
from contactcal.infer.methods.registry import METHODS, make_method
from contactcal.infer.pipeline.boundary import BoundaryOffset
from contactcal.infer.pipeline.manifest import Frame, read_manifest
from contactcal.infer.pipeline.measure import Measured, measure_files
from contactcal.infer.pipeline.scale import PixelScale

#: ``--method`` choices: one method, or ``both`` (every method of the registry).
METHOD_CHOICES = (*METHODS, "both")


@dataclass(frozen=True)
class Evaluation:
    """What an evaluation run produced."""

    record: dict[str, Any]  # the content of evaluation.json
    table: str  # the short text table the CLI prints
    files: dict[str, Path]  # "json", "png"


def _labelled(
    frames: list[Frame], labels: list[Label], where: Path
) -> tuple[list[Frame], list[Label]]:
    """The labelled frames (by pressure, with their labels) and the unlabelled frames' files."""
    by_frame = {lab.frame: lab for lab in labels}
    done = [f for f in frames if f.file in by_frame]
    if not done:
        raise LabelError(
            f"{where}: labels none of the manifest's {len(frames)} frames; expected masks named "
            f"<frame stem>.png or CSV rows naming the frames, e.g. {frames[-1].file.name}"
        )
    return done, [by_frame[f.file] for f in done]


@dataclass(frozen=True)
class _Setup:
    """How the frames are measured: besides the methods, what ``calibrate`` would also use."""

    model: str | os.PathLike[str] | None
    bit_depth: int | None
    change_gate: bool
    scale: PixelScale | None
    boundary: BoundaryOffset | None


def _measure(
    names: list[str], frames: list[Frame], files: list[Path], setup: _Setup
) -> tuple[dict[str, list[Measured]], dict[str, Any], str]:
    """Each method's measurements of ``files`` (the manifest's first frame is the reference),
    its ``describe()``, and the note of a stale boundary offset left out
    (:func:`~contactcal.infer.evaluate.offset.current_offset`; "" when none)."""
    out, described, stale = {}, {}, ""
    for name in names:
        method = make_method(name, setup.model, outline=True, change_gate=setup.change_gate)
        described[name] = method.describe()
        boundary, note = current_offset(setup.boundary, described[name].get("model_sha256"))
        stale = stale or note
        out[name] = measure_files(
            files, method, frames[0].file, setup.scale, bit_depth=setup.bit_depth, boundary=boundary
        )
    return out, described, stale


def _check_request(method: str, labels: Path, out: Path) -> None:
    """Refuse an unknown method, and a report inside the labels folder (its PNG would be read
    as a label by the next run)."""
    if method not in METHOD_CHOICES:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHOD_CHOICES)}")
    if labels.is_dir() and out.resolve().is_relative_to(labels.resolve()):
        raise LabelError(
            f"{out}: is inside the labels folder {labels}, whose PNGs are all read as labels "
            "(the next evaluate would take the report's PNG for one); give another --out folder"
        )


def evaluate_session(
    manifest: str | os.PathLike[str],
    labels: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    method: str = METHODS[0],
    model: str | os.PathLike[str] | None = None,
    bit_depth: int | None = None,
    outputs: OutputSet | None = None,
    change_gate: bool = True,
    scale: PixelScale | None = None,
    boundary: BoundaryOffset | None = None,
) -> Evaluation:
    """Score ``method`` on the frames of ``manifest`` labelled in ``labels``.

    (Over 60 lines by its arguments' documentation and one run's steps in order — read,
    stage, measure, score, record, write — kept in one place so that the staging brackets all
    of them.)

    Every labelled frame is measured (reference: the manifest's lowest-pressure frame) and
    compared with its label's rasterised mask: area (relative error against the rasterised
    pixel count, for ellipses too, so that it agrees with the IoU) and IoU of the method's
    filled outline. Frames without a label are listed under ``"unlabelled"`` (and in the
    table), never silently dropped.

    Args:
        manifest: session manifest CSV (``file``, ``pressure_kpa``).
        labels: folder of ``<frame stem>.png`` masks, or an ImageJ ellipse CSV
            (:mod:`contactcal.infer.evaluate.labels`).
        out_dir: folder for ``evaluation.json`` and ``evaluation.png``.
        method: ``"unet"``, ``"classical"`` or ``"both"``.
        model: ONNX model for the U-Net (None → the shipped one).
        bit_depth: significant bits of 16-bit frames; None → from the files.
        outputs: the enclosing run's outputs to stage into (None: this call is the run).
        change_gate: apply the U-Net model's change gate (``--no-change-gate``: off; recorded).
        scale: the rig's pixel scale (the boundary offset in mm; None: pixels only).
        boundary: the rig's boundary offset, applied as ``calibrate`` applies it; the offset
            measured here (``boundary_offset``, :mod:`~contactcal.infer.evaluate.offset`) is
            then what remains.

    Returns:
        The :class:`Evaluation`.

    Raises:
        LabelError: bad labels (naming the file); ManifestError / ImageError: bad manifest or
            frame; ValueError: unknown method or an output that would replace an input.
    """
    manifest, labels, out = Path(manifest), Path(labels), Path(out_dir)
    _check_request(method, labels, out)
    names = list(METHODS) if method == "both" else [method]
    frames = read_manifest(manifest)
    labelled, labs = _labelled(frames, read_labels(labels, frames, manifest), labels)
    base = manifest.resolve().parent
    done = {f.file for f in labelled}
    unlabelled = [os.path.relpath(f.file, base) for f in frames if f.file not in done]
    protect = [manifest, model, *(f.file for f in frames), *{lab.source for lab in labs}]
    with run_outputs(protect, join=outputs) as outs:
        paths = {"png": out / "evaluation.png", "json": out / "evaluation.json"}
        staged = {k: outs.stage(p) for k, p in paths.items()}  # refused here, before work
        files = [f.file for f in labelled]
        setup = _Setup(model, bit_depth, change_gate, scale, boundary)
        measured, described, stale = _measure(names, frames, files, setup)
        first = measured[names[0]]
        masks = [label_mask(lab, (m.width, m.height)) for lab, m in zip(labs, first, strict=True)]
        areas = [float(mask.area_px) for mask in masks]
        offset = unet_offset(measured.get("unet", []), areas, scale, described, stale)
        scored = score_frames(str(manifest), [f.pressure_kpa for f in labelled], masks, measured)
        onset, bins = onset_summary(scored), bin_table(scored, PRESSURE_BINS)
        record = {
            "manifest": str(manifest.resolve()),
            "labels": str(labels.resolve()),
            "methods": names,
            "model": None if model is None else os.fspath(model),
            "change_gate": "on" if change_gate else "off (--no-change-gate)",
            "area_note": "errors and IoU against the label's rasterised pixel count",
            "frames": frame_records(base, masks, [lab.where() for lab in labs], scored),
            "unlabelled": unlabelled,
            "summary": {"bins": bins, "onset": onset},
            "boundary_offset": offset,
        }  # the evaluation.json content
        text = json_text(record)
        plot_evaluation(staged["png"], scored)
        write_synced(staged["json"], text)
    table = "\n".join([format_table(bins, onset), *([offset_line(offset)] if offset else [])])
    if unlabelled:
        table += f"\n{len(unlabelled)} frame(s) without a label, skipped: {', '.join(unlabelled)}"
    return Evaluation(record, table, paths)

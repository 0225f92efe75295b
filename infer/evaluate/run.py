"""``contactcal evaluate``: measure a session's hand-labelled frames and score every method.

Outputs (all or nothing, never replacing an input): ``evaluation.json`` and ``evaluation.png``.
``evaluation.json`` records the sha256 of the manifest, the reference frame and each labelled
frame (``inputs``), by which ``contactcal boundary-offset`` pools each session once.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from contactcal.infer.bench.scoring import OPEN_BINS, ScoredFrame, bin_table
from contactcal.infer.evaluate.identity import input_digests
from contactcal.infer.evaluate.label_raster import LabelMask, label_mask
from contactcal.infer.evaluate.labels import Label, LabelError, read_labels
from contactcal.infer.evaluate.offset import current_offset, offset_line, unet_offset
from contactcal.infer.evaluate.plots import plot_evaluation
from contactcal.infer.evaluate.report import format_table
from contactcal.infer.evaluate.score import frame_records, onset_summary, score_frames
from contactcal.infer.evaluate.window import check_label_area, find_window
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_synced
from contactcal.infer.files.jsonable import json_text
from contactcal.infer.image.read import ImageFile, read_contents, source_size
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.pipeline.manifest import (
    Frame,
    Session,
    check_sweep_unit,
    read_session,
    sweep_top_warning,
)
from contactcal.infer.pipeline.manifest_rows import listed_name
from contactcal.infer.pipeline.measure import Measured
from contactcal.infer.pipeline.options import MeasureOptions

#: Unlabelled frames named in the printed table (a video session has hundreds; the JSON lists all).
LISTED = 10
#: ``--method`` choices: one method, or ``both`` (every method of the registry).
METHOD_CHOICES = (*METHODS, "both")


#: The files an evaluation writes into its ``--out`` folder: the record and its figure.
EVALUATION_FILES = ("evaluation.json", "evaluation.png")


@dataclass(frozen=True)
class Evaluation:
    """What an evaluation run produced."""

    record: dict[str, Any]  # the content of evaluation.json
    table: str  # the short text table the CLI prints
    files: dict[str, Path]  # "json", "png"


def _labelled(
    frames: list[Frame], labels: list[Label], where: Path, folder: Path
) -> tuple[list[Frame], list[Label], list[str]]:
    """The labelled frames (by pressure), their labels, and the unlabelled frames' files (as
    the manifest lists them; ``folder``: its
    :attr:`~contactcal.infer.pipeline.manifest.Session.folder`)."""
    by_frame = {lab.frame: lab for lab in labels}
    done = [f for f in frames if f.file in by_frame]
    if not done:
        raise LabelError(
            f"{where}: labels none of the manifest's {len(frames)} frames; expected masks named "
            f"<frame stem>.png or CSV rows naming the frames, e.g. {frames[-1].file.name}"
        )
    unlabelled = [listed_name(folder, f.file) for f in frames if f.file not in by_frame]
    return done, [by_frame[f.file] for f in done], unlabelled


def _read_frames(frames: list[Frame], labelled: list[Frame]) -> dict[Path, ImageFile]:
    """The content of the reference (the manifest's first frame) and of each labelled frame,
    each file read once: the labels' checks, the measurements of every method and the
    record's digests all come from it."""
    return read_contents([frames[0].file, *(f.file for f in labelled)])


def _measure(
    names: list[str], reference: ImageFile, files: list[ImageFile], measure: MeasureOptions
) -> tuple[dict[str, list[Measured]], dict[str, Any], str]:
    """Each method's measurements of ``files`` against ``reference``, its ``describe()``, and
    the note of a stale boundary offset left out
    (:func:`~contactcal.infer.evaluate.offset.current_offset`; "" when none)."""
    out, described, stale = {}, {}, ""
    for name in names:
        method = measure.method(name, outline=True)
        described[name] = method.describe()
        boundary, note = current_offset(measure.boundary, described[name].get("model_sha256"))
        stale = stale or note
        run = replace(measure, boundary=boundary)
        out[name] = run.measure(files, method, reference, digest=True)
    return out, described, stale


def _label_masks(
    labs: list[Label], reference: ImageFile, read: dict[Path, ImageFile], bit_depth: int | None
) -> list[LabelMask]:
    """The labels rasterised at the sizes of their frames' contents ``read`` (before any frame
    is measured, so a mask of another size is refused up front), each checked to fit the
    window ring of ``reference`` (:func:`~contactcal.infer.evaluate.window.check_label_area`)."""
    window = find_window(reference, bit_depth)
    masks = []
    for lab in labs:
        size = source_size(read[lab.frame], bit_depth)
        mask = label_mask(lab, size)
        check_label_area(lab, mask, size, window)
        masks.append(mask)
    return masks


def _score(
    manifest: Path,
    read: dict[Path, ImageFile],
    frames: list[Frame],
    labelled: list[Frame],
    masks: list[LabelMask],
    names: list[str],
    measure: MeasureOptions,
) -> tuple[list[ScoredFrame], dict[str, Any] | None, dict[str, list[Measured]]]:
    """The labelled frames (their contents ``read``) measured by each method and scored
    against their labels' masks; the U-Net's boundary offset record (None without a U-Net
    run); each method's measurements."""
    files = [read[f.file] for f in labelled]
    measured, described, stale = _measure(names, read[frames[0].file], files, measure)
    areas = [float(mask.area_px) for mask in masks]
    source = None if measure.boundary is None else measure.boundary.source
    offset = unet_offset(measured.get("unet", []), areas, measure.scale, described, stale, source)
    pressures = [f.pressure_kpa for f in labelled]
    scored = score_frames(str(manifest), pressures, masks, measured, measure.scale)
    return scored, offset, measured


def _table(
    bins_and_onset: str,
    offset: dict[str, Any] | None,
    unlabelled: list[str],
    masks: list[LabelMask],
) -> str:
    """The printed table: bins and onset, the boundary offset's line, the labels read other than
    as drawn (soft edges), the unlabelled frames (the first :data:`LISTED` named)."""
    table = "\n".join([bins_and_onset, *([offset_line(offset)] if offset else [])])
    soft = sum(m.note is not None for m in masks)
    if soft:
        table += (
            f"\nnote: {soft} mask(s) with a soft edge (several non-zero values) read as contact "
            "above half their largest value (each frame's label_note in evaluation.json)"
        )
    if unlabelled:
        shown = ", ".join(unlabelled[:LISTED]) + (", …" if len(unlabelled) > LISTED else "")
        table += (
            f"\n{len(unlabelled)} frame(s) without a label, skipped (all in evaluation.json's "
            f"unlabelled): {shown}"
        )
    return table


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


def evaluated_session(manifest: str | os.PathLike[str]) -> Session:
    """The manifest as an evaluation reads it: readings not pooled into steps (step tolerance
    0), each frame scored at its own pressure.

    Raises:
        ManifestError: a bad manifest.
    """
    return read_session(manifest, 0.0)


def evaluate_session(
    manifest: str | os.PathLike[str],
    labels: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    method: str = METHODS[0],
    measure: MeasureOptions | None = None,
    outputs: OutputSet | None = None,
    also_read: Sequence[Path] = (),
    session: Session | None = None,
) -> Evaluation:
    """Score ``method`` on the frames of ``manifest`` labelled in ``labels``.

    The reference and every labelled frame are read once, and that content serves every step
    (the labels' checks, each method's measurement, the digests recorded). Every label is
    rasterised at its frame's size and checked first, before any frame is measured. Every
    labelled frame is then measured (reference: the manifest's lowest-pressure frame) and
    compared with its label's rasterised mask: area (relative error against the rasterised
    pixel count, for ellipses too, so that it agrees with the IoU) and IoU of the method's
    filled outline. Frames without a label are listed under ``"unlabelled"`` (and in the
    table), never silently dropped. A boundary offset in ``measure`` is applied as
    ``calibrate`` applies it; the offset measured here (``boundary_offset``,
    :mod:`~contactcal.infer.evaluate.offset`) is then what remains.

    Args:
        manifest: session manifest CSV (``file``, ``pressure_kpa``).
        labels: folder of ``<frame stem>.png`` masks, or an ImageJ ellipse CSV
            (:mod:`contactcal.infer.evaluate.labels`).
        out_dir: folder for ``evaluation.json`` and ``evaluation.png``.
        method: ``"unet"``, ``"classical"`` or ``"both"``.
        measure: how the frames are measured (model, scale: the boundary offset in mm, the
            rig's offset, bit depth, change gate); None: the defaults (pixels only).
        outputs: the enclosing run's outputs to stage into (None: this call is the run).
        also_read: further files the run reads (the rig config): no output may replace them.
        session: ``manifest`` as the caller read it (:func:`evaluated_session`; the command
            shares its one read with its rig note), not read again; None: read here.

    Returns:
        The :class:`Evaluation`.

    Raises:
        LabelError: bad labels (naming the file), among them a mask without background (no
            pixel 0) or a label covering more than the reference frame's window ring;
            ManifestError / ImageError: bad manifest or frame; ValueError: unknown method or an
            output that would replace an input.
    """
    manifest, labels, out = Path(manifest), Path(labels), Path(out_dir)
    measure = measure if measure is not None else MeasureOptions()
    _check_request(method, labels, out)
    names = list(METHODS) if method == "both" else [method]
    session = session if session is not None else evaluated_session(manifest)
    frames = session.frames
    check_sweep_unit(manifest, frames)  # bar or MPa read as kPa, as calibrate refuses them
    high = sweep_top_warning(max(f.pressure_kpa for f in frames), "evaluate")
    labs = read_labels(labels, frames, session.folder)
    labelled, labs, unlabelled = _labelled(frames, labs, labels, session.folder)
    read = _read_frames(frames, labelled)  # each read once, for every step below
    masks = _label_masks(labs, read[frames[0].file], read, measure.bit_depth)  # before measuring
    protect = [manifest, measure.model, *also_read, *(f.file for f in frames)]
    protect += list({lab.source for lab in labs})
    with run_outputs(protect, join=outputs) as outs:
        paths = {"png": out / EVALUATION_FILES[1], "json": out / EVALUATION_FILES[0]}
        staged = {k: outs.stage(p) for k, p in paths.items()}  # refused here, before work
        scored, offset, measured = _score(manifest, read, frames, labelled, masks, names, measure)
        onset, bins = onset_summary(scored), bin_table(scored, OPEN_BINS)
        record = {
            "manifest": str(manifest.resolve()),
            "labels": str(labels.resolve()),
            "inputs": input_digests(manifest, session, measured[names[0]]),
            "methods": names,
            "model": None if measure.model is None else os.fspath(measure.model),
            "change_gate": "on" if measure.change_gate else "off (--no-change-gate)",
            "mm_per_px": None if measure.scale is None else measure.scale.mm_per_px,
            "scale_image_width_px": None if measure.scale is None else measure.scale.image_width_px,
            "warning": high,
            "area_note": "errors and IoU against the label's rasterised pixel count",
            "frames": frame_records(session.folder, masks, [lab.where() for lab in labs], scored),
            "unlabelled": unlabelled,
            "summary": {"bins": bins, "onset": onset},
            "boundary_offset": offset,
        }  # the evaluation.json content
        plot_evaluation(staged["png"], scored)
        write_synced(staged["json"], json_text(record))
    table = _table(format_table(bins, onset), offset, unlabelled, masks)
    table = table if high is None else f"{high}\n{table}"
    return Evaluation(record, table, paths)

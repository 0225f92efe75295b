"""Accuracy of every method on every session of a dataset, and the contact onsets it implies.

Accuracy is measured on the dataset's frames at their native size against the exact masks (areas
in input-file pixels; mm² through the frame's true pixel scale). Rendered frames (e.g. 400×300)
are already ~1/6 of the rig's 2592 px; the classical routine's kernels scale with the width, so its
accuracy here *is* its reduced-resolution accuracy (the speed table times it at both).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from contactcal.infer.bench.dataset import IndexRow
from contactcal.infer.bench.preflight import check_mask_size
from contactcal.infer.bench.scoring import (
    SESSION_SUFFIX,
    SOFT_SUFFIX,
    ScoredFrame,
    outline_iou,
    session_revised,
)
from contactcal.infer.image.read import ImageFile, ImageSource, load_image
from contactcal.infer.methods.base import Method
from contactcal.infer.methods.registry import METHODS

if TYPE_CHECKING:
    from contactcal.infer.bench.models import BenchModel


def score_session(
    method: Method, name: str, rows: Sequence[IndexRow], use_reference: bool = True
) -> list[ScoredFrame]:
    """Measure one session (``rows`` sorted by pressure; the first is its reference frame).

    With ``use_reference=False`` the method gets no reference frame (as ``measure`` without
    ``--reference``); the frames are the same. With it, the first frame is measured against
    itself: its frames are marked ``reference`` (left out of the tables, kept for the onset).
    The reference frame is read once: the method measures it as a frame in its own decode
    (``Started.reference``, as ``measure`` does).

    Returns:
        One :class:`ScoredFrame` per frame, plus one ``"<name> (soft area)"`` frame per frame for
        methods that report a probability-mass (sub-pixel) area, and one ``"<name> (session
        rule)"`` frame per frame for methods that state an interval (:func:`session_ruled`).
    """
    reference = ImageFile.read(rows[0].frame) if use_reference else None
    files: list[ImageSource] = [r.frame for r in rows]
    started = method.start(files if reference is None else [reference, *files[1:]], reference)
    k, decoded = started.reduction, started.reference
    out: list[ScoredFrame] = []
    for i, r in enumerate(rows):
        gray = decoded if i == 0 and decoded is not None else load_image(r.frame, reduce=k)
        res = method.measure(gray)
        truth = _truth(r, (gray.shape[0] * k, gray.shape[1] * k))  # k divides the file's size
        scored = ScoredFrame(
            method=name,
            session=r.session_key,
            frame=str(r.frame),
            pressure_kpa=r.pressure_kpa,
            true_area_px=r.area_px,
            area_px=float(res.area_px),
            contact=bool(res.contact),
            mm_per_px=r.mm_per_px,
            onset_kpa=r.onset_kpa,
            hard=r.hard,
            area_interval_px=res.area_interval_px,
            iou=None if truth is None else outline_iou(res, truth),
            reference=use_reference and i == 0,
        )
        out.append(scored)
        if res.soft_area_px is not None or name.startswith("unet"):
            # The same prediction measured by its probability mass (0 without contact); the
            # stated interval is the pixel count's, not the soft area's.
            soft = float(res.soft_area_px) if res.soft_area_px is not None else 0.0
            out.append(_renamed(scored, name + SOFT_SUFFIX, soft))
    return out + session_ruled([f for f in out if f.method == name])


def _truth(row: IndexRow, frame_shape: tuple[int, int]) -> np.ndarray | None:
    """``(H, W)`` bool exact mask of a frame with contact (None without), checked against its
    frame's ``(H, W)`` (px of the file) and the index: a damaged dataset would otherwise score a
    0/0 IoU.

    Raises:
        ValueError: the mask is not of its frame's size, or its pixel count is not the index's
            ``area_px`` (naming both).
    """
    if not row.contact:
        return None
    truth = load_image(row.mask) > 0
    check_mask_size(row, (truth.shape[0], truth.shape[1]), frame_shape)
    if int(np.count_nonzero(truth)) != round(row.area_px):
        raise ValueError(
            f"{row.mask}: holds {int(np.count_nonzero(truth))} contact px but index.csv of "
            f"{row.dataset} says area_px {row.area_px:g}; expected the mask the index was "
            "written from (render the session again)"
        )
    return truth


def session_ruled(frames: Sequence[ScoredFrame]) -> list[ScoredFrame]:
    """One session's frames (one method) after ``calibrate``'s session rule, renamed
    ``"<method> (session rule)"``; none for a method that states no interval.

    Args:
        frames: the session's scored frames of one method.

    Returns:
        The same frames, renamed; a revised one (:func:`session_revised`) reports no contact,
        area 0 and the interval ``(0, its upper end)``, as in a calibration record.
    """
    if all(f.area_interval_px is None for f in frames):
        return []
    out = []
    for f, revised in zip(frames, session_revised(frames), strict=True):
        if revised and f.area_interval_px is not None:
            iv = (0.0, f.area_interval_px[1])
            iou = None if f.iou is None else 0.0  # no region left to overlap the truth
            f = replace(f, area_px=0.0, contact=False, area_interval_px=iv, iou=iou)
        out.append(replace(f, method=f.method + SESSION_SUFFIX))
    return out


def _renamed(frame: ScoredFrame, method: str, area_px: float) -> ScoredFrame:
    return ScoredFrame(
        **{
            **asdict(frame),
            "method": method,
            "area_px": area_px,
            "area_interval_px": None,
            "iou": None,  # an area without an outline of its own
        }
    )


def evaluate(
    sessions: Mapping[str, Sequence[IndexRow]],
    models: Sequence[BenchModel],
    use_reference: bool = True,
) -> list[ScoredFrame]:
    """Measure every frame of every session with every method (:func:`bench_methods`), one
    thread."""
    frames: list[ScoredFrame] = []
    for name, method in bench_methods(models):
        for rows in sessions.values():
            frames.extend(score_session(method, name, rows, use_reference))
    return frames


def bench_methods(models: Sequence[BenchModel]) -> list[tuple[str, Method]]:
    """``(name, method)`` of every method scored, one thread, each U-Net built from its model's
    content as read (:func:`~contactcal.infer.bench.models.load_models`): ``METHODS`` (the
    U-Net of ``models[0]``), then the variants ``models[1:]`` as ``unet[label]``."""
    main, *variants = models
    methods = [(name, main.method(name, outline=True)) for name in METHODS]
    return methods + [(v.name, v.method(outline=True)) for v in variants]


def no_reference_modes(models: Sequence[BenchModel]) -> dict[str, str]:
    """What each method does without a reference frame (its ``NO_REFERENCE`` note, as
    ``measure`` prints it: for a U-Net, the model's own mode, blank placeholder or the frame
    itself), by method name."""
    return {name: method.NO_REFERENCE for name, method in bench_methods(models)}


def variant_name(label: str) -> str:
    """Method name of a U-Net variant in the tables: ``unet[label]``."""
    return f"unet[{label}]"


def to_record(frame: ScoredFrame) -> dict[str, Any]:
    """A frame as a ``results.json`` record: its fields plus ``true_contact`` and ``covered``
    (the stated ``area_interval_px``, a ``[lower, upper]`` list or None, contains the truth)."""
    iv = frame.area_interval_px
    return {
        **asdict(frame),
        "area_interval_px": None if iv is None else [float(iv[0]), float(iv[1])],
        "true_contact": frame.true_contact,
        "covered": frame.covered,
    }


def from_record(record: Mapping[str, Any]) -> ScoredFrame:
    """The frame of a ``results.json`` record (derived keys such as ``true_contact`` ignored)."""
    names = {f.name for f in fields(ScoredFrame)}
    values = {k: v for k, v in record.items() if k in names}
    if values.get("area_interval_px") is not None:
        values["area_interval_px"] = tuple(float(x) for x in values["area_interval_px"])
    return ScoredFrame(**values)

"""Scoring measured frames against hand labels: per-frame records, bins and the onset.

Areas are compared with the label's RASTERISED pixel count (for an ellipse too: its analytic
area ``π·major·minor/4`` is recorded beside it), so the relative error and the IoU refer to the
same pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.bench.scoring import ScoredFrame, outline_iou, session_revised
from contactcal.infer.calibration.fit import estimate_onset
from contactcal.infer.calibration.steps import pool
from contactcal.infer.evaluate.label_raster import LabelMask
from contactcal.infer.pipeline.manifest_rows import listed_name
from contactcal.infer.pipeline.measure import Measured
from contactcal.infer.pipeline.scale import PixelScale


def score_frames(
    session: str,
    pressures: Sequence[float],
    labels: Sequence[LabelMask],
    measured: dict[str, list[Measured]],
    scale: PixelScale | None = None,
) -> list[ScoredFrame]:
    """One :class:`ScoredFrame` per method and labelled frame (label area = rasterised count).

    Args:
        session: session key (the manifest's path).
        pressures: ``(N,)`` kPa of the labelled frames.
        labels: the N rasterised labels, same order.
        measured: per method name, the N measurements, same order.
        scale: the rig's pixel scale (then the bins state errors in mm² too); None: px only.
    """
    out = []
    for name, ms in measured.items():
        for p, lab, m in zip(pressures, labels, ms, strict=True):
            out.append(
                ScoredFrame(
                    method=name,
                    session=session,
                    frame=str(m.file),
                    pressure_kpa=float(p),
                    true_area_px=float(lab.area_px),
                    area_px=float(m.result.area_px),
                    contact=bool(m.result.contact),
                    iou=outline_iou(m.result, lab.mask) if lab.area_px > 0 else None,
                    area_interval_px=m.result.area_interval_px,
                    mm_per_px=None if scale is None else scale.at_width(m.width),
                )
            )
    return out


def _result(s: ScoredFrame) -> dict[str, Any]:
    return {
        "contact": s.contact,
        "area_px": s.area_px,
        "rel_error": s.rel_error if s.true_contact else None,
        "iou": s.iou,
    }


def frame_records(
    folder: Path,
    labels: Sequence[LabelMask],
    sources: Sequence[str],
    scored: Sequence[ScoredFrame],
) -> list[dict[str, Any]]:
    """``evaluation.json``'s ``frames``: per labelled frame, its label and each method's result.

    Args:
        folder: the manifest's :attr:`~contactcal.infer.pipeline.manifest.Session.folder`
            (frames are named as the manifest lists them).
        labels: the N rasterised labels, in frame order.
        sources: the N labels' locations (mask file or ``CSV row N``).
        scored: :func:`score_frames` of the same frames, each method's N frames in that order.

    ``rel_error`` and ``iou`` are null for a frame labelled without contact.
    """
    by_method: dict[str, list[ScoredFrame]] = {}
    for s in scored:
        by_method.setdefault(s.method, []).append(s)
    records = []
    for i, (lab, src) in enumerate(zip(labels, sources, strict=True)):
        first = next(iter(by_method.values()))[i]
        records.append(
            {
                "file": listed_name(folder, first.frame),
                "pressure_kpa": first.pressure_kpa,
                "label": src,
                "label_area_px": lab.area_px,
                "label_area_analytic_px": lab.analytic_area_px,
                "label_note": lab.note,
                "results": {m: _result(fs[i]) for m, fs in by_method.items()},
            }
        )
    return records


def onset_summary(scored: Sequence[ScoredFrame]) -> dict[str, Any]:
    """Onset from the labels vs from each method (both by ``estimate_onset``), kPa; a method
    that states intervals after ``calibrate``'s session rule, as its calibration would report.

    Frames at the same pressure (repeats, or a loading and an unloading pass) are pooled into
    one step: its median area, in contact when at least half of its frames are (said in
    ``note``).

    Returns:
        ``{"labels_onset_kpa", "methods": {name: {"onset_kpa", "error_kpa"}}, "note"}``; the
        onsets are null (with the reason in ``note``) when the labelled frames do not give at
        least two distinct pressures.
    """
    methods = sorted({s.method for s in scored})
    first = [s for s in scored if s.method == methods[0]]
    p = sorted({s.pressure_kpa for s in first})
    if len(p) < 2:
        note = (
            f"onset not compared: it needs labelled frames at >= 2 distinct pressures, got "
            f"{len(first)} frame(s) at {len(p)} pressure(s)"
        )
        none = {"onset_kpa": None, "error_kpa": None}
        return {"labels_onset_kpa": None, "methods": {m: none for m in methods}, "note": note}
    truth = estimate_onset(p, *_steps(first, p, truth=True))
    out: dict[str, Any] = {}
    for m in methods:
        mine = [s for s in scored if s.method == m]
        areas, contacts = _steps(mine, p, truth=False)
        contacts = _session_rule(mine, p, contacts)
        est = estimate_onset(p, areas, contacts)
        err = None if est is None or truth is None else est - truth
        out[m] = {"onset_kpa": est, "error_kpa": err}
    note = "" if len(p) == len(first) else "frames at one pressure pooled (median, majority)"
    if truth is None:
        note = "no contact range in the labels: no onset to compare"
    elif min(first, key=lambda s: s.pressure_kpa).true_contact:
        note = (
            f"the lowest labelled frame ({min(p):g} kPa) has contact, so the labels' onset is only "
            "bounded by it: label a frame without contact below the onset"
        )
    return {"labels_onset_kpa": truth, "methods": out, "note": note}


def _session_rule(
    frames: Sequence[ScoredFrame], pressures: Sequence[float], contacts: list[bool]
) -> list[bool]:
    """The steps' contact flags after ``calibrate``'s session rule (``rings.py``).

    Args:
        frames: one method's labelled frames (all passes pooled per pressure, as the onset
            here pools them).
        pressures: the distinct pressures, kPa, ascending (the steps).
        contacts: per step, in contact (majority of its frames).

    Returns:
        Per step, in contact and not revised (unchanged for a method without intervals).
    """
    revised = {s.pressure_kpa for s, r in zip(frames, session_revised(frames), strict=True) if r}
    return [c and q not in revised for c, q in zip(contacts, pressures, strict=True)]


def _steps(
    frames: Sequence[ScoredFrame], pressures: Sequence[float], truth: bool
) -> tuple[list[float], list[bool]]:
    """Per pressure: the median area and majority contact of its frames (labels or method)."""
    areas, contacts = [], []
    for q in pressures:
        at = [s for s in frames if s.pressure_kpa == q]
        area, contact = pool(
            [s.true_area_px if truth else s.area_px for s in at],
            [s.true_contact if truth else s.contact for s in at],
        )
        areas.append(area)
        contacts.append(contact)
    return areas, contacts

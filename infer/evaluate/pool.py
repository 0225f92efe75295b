"""``contactcal boundary-offset``: one rig's boundary offset from several sessions' evaluations.

``contactcal evaluate`` measures the offset on one session's labelled frames; its interval is
over those frames only. Sessions of one rig differ more than frames of one session do (on the
procedural cross-check sets the per-session medians spread by ~0.09 mm, on our renders by
~0.05 mm: ``docs/training.md``, "Boundary offset"), so the offset to put in the rig config is
pooled here over sessions: the median of the sessions' medians with the same distribution-free
90 % interval (:func:`~contactcal.infer.evaluate.offset.median_interval`, now over sessions),
applied only when that interval excludes 0. That interval needs five sessions.

Each session counts once: evaluations that read a byte-identical frame (a copied evaluation
folder, ``evaluate`` run twice on one session) or the same contact labels (one session's frames
re-encoded, e.g. as JPEG and as PNG) are refused with both files named, and an
evaluation without the frames' digests (an older ``evaluate``) is refused as unverifiable
(:mod:`~contactcal.infer.evaluate.identity`).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.evaluate.identity import (
    check_distinct_labels,
    check_distinct_sessions,
    read_frame_digests,
    read_label_areas,
)
from contactcal.infer.evaluate.offset import (
    MIN_FRAMES,
    UNRESOLVED,
    excludes_zero,
    median_interval,
    rig_total,
)
from contactcal.infer.files.regular import read_input_json
from contactcal.infer.pipeline.boundary import MAX_OFFSET_MM, MODEL_KEY, OFFSET_KEY

#: Fewest sessions pooled: the median's 90 % interval needs five values.
MIN_SESSIONS = 5


def _finite_list(value: object) -> bool:
    return isinstance(value, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
    )


def _load(file: Path) -> dict[str, Any]:
    """The ``boundary_offset`` of the evaluation ``file`` (a folder given was mapped to its
    ``evaluation.json`` by :func:`_sessions`), checked; ValueError naming the file otherwise."""
    try:
        record = read_input_json(file, "the evaluation.json of `contactcal evaluate`", ValueError)
    except (FileNotFoundError, NotADirectoryError):
        raise ValueError(
            f"{file}: missing; expected the evaluation.json that `contactcal evaluate ... --out "
            "DIR` writes into DIR (give each session's DIR, or that file)"
        ) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(
            f"{file}: not a readable evaluation.json of `contactcal evaluate`"
        ) from exc
    off = record.get("boundary_offset") if isinstance(record, dict) else None
    keys = ("model_sha256", "applied_mm", "frame_offsets_mm")
    if not isinstance(off, dict) or any(k not in off for k in keys):
        raise ValueError(
            f"{file}: has no U-Net boundary offsets per frame; run `contactcal evaluate` (this "
            "version) with the U-Net"
        )
    if off["frame_offsets_mm"] is None:
        raise ValueError(
            f"{file}: its offsets are in pixels only; run `contactcal evaluate` with the rig's "
            "scale (--rig, --mm-per-px or a rig.json beside the manifest)"
        )
    applied = off["applied_mm"]
    if not _finite_list(off["frame_offsets_mm"]) or not (
        applied is None or _finite_list([applied])
    ):
        raise ValueError(f"{file}: boundary_offset holds values that are not finite numbers")
    digests, labels = read_frame_digests(str(file), record), read_label_areas(str(file), record)
    return {**off, "file": str(file), "digests": digests, "labels": labels}


def _same(runs: Sequence[dict[str, Any]], key: str, what: str) -> Any:
    """The one value of ``key`` in every run; ValueError naming the runs otherwise."""
    if len({json.dumps(r[key]) for r in runs}) > 1:
        listed = ", ".join(f"{r['file']}: {r[key]}" for r in runs)
        raise ValueError(f"the evaluations differ in {what} ({listed}); pool runs of one setting")
    return runs[0][key]


def _sessions(paths: Sequence[str | os.PathLike[str]]) -> tuple[list[dict], list[str]]:
    """The evaluations with at least ``MIN_FRAMES`` frames, and the files of those left out."""
    files = [Path(p) / "evaluation.json" if Path(p).is_dir() else Path(p) for p in paths]
    twice = {f for f in files if sum(g.resolve() == f.resolve() for g in files) > 1}
    if twice:
        raise ValueError(f"{sorted(map(str, twice))[0]}: given twice; each session counts once")
    runs = [_load(f) for f in files]
    check_distinct_sessions(runs)
    check_distinct_labels(runs)
    kept = [r for r in runs if len(r["frame_offsets_mm"]) >= MIN_FRAMES]
    return kept, [r["file"] for r in runs if r not in kept]


def _check_each_fits(
    runs: Sequence[dict[str, Any]], meds: list[float], applied: float | None
) -> None:
    """Refuse a session whose own offset (with the one applied, rounded as ``evaluate`` rounds it)
    is beyond ``MAX_OFFSET_MM``: the model does not fit it (or its labels or scale are wrong), and
    a median over sessions would hide that."""
    for r, m in zip(runs, meds, strict=True):
        total, fits = rig_total(m, applied)  # as evaluate states it
        if not fits:
            raise ValueError(
                f"{r['file']}: this session's offset {total:+.3f} mm is beyond the ±"
                f"{MAX_OFFSET_MM:g} mm a rig config accepts: the model does not fit that session, "
                "or its labels or scale are wrong; check its labels, scale and overlays, or leave "
                "it out of the pool"
            )


def pool_offsets(paths: Sequence[str | os.PathLike[str]]) -> dict[str, Any]:
    """The pooled offset of several sessions' evaluations (folders or ``evaluation.json``).

    Returns:
        ``sessions`` (file, frames, median mm each), ``left_out`` (files with fewer than
        ``MIN_FRAMES`` frames), ``median_mm`` (of the sessions' medians), ``interval_mm``
        (``median_interval`` over sessions), ``applied_mm``, ``rig_config`` (the two keys with
        applied + pooled; None when the interval includes 0) and a ``note``.

    Raises:
        ValueError: a file given twice, evaluations of one session (a frame read by both, or
            the same contact labels), an unusable evaluation (one without frame digests or
            labels too), evaluations of different models
            or applied offsets, fewer than :data:`MIN_SESSIONS` usable sessions, or a session
            whose own offset is beyond ``MAX_OFFSET_MM``.
    """
    runs, left_out = _sessions(paths)
    if len(runs) < MIN_SESSIONS:
        raise ValueError(
            f"{len(runs)} of {len(paths)} evaluation(s) have >= {MIN_FRAMES} frames in contact "
            f"by both the labels and the U-Net; pooling needs {MIN_SESSIONS} such sessions (a "
            "90 % interval of a median needs five values)"
        )
    sha = _same(runs, "model_sha256", "model")
    applied = _same(runs, "applied_mm", "the boundary offset already applied")
    meds = [float(np.median(r["frame_offsets_mm"])) for r in runs]
    _check_each_fits(runs, meds, applied)
    interval = median_interval(meds)
    median = float(np.median(meds))
    total, _ = rig_total(median, applied)  # within: every session is
    resolved = excludes_zero(interval)
    note = "" if resolved else UNRESOLVED
    return {
        "sessions": [
            {"file": r["file"], "frames": len(r["frame_offsets_mm"]), "median_mm": m}
            for r, m in zip(runs, meds, strict=True)
        ],
        "left_out": left_out,
        "median_mm": median,
        "interval_mm": interval,
        "applied_mm": applied,
        "rig_config": {OFFSET_KEY: total, MODEL_KEY: sha} if resolved else None,
        "note": note,
    }


def pooled_text(pooled: dict[str, Any]) -> str:
    """The lines ``contactcal boundary-offset`` prints."""
    lines = [
        f"{s['file']}: {s['frames']} frames, {s['median_mm']:+.3f} mm" for s in pooled["sessions"]
    ]
    lines += [
        f"{f}: left out (fewer than {MIN_FRAMES} frames in contact)" for f in pooled["left_out"]
    ]
    lo, hi = pooled["interval_mm"]
    lines.append(
        f"pooled over {len(pooled['sessions'])} sessions: {pooled['median_mm']:+.3f} mm "
        f"(90 % interval {lo:+.3f} … {hi:+.3f}, over sessions)"
    )
    if pooled["rig_config"] is None:
        lines.append(f"  {pooled['note']}")
    else:
        keys = ", ".join(
            f"{json.dumps(k)}: {json.dumps(v)}" for k, v in pooled["rig_config"].items()
        )
        lines.append(f"  to apply it, put in the rig config: {keys}")
    return "\n".join(lines)

"""``contactcal boundary-offset``: one rig's boundary offset from several sessions' evaluations.

``contactcal evaluate`` measures the offset on one session's labelled frames; its interval is
over those frames only. Sessions of one rig differ more than frames of one session do (on the
procedural cross-check sets the per-session medians spread by ~0.09 mm, on our renders by
~0.05 mm: ``docs/training.md``, "Boundary offset"), so the offset to put in the rig config is
pooled here over sessions: the median of the sessions' medians, with a 90 % interval from
resampling whole sessions, applied only when that interval excludes 0.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.evaluate.offset import RESAMPLES, SEED
from contactcal.infer.pipeline.boundary import MAX_OFFSET_MM, MODEL_KEY, OFFSET_KEY

#: Fewest sessions pooled: with one, `evaluate`'s own figure is all there is.
MIN_SESSIONS = 2


def _load(path: Path) -> dict[str, Any]:
    """An evaluation's ``boundary_offset``, checked to carry per-frame offsets in mm."""
    file = path / "evaluation.json" if path.is_dir() else path
    try:
        off = json.loads(file.read_text(encoding="utf-8")).get("boundary_offset")
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, AttributeError) as exc:
        raise ValueError(
            f"{file}: not a readable evaluation.json of `contactcal evaluate`"
        ) from exc
    if not off or off.get("frame_offsets_mm") is None:
        raise ValueError(
            f"{file}: has no U-Net boundary offsets in mm; run `contactcal evaluate` with the "
            "U-Net and the rig's scale (--rig, --mm-per-px or a rig.json beside the manifest)"
        )
    return {**off, "file": str(file)}


def _same(runs: Sequence[dict[str, Any]], key: str, what: str) -> Any:
    """The one value of ``key`` in every run; ValueError naming the runs otherwise."""
    values = {json.dumps(r[key]) for r in runs}
    if len(values) > 1:
        listed = ", ".join(f"{r['file']}: {r[key]}" for r in runs)
        raise ValueError(f"the evaluations differ in {what} ({listed}); pool runs of one setting")
    return runs[0][key]


def pool_offsets(paths: Sequence[str | os.PathLike[str]]) -> dict[str, Any]:
    """The pooled offset of several sessions' evaluations (folders or ``evaluation.json``).

    Returns:
        ``sessions`` (file, frames, median mm each), ``median_mm`` (of the sessions' medians),
        ``interval_mm`` (90 %, bootstrap over sessions; seeded), ``applied_mm``,
        ``rig_config`` (the two keys with applied + pooled, or None when the interval includes
        0 or the total is beyond ``MAX_OFFSET_MM``) and a ``note``.

    Raises:
        ValueError: fewer than :data:`MIN_SESSIONS` evaluations, one without offsets in mm, or
            evaluations of different models or applied offsets.
    """
    if len(paths) < MIN_SESSIONS:
        raise ValueError(
            f"boundary-offset pools {MIN_SESSIONS} or more sessions' evaluations, got "
            f"{len(paths)}; for one session `contactcal evaluate` prints its offset"
        )
    runs = [_load(Path(p)) for p in paths]
    sha = _same(runs, "model_sha256", "model")
    applied = _same(runs, "applied_mm", "the boundary offset already applied")
    runs = [r for r in runs if r["frame_offsets_mm"]]
    if len(runs) < MIN_SESSIONS:
        raise ValueError(
            f"only {len(runs)} of the {len(paths)} evaluations have frames in contact by both "
            "the labels and the U-Net; label frames in contact in each session"
        )
    meds = np.array([np.median(r["frame_offsets_mm"]) for r in runs])
    idx = np.random.default_rng(SEED).integers(0, meds.size, size=(RESAMPLES, meds.size))
    lo, hi = (float(x) for x in np.percentile(np.median(meds[idx], axis=1), (5, 95)))
    median = float(np.median(meds))
    total = round(median + (applied or 0.0), 3)
    ok = (lo > 0.0 or hi < 0.0) and abs(total) <= MAX_OFFSET_MM
    return {
        "sessions": [
            {"file": r["file"], "frames": len(r["frame_offsets_mm"]), "median_mm": float(m)}
            for r, m in zip(runs, meds, strict=True)
        ],
        "median_mm": median,
        "interval_mm": (lo, hi),
        "applied_mm": applied,
        "rig_config": {OFFSET_KEY: total, MODEL_KEY: sha} if ok else None,
        "note": ""
        if ok
        else f"no offset resolved (interval includes 0) or beyond ±{MAX_OFFSET_MM:g} mm",
    }


def pooled_text(pooled: dict[str, Any]) -> str:
    """The lines ``contactcal boundary-offset`` prints."""
    lines = [
        f"{s['file']}: {s['frames']} frames, {s['median_mm']:+.3f} mm" for s in pooled["sessions"]
    ]
    lo, hi = pooled["interval_mm"]
    lines.append(
        f"pooled over {len(pooled['sessions'])} sessions: {pooled['median_mm']:+.3f} mm "
        f"(90 % interval {lo:+.3f} … {hi:+.3f}, resampling sessions)"
    )
    if pooled["rig_config"] is None:
        lines.append(f"  {pooled['note']}: nothing to change in the rig config")
    else:
        keys = ", ".join(
            f"{json.dumps(k)}: {json.dumps(v)}" for k, v in pooled["rig_config"].items()
        )
        lines.append(f"  to apply it, put in the rig config: {keys}")
    return "\n".join(lines)

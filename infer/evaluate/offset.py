"""The rig's boundary offset measured against hand labels (``contactcal evaluate``).

Per labelled frame in contact (by the label and by the U-Net), the outward move of the U-Net's
boundary that would give the label's area (:func:`~contactcal.infer.pipeline.boundary.fit_offset`,
from the region's area and perimeter); the session's offset is their median, with a 90 %
distribution-free interval (:func:`median_interval`). The result names the rig config keys that
apply it (:mod:`contactcal.infer.pipeline.boundary`) when that interval excludes 0.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from contactcal.infer.pipeline.boundary import (
    MAX_OFFSET_MM,
    MODEL_KEY,
    OFFSET_KEY,
    BoundaryOffset,
    fit_offset,
)
from contactcal.infer.pipeline.measure import Measured
from contactcal.infer.pipeline.scale import PixelScale

#: Coverage of the median's interval. With fewer than 5 values no interval of order
#: statistics reaches it ([min, max] of 4 values covers 87.5 %): hence at least 5 frames, and 5
#: sessions when pooling.
LEVEL = 0.90
#: Fewest frames in contact (label and U-Net) that an offset is stated from.
MIN_FRAMES = 5
#: The notes of a measured offset: keys given, or too far to be a rig config's.
APPLY_NOTE = (
    "positive: the labelled edge lies outside the U-Net's, negative: inside; from one session, "
    "and sessions differ by ~0.05-0.09 mm: pool five or more with `contactcal boundary-offset` "
    "before putting rig_config's two keys in the rig config"
)
UNRESOLVED = (
    "its 90 % interval includes 0: no offset is resolved on these frames, nothing to change in "
    "the rig config (label more frames, from several sessions, to resolve a small one)"
)
TOO_FAR = (
    "the labels' edge lies {:+.3f} mm from the U-Net's, beyond the ±"
    f"{MAX_OFFSET_MM:g} mm a rig config accepts: the model does not fit this rig (or the labels "
    "or the scale are wrong); no keys given"
)


def median_interval(values: Sequence[float] | np.ndarray) -> tuple[float, float]:
    """A distribution-free 90 % interval of the median (the sign test's).

    The sorted values' ``[x(k), x(n+1-k)]`` with the largest ``k`` whose coverage
    ``1 − 2·P(Binomial(n, ½) < k)`` is at least :data:`LEVEL`; it assumes independent values
    only (no bootstrap, no seed: a 2-value bootstrap "interval" is their range, and resolves a
    zero offset half the time).

    Raises:
        ValueError: fewer than 5 values (no such interval reaches 90 %).
    """
    x = np.sort(np.asarray(values, dtype=float))
    n = x.size
    tail = [sum(math.comb(n, i) for i in range(k)) / 2.0**n for k in range(1, n // 2 + 2)]
    ks = [k for k, t in enumerate(tail, start=1) if 1.0 - 2.0 * t >= LEVEL]
    if not ks:
        raise ValueError(f"a 90 % interval of a median needs at least 5 values, got {n}")
    k = max(ks)
    return float(x[k - 1]), float(x[n - k])


def excludes_zero(interval: tuple[float, float]) -> bool:
    """The interval lies wholly above or below 0: an offset is resolved."""
    return interval[0] > 0.0 or interval[1] < 0.0


def resolved_offset(values_mm: Sequence[float] | np.ndarray) -> float:
    """The offset to apply from per-frame (or per-session) offsets: their median when its
    interval (:func:`median_interval`) excludes 0, else 0 (none resolved; fewer than 5 values
    resolve none)."""
    if len(values_mm) < MIN_FRAMES or not excludes_zero(median_interval(values_mm)):
        return 0.0
    return float(np.median(values_mm))


def current_offset(
    boundary: BoundaryOffset | None, model_sha256: str | None
) -> tuple[BoundaryOffset | None, str]:
    """What ``evaluate`` applies of the rig config's offset: it unless it was measured for
    another model (stale), which ``measure`` and ``calibrate`` refuse but ``evaluate`` is the
    way to measure again: then none, and a note saying so.

    Returns:
        ``(offset or None, note)``; the note is "" unless the offset was stale.
    """
    if boundary is None or model_sha256 is None or boundary.model_sha256 == model_sha256:
        return boundary, ""
    return None, (
        f"{boundary.source}: its boundary offset ({boundary.mm:+.3f} mm) was measured for the "
        f"model {boundary.model_sha256[:12]}…, not this one ({model_sha256[:12]}…): not applied; "
        "the keys below replace it"
    )


def boundary_offset(
    measured: Sequence[Measured],
    label_areas: Sequence[float],
    scale: PixelScale | None,
    model_sha256: str,
    stale: str = "",
    applied_from: str | None = None,
) -> dict[str, Any]:
    """The U-Net's boundary offset against the labels (the ``boundary_offset`` of
    ``evaluation.json``).

    Args:
        measured: the U-Net's measurements of the labelled frames (any offset already applied).
        label_areas: each frame's label area, input pixels (0: no contact).
        scale: the rig's pixel scale (None: the offset in pixels only).
        model_sha256: the model measured, for the rig config keys.
        stale: :func:`current_offset`'s note, kept as ``stale`` (None when "").
        applied_from: the rig config whose offset the measurements applied, for the record
            and the printed line (kept only when an offset was applied).

    Returns:
        ``frames`` (used), ``frame_offsets_px`` / ``_mm`` (each used frame's), ``model_sha256``,
        ``median_px`` and ``interval_px`` (:func:`median_interval`), the same in mm (None
        without a scale), ``applied_mm`` (the offset the run already applied; the median is
        what remains on top of it), ``applied_from`` (its rig config),
        ``rig_config`` (the two keys with the total offset: applied + measured; None without a
        scale, with fewer than :data:`MIN_FRAMES` frames, when the interval includes 0 or beyond
        ``MAX_OFFSET_MM``), ``stale`` and a ``note``.
    """
    px, mm = [], []
    for m, target in zip(measured, label_areas, strict=True):
        r = m.result
        if target <= 0.0 or not r.contact or r.perimeter_px is None:
            continue
        d = fit_offset(r.area_px, r.perimeter_px, float(target))
        px.append(d)
        mm.append(None if scale is None else d * scale.at_width(m.width))
    applied = measured[0].boundary_offset_mm if measured else None
    out: dict[str, Any] = {"frames": len(px), "applied_mm": applied, "rig_config": None}
    out["applied_from"] = None if applied is None else applied_from
    out["stale"] = stale or None
    out["model_sha256"] = model_sha256
    out["frame_offsets_px"] = px  # per frame used, for `contactcal boundary-offset` (pooling)
    out["frame_offsets_mm"] = None if scale is None else mm
    out.update(median_px=None, interval_px=None, median_mm=None, interval_mm=None)
    if len(px) < MIN_FRAMES:
        out["note"] = (
            f"not measured: {len(px)} frame(s) in contact by both the labels and the U-Net; "
            f"label at least {MIN_FRAMES} frames in contact"
        )
        return out
    out.update(median_px=float(np.median(px)), interval_px=median_interval(np.asarray(px)))
    if scale is None:
        out["note"] = "in pixels only: give the rig's scale (--rig or --mm-per-px) for mm"
        return out
    arr = np.asarray(mm, dtype=float)
    total, fits = rig_total(float(np.median(arr)), applied)
    out.update(median_mm=float(np.median(arr)), interval_mm=median_interval(arr))
    if not excludes_zero(out["interval_mm"]):
        out["note"] = UNRESOLVED
        return out
    if fits:
        out["rig_config"] = {OFFSET_KEY: total, MODEL_KEY: model_sha256}
    out["note"] = TOO_FAR.format(total) if out["rig_config"] is None else APPLY_NOTE
    return out


def rig_total(median_mm: float, applied_mm: float | None) -> tuple[float, bool]:
    """The offset a rig config would state, mm (the measured median plus the one already
    applied, rounded to µm as printed), and whether it is within ``MAX_OFFSET_MM``."""
    total = round(median_mm + (applied_mm or 0.0), 3)
    return total, abs(total) <= MAX_OFFSET_MM


def unet_offset(
    measured: Sequence[Measured],
    label_areas: Sequence[float],
    scale: PixelScale | None,
    described: dict[str, Any],
    stale: str,
    applied_from: str | None = None,
) -> dict[str, Any] | None:
    """:func:`boundary_offset` of the U-Net's measurements (None when the U-Net did not run)."""
    if "unet" not in described:
        return None
    sha = described["unet"]["model_sha256"]
    return boundary_offset(measured, label_areas, scale, sha, stale, applied_from)


def offset_line(off: dict[str, Any]) -> str:
    """The lines for the printed table (a stale or an applied offset's note first)."""
    first = f"note: {off['stale']}\n" if off["stale"] else ""
    if off["applied_mm"] is not None:
        first += (
            f"note: the U-Net's areas include the rig's boundary offset {off['applied_mm']:+.3f} "
            f"mm ({off['applied_from'] or 'rig config'}); the offset below is what remains on "
            "top of it\n"
        )
    return first + _offset_text(off)


def _offset_text(off: dict[str, Any]) -> str:
    """The offset's numbers and the keys that apply it, or why there are none."""
    if off["median_px"] is None:
        return f"boundary offset (unet): {off['note']}"
    lo, hi = off["interval_px"]
    text = f"{off['median_px']:+.2f} px (90 % interval {lo:+.2f} … {hi:+.2f})"
    if off["median_mm"] is not None:
        lo, hi = off["interval_mm"]
        text = f"{off['median_mm']:+.3f} mm (90 % interval {lo:+.3f} … {hi:+.3f}), " + text
    applied = off["applied_mm"]
    remains = "" if applied is None else f" on top of the applied {applied:+.3f} mm"
    line = f"boundary offset (unet) against the labels{remains}, {off['frames']} frames: {text}"
    if off["rig_config"] is None:
        return f"{line}\n  {off['note']}"
    keys = ", ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in off["rig_config"].items())
    what = "it" if applied is None else f"the total ({applied:+.3f} mm applied + this)"
    return (
        f"{line}\n  one session's: pool five or more sessions' evaluations with `contactcal "
        f"boundary-offset` before you apply it; these keys would apply {what}: {keys}"
    )

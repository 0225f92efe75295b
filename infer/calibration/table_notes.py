"""The warning and note lines printed under a calibration's table, in a fixed order."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from contactcal.infer.calibration.gate_check import (
    LOST_ABOVE_CONTACT_WARNING,
    NOT_AT_REST_WARNING,
    REFERENCE_NOTE,
    REST_KPA,
)
from contactcal.infer.calibration.provenance import identical_frames_warning
from contactcal.infer.pipeline.manifest import sweep_top_warning

if TYPE_CHECKING:
    from contactcal.infer.calibration.calibrate import SessionOptions
    from contactcal.infer.calibration.points import CalibrationPoint
    from contactcal.infer.pipeline.manifest import Session

#: Frames a warning listing frames names (without contact above a contact, off their step's
#: median); the record lists all.
LISTED_FRAMES = 5
#: The table's line when readings were pooled into steps (``{p}``: the session's
#: :class:`~contactcal.infer.pipeline.manifest.Pooled`, ``{t}``: the tolerance, kPa).
POOLED_NOTE = (
    "note: {p.frames} frame(s) in {p.steps} step(s) pooled from differing gauge readings "
    "(widest {p.widest_kpa[0]:g}-{p.widest_kpa[1]:g} kPa; readings less than {t:g} kPa apart "
    "are one step at their median, each frame keeping its reading as pressure_kpa_read; "
    "--step-tolerance-kpa 0 reads every distinct value as a step)"
)
#: The table's line when a step was read below 0 kPa (``{r}``: the session's
#: :class:`~contactcal.infer.pipeline.manifest.AtRest`).
AT_REST_NOTE = (
    "note: {r.frames} frame(s) in steps read below 0 kPa (lowest reading {r.lowest_kpa:g} kPa: "
    "the gauge's offset at rest) are given as 0 kPa, each keeping its reading as "
    "pressure_kpa_read"
)
#: The table's line when one or two rows broke an otherwise rising (then falling) row order
#: (``{rows}``: the rows, named; the session was read as one loading pass in pressure order).
OUT_OF_ORDER_WARNING = (
    "warning: {rows} {verb} the rows' order, rising then falling elsewhere, so the session was "
    "read as one loading pass in pressure order (a mistyped pressure, or a frame listed in the "
    "wrong place?); correct the manifest, or state the passes in a 'phase' column"
)


def session_notes(
    session: Session,
    results: list[CalibrationPoint],
    checks: dict[str, object],
    same: list[dict[str, Any]],
    options: SessionOptions,
    off_warning: str | None,
) -> list[str]:
    """The warning and note lines printed under the table, in a fixed order: the reference
    (gated above 0 kPa, or not at rest), identical frames, rows out of order, frames off their
    step (``off_warning``, None when none is), pooled readings, readings below 0 kPa, a sweep
    top far above the display's range."""
    lines = []
    if checks["reference_gated_above_zero"]:
        lines.append("warning: " + REFERENCE_NOTE.format(p=results[0].pressure_kpa))
    elif checks["reference_above_rest_kpa"] is not None:
        name = os.path.basename(results[0].file)
        lines.append(
            NOT_AT_REST_WARNING.format(name=name, p=results[0].pressure_kpa, rest=REST_KPA)
        )
    lost = checks["no_contact_above_contact"]
    if lost:
        shown = ", ".join(os.path.basename(f) for f in lost[:LISTED_FRAMES])
        more = ", …" if len(lost) > LISTED_FRAMES else ""
        lines.append(LOST_ABOVE_CONTACT_WARNING.format(n=len(lost), shown=shown + more))
    if same:
        lines.append(identical_frames_warning(same))
    if session.out_of_order:
        verb = "breaks" if len(session.out_of_order) == 1 else "break"
        lines.append(
            OUT_OF_ORDER_WARNING.format(rows=" and ".join(session.out_of_order), verb=verb)
        )
    if off_warning is not None:
        lines.append(off_warning)
    if session.pooled is not None:
        lines.append(POOLED_NOTE.format(p=session.pooled, t=options.step_tolerance_kpa))
    if session.at_rest is not None:
        lines.append(AT_REST_NOTE.format(r=session.at_rest))
    high = sweep_top_warning(max(f.pressure_kpa for f in session.frames))
    if high is not None:
        lines.append(high)
    return lines

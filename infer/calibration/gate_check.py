"""A session check on the U-Net's change gate: no frame "unchanged" above a pressure in contact.

The change gate (model metadata ``min_change``) decides frame by frame: a region that has not
changed since the zero-pressure frame is no contact. Within one pass of a session the contact
area does not fall as the pressure rises, so a frame the gate called unchanged at a pressure above
one already in contact contradicts the session: a contact there may be too faint for the gate (a
dark patch whose ridges barely show). Such frames keep their decision and get a note that says so
and points to ``--no-change-gate``; the record counts them (``extra.gated_above_contact``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.methods.base import UNCHANGED_NOTE

#: Appended to the note of a frame the gate called unchanged above a pressure in contact.
ABOVE_CONTACT_NOTE = (
    "above {p:g} kPa, which is in contact: contact does not end as the pressure rises; if this "
    "rig's contacts change the image this little, measure with --no-change-gate"
)


def _lowest_contact(points: Sequence[CalibrationPoint]) -> dict[str, float]:
    """kPa: the lowest pressure in contact of each pass (phase) that has one."""
    lowest: dict[str, float] = {}
    for r in points:
        if r.contact:
            lowest[r.phase] = min(lowest.get(r.phase, math.inf), r.pressure_kpa)
    return lowest


def flag_gated_above_contact(
    points: Sequence[CalibrationPoint],
) -> tuple[list[CalibrationPoint], int]:
    """Note the frames the change gate called unchanged above the lowest contact of their pass.

    Args:
        points: the session's frames (after the session rule), any order.

    Returns:
        ``(points, n)``: the same points in the same order, the flagged ones with
        :data:`ABOVE_CONTACT_NOTE` appended to their note (decision and area unchanged), and how
        many were flagged.
    """
    lowest = _lowest_contact(points)
    out, n = [], 0
    for r in points:
        p = lowest.get(r.phase)
        if p is not None and r.note.startswith(UNCHANGED_NOTE) and r.pressure_kpa > p:
            r = replace(r, note=f"{r.note}; {ABOVE_CONTACT_NOTE.format(p=p)}")
            n += 1
        out.append(r)
    return out, n


def lost_above_contact(points: Sequence[CalibrationPoint]) -> list[str]:
    """The frames without contact above the lowest contact of their pass, for any reason (the
    gate, no ring found in a dark or blank frame, the session rule): within a pass contact does
    not end as the pressure rises, so each is a frame to check, and it pulls the fit (a miss
    next to the onset can move it by kPa).

    Returns:
        Their files, in the order given.
    """
    lowest = _lowest_contact(points)
    return [
        r.file for r in points if not r.contact and r.pressure_kpa > lowest.get(r.phase, math.inf)
    ]


#: The warning of :func:`lost_above_contact`'s frames (the first few named).
LOST_ABOVE_CONTACT_WARNING = (
    "warning: {n} frame(s) without contact above a pressure in contact of their pass ({shown}): "
    "contact does not end as the pressure rises, and each pulls the fit; check them (their "
    "notes say why: a dark or blank frame, no ring found, the change gate) and leave them out "
    "of the manifest if they are bad frames"
)


#: A reference frame at or below this pressure (kPa) is at rest: a video step's pressure is the
#: median of a noisy gauge (0.00x kPa at rest), and contact onsets are 2-4 kPa.
REST_KPA = 0.5
#: Appended to the note of a reference frame above :data:`REST_KPA` that the gate called
#: unchanged.
REFERENCE_NOTE = (
    "this is the session's reference frame, compared with itself: at {p:g} kPa the display may "
    "already touch the finger, and the gate cannot tell; record a 0 kPa frame first (or measure "
    "with --no-change-gate)"
)


def flag_gated_reference(points: Sequence[CalibrationPoint]) -> tuple[list[CalibrationPoint], bool]:
    """Note a reference frame above :data:`REST_KPA` whose region the change gate removed.

    The gate compares each frame with the session's reference (its lowest loading frame), so the
    reference itself always looks unchanged: at 0 kPa that is right, above it a contact there is
    lost without a trace (and the onset comes out at the next step).

    Args:
        points: the session's frames in manifest order after sorting, the reference first.

    Returns:
        ``(points, flagged)``: the same points, the reference's note extended by
        :data:`REFERENCE_NOTE` when it is above :data:`REST_KPA` and gated; whether it was.
    """
    ref = points[0] if points else None
    if ref is None or ref.pressure_kpa <= REST_KPA or not ref.note.startswith(UNCHANGED_NOTE):
        return list(points), False
    noted = replace(ref, note=f"{ref.note}; {REFERENCE_NOTE.format(p=ref.pressure_kpa)}")
    return [noted, *points[1:]], True


#: The warning of a session whose reference frame is above :data:`REST_KPA` (any method, gated
#: or not): every frame is compared with it.
NOT_AT_REST_WARNING = (
    "warning: the session's reference frame (its lowest loading frame, {name}) is at {p:g} kPa, "
    "not at rest (<= {rest:g} kPa): every frame is compared with a frame that may already touch "
    "the finger (the U-Net's reference and change gate, the classical routine's region of "
    "interest); record a 0 kPa frame first"
)


def reference_above_rest(points: Sequence[CalibrationPoint]) -> float | None:
    """The reference frame's pressure, kPa, when it is above :data:`REST_KPA`; else None.

    Args:
        points: the session's frames, the reference first.
    """
    if points and points[0].pressure_kpa > REST_KPA:
        return points[0].pressure_kpa
    return None

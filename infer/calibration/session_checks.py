"""The session checks of a calibration, between measuring and fitting: the points as the
calibration reports them (session rule, the change gate's notes, the record's counts), and the
run errors of a session left without contact, in all or in its inverted pass.
"""

from __future__ import annotations

from pathlib import Path

from contactcal.infer.calibration.gate_check import (
    flag_gated_above_contact,
    flag_gated_reference,
    lost_above_contact,
    reference_above_rest,
)
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.rings import revise_points
from contactcal.infer.calibration.session import SessionFit
from contactcal.infer.errors import RunError
from contactcal.infer.methods.base import UNCHANGED_NOTE
from contactcal.infer.pipeline.boundary import GONE_NOTE


def session_points(
    manifest: Path, points: list[CalibrationPoint], session_rule: bool, name: str
) -> tuple[list[CalibrationPoint], dict[str, object]]:
    """The points as the calibration reports them: revised by the session rule (when on),
    checked to keep a contact (:func:`check_contact`), a gated frame above a contact and a
    gated reference above 0 kPa noted (:mod:`~contactcal.infer.calibration.gate_check`); and
    the record's ``extra`` keys counting those notes."""
    results = revise_points(points) if session_rule else points
    check_contact(manifest, points, results, name)
    results, above = flag_gated_above_contact(results)
    results, reference = flag_gated_reference(results)
    checks = {
        "gated_above_contact": above,
        "reference_gated_above_zero": reference,
        "no_contact_above_contact": lost_above_contact(results),
    }
    return results, checks | {"reference_above_rest_kpa": reference_above_rest(results)}


def check_contact(
    manifest: Path, measured: list[CalibrationPoint], results: list[CalibrationPoint], name: str
) -> None:
    """Raise ``RunError`` when no frame is left in contact, saying whether the session rule
    removed the contacts the method found."""
    found = sum(r.contact for r in measured)
    if any(r.contact for r in results):
        return
    if found:
        raise RunError(
            f"{manifest}: the method ({name}) found contact in {found} of its {len(results)} "
            "frames, but the session rule set every one of them to no contact (each region "
            "shrinks at a higher pressure or lies below any contact range); check the pressure "
            "range, or keep the frames' own flags with --per-frame-contact"
        )
    gated = sum(r.note.startswith(UNCHANGED_NOTE) for r in measured)
    gone = sum(r.note.startswith(GONE_NOTE) for r in measured)
    hint = (
        f"; the change gate called {gated} of them unchanged from the reference frame (their "
        "notes): if the contacts on this rig change the image that little, use --no-change-gate"
        if gated
        else ""
    )
    if gone:
        hint += (
            f"; the rig config's boundary offset removed the region of {gone} of them: check "
            "its boundary_offset_mm (measured with `contactcal evaluate`)"
        )
    raise RunError(
        f"{manifest}: no contact detected in any of its {len(results)} frames "
        f"(method {name}); check the frames, the pressure range or the method{hint}"
    )


def check_inverse_contact(manifest: Path, fit: SessionFit) -> None:
    """Raise ``RunError`` when the inverted pass (``--inverse-phase``) has no contact: its curve
    has no inverse, so the record would hold ``inverse: null`` for a controller.

    Valid inputs with an unusable result: a run-time failure (exit 1), as no contact at all.
    """
    name = fit.inverse_phase
    if fit.curve.has_contact:
        return
    others = [ph for ph, f in fit.phases.items() if ph != name and f.curve.has_contact]
    hint = (
        f"; the {others[0]} pass has contact: calibrate with --inverse-phase {others[0]} to "
        "invert it"
        if others
        else ""
    )
    steps = fit.phases[name].steps
    raise RunError(
        f"{manifest}: the {name} pass (the one inverted, --inverse-phase {name}) has no contact "
        f"in any of its {len(steps)} step(s) (up to {max(s.pressure_kpa for s in steps):g} kPa), "
        f"so its curve cannot be inverted; record its steps up into contact{hint}"
    )

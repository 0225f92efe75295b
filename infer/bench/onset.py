"""Contact onsets in ``contactcal bench``: each method's onset per session vs the truth, and the
report's onset table (sessions covered, errors where an onset was found, misses, false onsets)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from contactcal.infer.bench.markdown import Columns
from contactcal.infer.bench.scoring import ScoredFrame, median_or_none
from contactcal.infer.calibration.fit import estimate_onset

#: A session's onset outcome (``onset_errors``' ``outcome``): true contact and an onset found
#: (its error counts); true contact, none found; no frame with true contact, yet an onset found;
#: no true contact and none found (correct, no error).
FOUND, MISSED, FALSE_ONSET, NO_CONTACT = "found", "missed", "false onset", "no contact"


def onset_errors(frames: Sequence[ScoredFrame]) -> list[dict[str, Any]]:
    """Per (method, session): onset estimated from the method's frames vs the truth.

    Returns:
        Rows with ``method``, ``session``, ``onset_kpa`` (estimated, None when no contact range
        was found), ``truth_masks_onset_kpa`` (the same rule on the exact masks),
        ``mechanics_onset_kpa``, ``error_kpa`` (estimated − mechanics, or None) and
        ``outcome`` (:data:`FOUND`, :data:`MISSED`, :data:`FALSE_ONSET` or :data:`NO_CONTACT`:
        whether any frame of the session has true contact, and whether an onset was found).
    """
    groups: dict[tuple[str, str], list[ScoredFrame]] = {}
    for f in frames:
        groups.setdefault((f.method, f.session), []).append(f)
    out = []
    for (method, session), fs in sorted(groups.items()):
        p = [f.pressure_kpa for f in fs]
        est = estimate_onset(p, [f.area_px for f in fs], [f.contact for f in fs])
        truth = estimate_onset(p, [f.true_area_px for f in fs], [f.true_contact for f in fs])
        mech = fs[0].onset_kpa
        error = None if est is None or mech is None else est - mech
        if any(f.true_contact for f in fs):
            outcome = MISSED if est is None else FOUND
        else:
            outcome = NO_CONTACT if est is None else FALSE_ONSET
        out.append(
            {
                "method": method,
                "session": session,
                "onset_kpa": est,
                "truth_masks_onset_kpa": truth,
                "mechanics_onset_kpa": mech,
                "error_kpa": error,
                "outcome": outcome,
            }
        )
    return out


#: The report's onset table.
ONSET_COLUMNS: Columns = (
    ("method", "method", False),
    ("sessions", "sessions", False),
    ("contact_sessions", "with true contact", False),
    ("found", "onset found", False),
    ("median_abs_error_kpa_found", "median abs. error kPa (found)", False),
    ("max_shown", "max abs. error kPa", False),
    ("missed", "missed", False),
    ("false_onsets", "false onset", False),
)


def found_errors(onset: Sequence[Mapping[str, Any]]) -> list[float]:
    """|onset error| (kPa) of the sessions with true contact where an onset was found."""
    return [
        abs(o["error_kpa"]) for o in onset if o["outcome"] == FOUND and o["error_kpa"] is not None
    ]


def onset_table(onset: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per method, over all its sessions: how many have true contact, how many of those got an
    onset (``found``), the median and max |onset error| (kPa) over those, the ``missed`` ones
    (true contact, no onset found) and the ``false_onsets`` (no true contact, an onset found).

    A session without true contact and no onset found is correct: counted in ``sessions`` only.
    """
    out = []
    for method in sorted({o["method"] for o in onset}):
        mine = [o for o in onset if o["method"] == method]
        errs = found_errors(mine)
        out.append(
            {
                "method": method,
                "sessions": len(mine),
                "contact_sessions": sum(o["outcome"] in (FOUND, MISSED) for o in mine),
                "found": sum(o["outcome"] == FOUND for o in mine),
                "median_abs_error_kpa_found": median_or_none(errs),
                "max_abs_error_kpa_found": max(errs, default=None),
                "missed": sum(o["outcome"] == MISSED for o in mine),
                "false_onsets": sum(o["outcome"] == FALSE_ONSET for o in mine),
            }
        )
    return out


#: The report's sentence under the onset table.
ONSET_NOTE = (
    "Errors over the sessions with true contact where the method found an onset; missed: true "
    'contact but no\nonset found (the max then reads "missed"); false onset: no frame with true '
    "contact, yet an onset found.\nA session without true contact and no onset found is correct "
    "(no error)."
)


def onset_shown(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """:func:`onset_table` rows as the report shows them (:data:`ONSET_COLUMNS`): the max reads
    "missed" where a session with true contact got no onset."""
    return [
        {**r, "max_shown": "missed" if r["missed"] else r["max_abs_error_kpa_found"]} for r in rows
    ]

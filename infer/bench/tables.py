"""The accuracy tables of one dataset's scored frames (``contactcal bench``): error per
pressure bin, normal vs hard sessions, coverage of the stated area interval, and the onset."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from contactcal.infer.bench.onset import FALSE_ONSET, MISSED, found_errors, onset_table
from contactcal.infer.bench.scoring import (
    ScoredFrame,
    bin_label,
    bin_table,
    coverage_row,
    covering_bins,
    median_or_none,
    not_references,
)


def _no_contact_accuracy(frames: Sequence[ScoredFrame]) -> float | None:
    none = [f for f in frames if not f.true_contact]
    return sum(not f.contact for f in none) / len(none) if none else None


def hard_table(
    frames: Sequence[ScoredFrame], onset: Sequence[Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """Per method: normal vs hard sessions (exposure, off-centre, faint ridges, dim LEDs)."""
    out = []
    for method in sorted({f.method for f in frames}):
        for hard in (False, True):
            fs = [f for f in frames if f.method == method and f.hard == hard]
            if not fs:
                continue
            cont = [f for f in fs if f.true_contact]
            sess = {f.session for f in fs}
            ons = [o for o in onset if o["method"] == method and o["session"] in sess]
            out.append(
                {
                    "method": method,
                    "sessions": "hard" if hard else "normal",
                    "n": len(sess),
                    "median_abs_rel_error_ge5": median_or_none(
                        [abs(f.rel_error) for f in cont if f.pressure_kpa >= 5]
                    ),
                    "median_abs_rel_error_3to5": median_or_none(
                        [abs(f.rel_error) for f in cont if 3 <= f.pressure_kpa < 5]
                    ),
                    "no_contact_accuracy": _no_contact_accuracy(fs),
                    "median_abs_onset_error_kpa": median_or_none(found_errors(ons)),
                    "onset_missing": sum(o["outcome"] == MISSED for o in ons),
                    "false_onsets": sum(o["outcome"] == FALSE_ONSET for o in ons),
                }
            )
    return out


def coverage_table(
    frames: Sequence[ScoredFrame], bins: Sequence[tuple[float, float]]
) -> list[dict[str, Any]]:
    """Per method: coverage of its stated area interval per pressure bin and overall.

    A method that states no interval (the classical routine) gets one row, ``bin_kpa`` "no
    interval", with no values.
    """
    out: list[dict[str, Any]] = []
    for method in sorted({f.method for f in frames}):
        fs = [f for f in frames if f.method == method]
        if all(f.area_interval_px is None for f in fs):
            out.append({"method": method, "bin_kpa": "no interval"})
            continue
        for lo, hi in bins:
            sel = [f for f in fs if lo <= f.pressure_kpa < hi]
            out.append({"method": method, "bin_kpa": bin_label(lo, hi), **coverage_row(sel)})
        out.append({"method": method, "bin_kpa": "all", **coverage_row(fs)})
    return out


def accuracy_tables(
    frames: Sequence[ScoredFrame],
    onset: Sequence[Mapping[str, Any]],
    bins: Sequence[tuple[float, float]],
) -> dict[str, list[dict[str, Any]]]:
    """The ``bins``, ``hard``, ``coverage`` and ``onset_table`` (:func:`onset_table`) tables of
    one dataset's scored frames (the last bin opened when a frame lies past it:
    :func:`~contactcal.infer.bench.scoring.covering_bins`). The sessions' reference frames are
    left out of the tables (:func:`~contactcal.infer.bench.scoring.not_references`); ``onset``
    was estimated from whole sessions."""
    scored = not_references(frames)
    bins = covering_bins([f.pressure_kpa for f in scored], bins)
    return {
        "bins": bin_table(scored, bins),
        "hard": hard_table(scored, onset),
        "coverage": coverage_table(scored, bins),
        "onset_table": onset_table(onset),
    }

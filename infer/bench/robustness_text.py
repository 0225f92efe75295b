"""The robustness section of ``contactcal bench``'s report (``--robustness``; the suite itself is
:mod:`~contactcal.infer.bench.robustness`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from contactcal.infer.bench.markdown import md_table


def unperturbed_note(methods: Sequence[str]) -> str:
    """The sentence that ``methods`` (``--variant`` models) were left out of the suite ("" for
    none): the suite measures ``--model`` and the classical routine only (each method costs ~50
    perturbed measurements per frame)."""
    if not methods:
        return ""
    return (
        "--robustness measures --model and the classical routine only; variants "
        f"{', '.join(methods)} were not perturbed"
    )


def _worst_in_range(rows: Sequence[Mapping[str, Any]], methods: Sequence[str]) -> str:
    """One line per method: the largest error ratio at a randomised, non-baseline level."""
    lines = []
    for m in methods:
        cands = [
            r
            for r in rows
            if r["method"] == m and r["in_range"] and not r["baseline"] and r["error_ratio"]
        ]
        if not cands:
            lines.append(f"- {m}: no randomised level with a defined error ratio")
            continue
        w = max(cands, key=lambda r: r["error_ratio"])
        lines.append(
            f"- {m}: worst ratio inside the randomised ranges {_ratio(w)}, "
            f"{_change(w)} points ({w['perturbation']} {w['label']})"
        )
    return "\n".join(lines)


def _ratio(row: Mapping[str, Any]) -> str | None:
    """A robustness row's error ratio with its 90 % interval: ``"2.19× (1.41-3.02)"``."""
    ratio, interval = row["error_ratio"], row.get("error_ratio_interval")
    if ratio is None:
        return None
    text = f"{ratio:.2f}×"
    return text if interval is None else f"{text} ({interval[0]:.2f}-{interval[1]:.2f})"


def _change(row: Mapping[str, Any]) -> str | None:
    """A robustness row's error change from its baseline level, signed: ``"+1.23"`` points."""
    change = row["error_change_points"]
    return None if change is None else f"{change:+.2f}"


def _unperturbed(rob: Mapping[str, Any]) -> str:
    """The sentence naming the ``--variant`` models the suite left out ("" for none)."""
    note = unperturbed_note(rob.get("not_perturbed", []))
    return f"\n\n{note}." if note else ""


def robustness_text(rob: Mapping[str, Any]) -> str:
    """The report's robustness section: one table row per perturbation and level, each method's
    error at ≥ 5 kPa, its ratio to and change from the baseline level's, and its no-contact
    accuracy."""
    methods = list(dict.fromkeys(r["method"] for r in rob["rows"]))
    cols: list[tuple[str, str, bool]] = [("perturbation", "perturbation", False)]
    cols.append(("label", "level", False))
    cols.append(("range", "randomised", False))
    for m in methods:
        cols += [(f"{m} err", f"{m} ≥5 kPa", True), (f"{m} ratio", "× base (90 % interval)", False)]
        cols.append((f"{m} change", "− base, points", False))
        cols.append((f"{m} nc", f"{m} no-contact acc.", True))
    table: dict[tuple[str, float], dict[str, Any]] = {}
    for r in rob["rows"]:
        row = table.setdefault(
            (r["perturbation"], r["level"]), {**r, "range": "yes" if r["in_range"] else "no"}
        )
        m = r["method"]
        row[f"{m} err"], row[f"{m} ratio"] = r["median_abs_rel_error_ge5"], _ratio(r)
        row[f"{m} change"], row[f"{m} nc"] = _change(r), r["no_contact_accuracy"]
    first = rob["rows"][0]
    refs = "\n".join(
        f"- {p['name']} ({p['unit']}): reference {p['reference']}" for p in rob["perturbations"]
    )
    return (
        "## Robustness to perturbed frames\n\n"
        f"{len(rob['frames'])} frames sampled evenly across pressures and sessions (seed "
        f"{rob['seed']}), each measured at every\nlevel of every perturbation "
        "(`contactcal.infer.bench.perturb` documents the levels and the truth).\n"
        f"≥5 kPa: median |relative area error| over the {first['contact_frames_ge5']} frames "
        "with true contact at ≥ 5 kPa; × base: its\nratio to the perturbation's unperturbed "
        "level, with a 90 % bootstrap interval over\nthose frames (each resample keeps a frame's "
        "errors at both levels); − base: the error minus the unperturbed level's, in "
        "percentage\npoints; no-contact acc.: share of the "
        f"{first['no_contact_frames']} frames without true contact reported as no contact. "
        f"The reference frame\nper perturbation:\n\n{refs}\n\n"
        "randomised: the level lies inside what the training renders or augmentation randomise "
        "(`suite.PERTURBATIONS`),\nwhere the error target (≤ 2× the unperturbed error) "
        "applies. The perturbations are applied on top of the\nheld-out renders' own "
        "randomised degradation (their exposure, blur, noise, JPEG, ...), so a level at the "
        "top\nof a randomised range can exceed what any training frame had."
        + _unperturbed(rob)
        + "\n\n"
        + _worst_in_range(rob["rows"], methods)
        + "\n\n"
        + md_table(list(table.values()), cols)
        + "\n\n![robustness](robustness.png)\n\n"
        + _no_contact_intro(first["no_contact_frames"], len(rob["frames"]))
        + "\n\n![robustness, no-contact accuracy](robustness_no_contact.png)"
    )


def _no_contact_intro(no_contact: int, sampled: int) -> str:
    """The line above ``robustness_no_contact.png``: what it shows, or that it shows no points
    because no sampled frame is without true contact."""
    if no_contact:
        return "No-contact accuracy per level (frames without true contact):"
    return (
        f"No-contact accuracy per level: none of the {sampled} sampled frames is without true "
        "contact, so the figure has no points (its panels say so); a larger sample "
        "(`--robustness-frames`) takes frames without contact where the set has them:"
    )

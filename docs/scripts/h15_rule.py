"""H15's rule (``docs/training.md``, "H15"), condition by condition, from the chain's bench runs.

Reads the choosing run (``out/h15_choose/results.json``: v2.4 as ``unet``, the candidate as
``unet[h15]``, the cross-check sets by label) and the two robustness runs (``out/h15_rob_v24``,
``out/h15_rob_h15``: each model as ``unet``), and prints (a)-(e) with both models' values, the
bound and PASS/FAIL; exit 0 whatever the verdict, 2 on unreadable input. Values are compared
unrounded. Condition (e) leaves out each session's reference frame (its lowest pressure): a
reference measured against itself is "no contact" for every model with the change gate, so it
would only dilute the pool (amended before H15 was trained; the count with them is printed too).

    .venv/bin/python docs/scripts/h15_rule.py out/h15_choose/results.json \
        out/h15_rob_v24/results.json out/h15_rob_h15/results.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rule_scores import datasets, scores

BASE, CANDIDATE = "unet", "unet[h15]"
#: (label, sets pooled, the candidate's allowed excess over v2.4 in points) of (a)-(c).
ERROR_CONDITIONS = (
    ("(a) procedural 7800+7900, median err >= 5 kPa", ("cc7800_hr", "cc7900_hr"), 0.5),
    ("(b) val_depart, median err >= 5 kPa", ("val_depart",), 0.0),
    ("(c) val_v6, median err >= 5 kPa", ("main",), 0.2),
)
#: The sets of (e), pooled; and its allowed loss in points.
NO_CONTACT_SETS = ("main", "val_v6_depart", "val_v6_onset", "val_depart", "val_r3", "v2_cal")
NO_CONTACT_LOSS = 1.0
#: (d): the largest error ratio at a randomised, non-baseline level.
MAX_RATIO = 2.0


def without_references(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The records less each (method, session)'s lowest-pressure frame, its reference."""
    low: dict[tuple[str, str], float] = {}
    for r in records:
        key = (r["method"], r["session"])
        low[key] = min(low.get(key, r["pressure_kpa"]), r["pressure_kpa"])
    return [r for r in records if r["pressure_kpa"] > low[(r["method"], r["session"])]]


def worst_ratio(robustness: dict[str, Any]) -> tuple[float, str]:
    """``unet``'s largest in-range, non-baseline error ratio and where it is."""
    rows = [
        r
        for r in robustness["rows"]
        if r["method"] == BASE and r["in_range"] and not r["baseline"] and r["error_ratio"]
    ]
    if not rows:
        raise ValueError("no in-range robustness level with an error ratio")
    w = max(rows, key=lambda r: r["error_ratio"])
    return float(w["error_ratio"]), f"{w['perturbation']} {w['label']}"


def _both(label: str, s: dict[str, dict[str, Any]], key: str) -> tuple[float, float]:
    """v2.4's and H15's ``key`` in :func:`scores` output; ValueError naming the condition when
    a model or its value is missing (no frames of that kind)."""
    try:
        b, c = s[BASE][key], s[CANDIDATE][key]
    except KeyError as e:
        raise ValueError(f"{label}: no records of {e}; expected {BASE} and {CANDIDATE}") from None
    if b is None or c is None:
        raise ValueError(f"{label}: no frames to score ({key}: v2.4 {b}, H15 {c})")
    return float(b), float(c)


def verdicts(
    choose: dict[str, Any], rob_base: dict[str, Any], rob_cand: dict[str, Any]
) -> list[str]:
    """One Markdown table row per condition.

    Raises:
        ValueError: a set the rule reads is missing, or a condition has no frames to score.
    """
    per_set = datasets(choose)
    needed = {k for _, sets, _ in ERROR_CONDITIONS for k in sets} | set(NO_CONTACT_SETS)
    if missing := sorted(needed - set(per_set)):
        raise ValueError(f"no dataset {missing} in the choosing run; it has {sorted(per_set)}")
    lines = []
    for label, sets, excess in ERROR_CONDITIONS:
        s = scores([r for k in sets for r in per_set[k]])
        b, c = _both(label, s, "median_err_ge5_pct")
        ok = c <= b + excess
        lines.append(f"| {label} | {b:.2f} % | {c:.2f} % | <= {b + excess:.2f} % | {_v(ok)} |")
    (rb, wb), (rc, wc) = worst_ratio(rob_base), worst_ratio(rob_cand)
    lines.append(
        f"| (d) worst in-range robustness ratio | {rb:.2f}× ({wb}) | {rc:.2f}× ({wc}) "
        f"| <= {MAX_RATIO:g}× | {_v(rc <= MAX_RATIO)} |"
    )
    pooled = [r for k in NO_CONTACT_SETS for r in per_set[k]]
    for label, recs in (
        ("(e) no contact, references left out", without_references(pooled)),
        ("(e') no contact, references counted", pooled),
    ):
        s = scores(recs)
        b, c = _both(label, s, "no_contact_pct")
        n = s[BASE]["frames_no_contact"]
        ok = c >= b - NO_CONTACT_LOSS
        verdict = _v(ok) if recs is not pooled else "reported"
        lines.append(
            f"| {label}, {n} frames | {b:.1f} % | {c:.1f} % | >= {b - NO_CONTACT_LOSS:.1f} % "
            f"| {verdict} |"
        )
    return lines


def _v(ok: bool) -> str:
    return "PASS" if ok else "FAIL"


def main(argv: list[str] | None = None) -> int:
    """Print the conditions as one Markdown table."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("choose", type=Path, help="results.json of the choosing bench run")
    p.add_argument("rob_base", type=Path, help="results.json of v2.4's robustness run")
    p.add_argument("rob_candidate", type=Path, help="results.json of H15's robustness run")
    args = p.parse_args(argv)
    try:
        loaded = [
            json.loads(f.read_text(encoding="utf-8"))
            for f in (args.choose, args.rob_base, args.rob_candidate)
        ]
        rows = verdicts(loaded[0], loaded[1]["robustness"], loaded[2]["robustness"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"h15_rule: {e}; expected the chain's three bench results.json", file=sys.stderr)
        return 2
    print("| condition | v2.4 | H15 | bound | verdict |\n|---|---|---|---|---|")
    print("\n".join(rows))
    decisive = [r for r in rows if not r.endswith("| reported |")]
    print(
        f"\nH15 replaces v2.4: {'yes' if all(r.endswith('| PASS |') for r in decisive) else 'no'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""H15's rule (``docs/training.md``, "H15"), condition by condition, from the chain's bench runs.

Reads the choosing run (``out/h15_choose/results.json``: v2.4 as ``unet``, the candidate as
``unet[h15]``, the cross-check sets by label) and the two robustness runs (``out/h15_rob_v24``,
``out/h15_rob_h15``: each model as ``unet``), and prints (a)-(e) with both models' values, the
bound and PASS/FAIL; exit 0 whatever the verdict, 2 on unreadable input or runs other than the
chain's (:func:`check_runs`). Values are compared
unrounded. Condition (e) leaves out each session's reference frame (its lowest pressure): a
reference measured against itself is "no contact" for every model with the change gate, so it
would only dilute the pool (amended before H15 was trained; the count with them is printed too).

    .venv/bin/python docs/scripts/h15_rule.py out/h15_choose/results.json \
        out/h15_rob_v24/results.json out/h15_rob_h15/results.json
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rule_scores import datasets, scores

from contactcal.infer.files.digest import sha256_file

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
#: The runs the rule reads (:func:`check_runs`).
REFERENCE_MODE = "session zero-pressure frame"
BASE_MODEL, CANDIDATE_MODEL = "models/contact_unet.onnx", "runs/h15/v25.onnx"
ROBUSTNESS_FRAMES = 80


def without_references(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The records less each (method, session)'s reference: its first record at the lowest
    pressure, as the bench picks it (one frame, also where pressures tie)."""
    ref: dict[tuple[str, str], int] = {}
    for i, r in enumerate(records):
        key = (r["method"], r["session"])
        if key not in ref or r["pressure_kpa"] < records[ref[key]]["pressure_kpa"]:
            ref[key] = i
    drop = set(ref.values())
    return [r for i, r in enumerate(records) if i not in drop]


def worst_ratio(robustness: dict[str, Any]) -> tuple[float, str]:
    """``unet``'s largest in-range, non-baseline error ratio and where it is."""
    rows = [
        r for r in robustness["rows"] if r["method"] == BASE and r["in_range"] and not r["baseline"]
    ]
    if not rows:
        raise ValueError("no in-range robustness level")
    for r in rows:  # the worst over every in-range level: none may lack its ratio
        if r["error_ratio"] is None or not math.isfinite(r["error_ratio"]):
            raise ValueError(f"{r['perturbation']} {r['label']}: no error ratio")
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
        n = s[BASE]["frames_ge5"], s[CANDIDATE]["frames_ge5"]
        lines.append(
            f"| {label}, {n[0]}/{n[1]} frames | {b:.3f} % | {c:.3f} % | <= {b + excess:.3f} % "
            f"| {_v(ok)} |"
        )
    (rb, wb), (rc, wc) = worst_ratio(rob_base), worst_ratio(rob_cand)
    lines.append(
        f"| (d) worst in-range robustness ratio | {rb:.3f}× ({wb}) | {rc:.3f}× ({wc}) "
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


def check_runs(choose: dict[str, Any], rob_base: dict[str, Any], rob_cand: dict[str, Any]) -> None:
    """Refuse runs other than the chain's (each step is skipped when its output exists, so a
    stale or swapped file would otherwise be judged): the choosing run with the reference, on
    ``val_v6``; both robustness runs on ``val_v6``, the same 80 frames, v2.4's
    model and the candidate's, the same files (sha256) as the choosing run's.

    Raises:
        ValueError: naming the first mismatch.
    """
    want = (
        ("choosing run", choose["data"].endswith("val_v6"), "data on data/val_v6"),
        ("choosing run", choose["reference"] == REFERENCE_MODE, f"reference {REFERENCE_MODE!r}"),
        ("v2.4's robustness run", rob_base["model"].endswith(BASE_MODEL), f"model {BASE_MODEL}"),
        ("H15's robustness run", rob_cand["model"].endswith(CANDIDATE_MODEL), CANDIDATE_MODEL),
    )
    for name, ok, expected in want:
        if not ok:
            raise ValueError(f"{name}: expected {expected}")
    for name, run in (("v2.4's", rob_base), ("H15's", rob_cand)):
        n = len(run["robustness"]["frames"])
        if not run["data"].endswith("val_v6") or n != ROBUSTNESS_FRAMES:
            raise ValueError(
                f"{name} robustness run: expected {ROBUSTNESS_FRAMES} frames of data/val_v6, "
                f"got {n} of {run['data']}"
            )
    if rob_base["robustness"]["frames"] != rob_cand["robustness"]["frames"]:
        raise ValueError("the two robustness runs perturbed different frames")
    pairs = (
        ("v2.4", BASE, rob_base, BASE_MODEL),
        ("H15", CANDIDATE, rob_cand, CANDIDATE_MODEL),
    )
    for name, method, run, path in pairs:  # one file per model: the three runs' and today's
        if _sha(choose, method) != _sha(run, BASE):
            raise ValueError(f"{name}: the choosing and robustness runs measured other files")
        if Path(path).is_file() and _sha(run, BASE) != sha256_file(path):
            raise ValueError(f"{name}: the runs measured another file than today's {path}")


def _sha(run: dict[str, Any], method: str) -> str:
    """The sha256 of the file ``run`` measured as ``method`` (bench's ``models``)."""
    try:
        return str(run["models"][method]["sha256"])
    except KeyError:
        raise ValueError(
            f"no model file recorded for {method}; run the chain's bench again"
        ) from None


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
        check_runs(*loaded)
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

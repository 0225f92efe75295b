"""H15's rule (``docs/training.md``, "H15"; H16's too), condition by condition, from the chain's
bench runs (``docs/scripts/chain.sh``).

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

Another draw of the recipe names its run and validation sets (``--candidate h16 --val val_v7``:
``runs/h16/v25.onnx`` as ``unet[h16]``, the sets ``val_v7``, ``val_v7_depart``, ``val_v7_onset``).
``--rule h17`` applies H17's rule: H15's, with (b) allowing 0.5 points (``EXCESS``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rule_scores import datasets, scores

from contactcal.infer.files.digest import sha256_file

BASE = "unet"
#: The candidate's allowed excess over v2.4 in points, per condition (a)-(c), per rule: H17's
#: (b) allows the seed spread measured on ``val_depart`` (docs/training.md, "H17").
EXCESS = {
    "h15": {"a": 0.5, "b": 0.0, "c": 0.2},
    "h17": {"a": 0.5, "b": 0.5, "c": 0.2},
}
#: Its allowed loss in points of (e).
NO_CONTACT_LOSS = 1.0
#: (d): the largest error ratio at a randomised, non-baseline level.
MAX_RATIO = 2.0
#: The runs the rule reads (:func:`check_runs`).
REFERENCE_MODE = "session zero-pressure frame"
BASE_MODEL = "models/contact_unet.onnx"
ROBUSTNESS_FRAMES = 80


@dataclass(frozen=True)
class Draw:
    """One draw of the recipe: its run name (``h15``) and validation set (``val_v6``)."""

    name: str = "h15"
    val: str = "val_v6"
    rule: str = "h15"

    @property
    def method(self) -> str:
        """The candidate's method label in the choosing run."""
        return f"unet[{self.name}]"

    @property
    def model(self) -> str:
        """The candidate's restated model file."""
        return f"runs/{self.name}/v25.onnx"

    @property
    def title(self) -> str:
        """``H15``."""
        return self.name.upper()

    def error_conditions(self) -> tuple[tuple[str, tuple[str, ...], float], ...]:
        """(label, sets pooled, allowed excess in points) of (a)-(c)."""
        excess = EXCESS[self.rule]
        return (
            (
                "(a) procedural 7800+7900, median err >= 5 kPa",
                ("cc7800_hr", "cc7900_hr"),
                excess["a"],
            ),
            ("(b) val_depart, median err >= 5 kPa", ("val_depart",), excess["b"]),
            (f"(c) {self.val}, median err >= 5 kPa", ("main",), excess["c"]),
        )

    def no_contact_sets(self) -> tuple[str, ...]:
        """The sets of (e), pooled."""
        v = self.val
        return ("main", f"{v}_depart", f"{v}_onset", "val_depart", "val_r3", "v2_cal")


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


def _both(label: str, s: dict[str, dict[str, Any]], key: str, draw: Draw) -> tuple[float, float]:
    """v2.4's and the candidate's ``key`` in :func:`scores` output; ValueError naming the
    condition when a model or its value is missing (no frames of that kind)."""
    try:
        b, c = s[BASE][key], s[draw.method][key]
    except KeyError as e:
        raise ValueError(f"{label}: no records of {e}; expected {BASE} and {draw.method}") from None
    if b is None or c is None:
        raise ValueError(f"{label}: no frames to score ({key}: v2.4 {b}, {draw.title} {c})")
    return float(b), float(c)


def verdicts(
    choose: dict[str, Any], rob_base: dict[str, Any], rob_cand: dict[str, Any], draw: Draw
) -> list[str]:
    """One Markdown table row per condition.

    Raises:
        ValueError: a set the rule reads is missing, or a condition has no frames to score.
    """
    per_set = datasets(choose)
    needed = {k for _, sets, _ in draw.error_conditions() for k in sets}
    needed |= set(draw.no_contact_sets())
    if missing := sorted(needed - set(per_set)):
        raise ValueError(f"no dataset {missing} in the choosing run; it has {sorted(per_set)}")
    lines = []
    for label, sets, excess in draw.error_conditions():
        s = scores([r for k in sets for r in per_set[k]])
        b, c = _both(label, s, "median_err_ge5_pct", draw)
        ok = c <= b + excess
        n = s[BASE]["frames_ge5"], s[draw.method]["frames_ge5"]
        lines.append(
            f"| {label}, {n[0]}/{n[1]} frames | {b:.3f} % | {c:.3f} % | <= {b + excess:.3f} % "
            f"| {_v(ok)} |"
        )
    (rb, wb), (rc, wc) = worst_ratio(rob_base), worst_ratio(rob_cand)
    lines.append(
        f"| (d) worst in-range robustness ratio | {rb:.3f}× ({wb}) | {rc:.3f}× ({wc}) "
        f"| <= {MAX_RATIO:g}× | {_v(rc <= MAX_RATIO)} |"
    )
    pooled = [r for k in draw.no_contact_sets() for r in per_set[k]]
    for label, recs in (
        ("(e) no contact, references left out", without_references(pooled)),
        ("(e') no contact, references counted", pooled),
    ):
        s = scores(recs)
        b, c = _both(label, s, "no_contact_pct", draw)
        n = s[BASE]["frames_no_contact"]
        ok = c >= b - NO_CONTACT_LOSS
        verdict = _v(ok) if recs is not pooled else "reported"
        lines.append(
            f"| {label}, {n} frames | {b:.1f} % | {c:.1f} % | >= {b - NO_CONTACT_LOSS:.1f} % "
            f"| {verdict} |"
        )
    return lines


def check_runs(
    choose: dict[str, Any], rob_base: dict[str, Any], rob_cand: dict[str, Any], draw: Draw
) -> None:
    """Refuse runs other than the chain's (each step is skipped when its output exists, so a
    stale or swapped file would otherwise be judged): the choosing run with the reference, on
    the draw's validation set; both robustness runs on it, the same 80 frames, v2.4's
    model and the candidate's, the same files (sha256) as the choosing run's.

    Raises:
        ValueError: naming the first mismatch.
    """
    v, title = draw.val, draw.title
    want = (
        ("choosing run", choose["data"].endswith(v), f"data on data/{v}"),
        ("choosing run", choose["reference"] == REFERENCE_MODE, f"reference {REFERENCE_MODE!r}"),
        ("v2.4's robustness run", rob_base["model"].endswith(BASE_MODEL), f"model {BASE_MODEL}"),
        (f"{title}'s robustness run", rob_cand["model"].endswith(draw.model), draw.model),
    )
    for name, ok, expected in want:
        if not ok:
            raise ValueError(f"{name}: expected {expected}")
    for name, run in (("v2.4's", rob_base), (f"{title}'s", rob_cand)):
        n = len(run["robustness"]["frames"])
        if not run["data"].endswith(v) or n != ROBUSTNESS_FRAMES:
            raise ValueError(
                f"{name} robustness run: expected {ROBUSTNESS_FRAMES} frames of data/{v}, "
                f"got {n} of {run['data']}"
            )
    if rob_base["robustness"]["frames"] != rob_cand["robustness"]["frames"]:
        raise ValueError("the two robustness runs perturbed different frames")
    pairs = (
        ("v2.4", BASE, rob_base, BASE_MODEL),
        (title, draw.method, rob_cand, draw.model),
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
    p.add_argument(
        "rob_candidate", type=Path, help="results.json of the candidate's robustness run"
    )
    p.add_argument("--candidate", default="h15", help="the draw's run name (default h15)")
    p.add_argument("--val", default="val_v6", help="the draw's validation set (default val_v6)")
    p.add_argument(
        "--rule", choices=sorted(EXCESS), default="h15", help="the rule's margins (default h15)"
    )
    args = p.parse_args(argv)
    draw = Draw(args.candidate, args.val, args.rule)
    try:
        loaded = [
            json.loads(f.read_text(encoding="utf-8"))
            for f in (args.choose, args.rob_base, args.rob_candidate)
        ]
        check_runs(*loaded, draw)
        rows = verdicts(loaded[0], loaded[1]["robustness"], loaded[2]["robustness"], draw)
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"h15_rule: {e}; expected the chain's three bench results.json", file=sys.stderr)
        return 2
    print(f"| condition | v2.4 | {draw.title} | bound | verdict |\n|---|---|---|---|---|")
    print("\n".join(rows))
    decisive = [r for r in rows if not r.endswith("| reported |")]
    passed = all(r.endswith("| PASS |") for r in decisive)
    print(f"\n{draw.title} replaces v2.4: {'yes' if passed else 'no'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Pooled numbers of a ``contactcal bench`` ``results.json`` that its report does not print.

Per method: the median |relative area error| over the frames at or above 5 kPa with true contact,
pooled over the chosen datasets (the main one and/or its cross-check sets, by label), and the
no-contact accuracy over every frame without true contact and over those at ≤ 1 kPa (before the
session rule). The
selection rules in ``docs/training.md`` read these.

    .venv/bin/python docs/scripts/rule_scores.py out/h11_choose/results.json \
        --sets cc7800_hr cc7900_hr
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from contactcal.infer.bench.accuracy import from_record
from contactcal.infer.bench.crosscheck import POOLED_FROM_KPA
from contactcal.infer.bench.scoring import bin_row

#: The issue's cross-check no-contact target counts the frames at or below this pressure, kPa.
LOW_KPA = 1.0


def datasets(results: dict[str, Any]) -> dict[str, list[dict[str, Any]]]:
    """Records per dataset label (the main dataset is ``main``)."""
    out = {"main": results["records"]}
    for res in results.get("crosscheck", []):
        out[res["label"]] = res["records"]
    return out


def scores(records: list[dict[str, Any]]) -> dict[str, dict[str, float | int | None]]:
    """Per method: the bench's :func:`bin_row` of the contact frames at ≥ 5 kPa (error) and of
    every frame (no-contact accuracy); a share over no frames is None (printed "–")."""
    frames = [from_record(r) for r in records]
    out: dict[str, dict[str, float | int | None]] = {}
    for method in sorted({f.method for f in frames}):
        mine = [f for f in frames if f.method == method]
        high = bin_row([f for f in mine if f.true_contact and f.pressure_kpa >= POOLED_FROM_KPA])
        every = bin_row(mine)
        low = bin_row([f for f in mine if f.pressure_kpa <= LOW_KPA])
        out[method] = {
            "median_err_ge5_pct": _pct(high["median_abs_rel_error"]),
            "frames_ge5": high["contact_frames"],
            "no_contact_pct": _pct(every["no_contact_accuracy"]),
            "frames_no_contact": every["no_contact_frames"],
            "no_contact_low_pct": _pct(low["no_contact_accuracy"]),
            "frames_no_contact_low": low["no_contact_frames"],
        }
    return out


def _pct(share: float | int | None) -> float | None:
    """A share in %, None kept."""
    return None if share is None else 100 * float(share)


def main(argv: list[str] | None = None) -> int:
    """Print the pooled scores as one Markdown table."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("results", type=Path, help="results.json of contactcal bench")
    p.add_argument("--sets", nargs="+", default=["main"], help="dataset labels to pool")
    args = p.parse_args(argv)
    try:
        per_set = datasets(json.loads(args.results.read_text(encoding="utf-8")))
    except (OSError, ValueError, KeyError) as e:
        print(f"{args.results}: expected a contactcal bench results.json ({e})", file=sys.stderr)
        return 2
    missing = [s for s in args.sets if s not in per_set]
    if missing:
        print(f"{args.results}: no dataset {missing}; it has {sorted(per_set)}", file=sys.stderr)
        return 2
    pooled = [r for s in args.sets for r in per_set[s]]
    print(f"pooled over {', '.join(args.sets)}\n")
    print(
        "| method | median err ≥ 5 kPa | frames | no-contact acc. | frames "
        f"| no-contact acc. ≤ {LOW_KPA:g} kPa | frames |"
    )
    print("|---|---|---|---|---|---|---|")
    for method, s in scores(pooled).items():
        err, acc, low = s["median_err_ge5_pct"], s["no_contact_pct"], s["no_contact_low_pct"]
        print(
            f"| {method} | {'–' if err is None else f'{err:.2f} %'} | {s['frames_ge5']} "
            f"| {'–' if acc is None else f'{acc:.1f} %'} | {s['frames_no_contact']} "
            f"| {'–' if low is None else f'{low:.1f} %'} | {s['frames_no_contact_low']} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())

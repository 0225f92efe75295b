"""The reading of "v2.4's robustness at 1296 px on 12 new fingers" (``docs/training.md``).

Reads one ``contactcal bench --robustness --robustness-frames 120`` run of a model (the shipped
one, or H18-ab's A) on ``data/rob_hr12`` (``docs/scripts/rob_hr12.sh``), refuses a run of other
frames or another set, and prints: for each method, the median |area error| at ≥ 5 kPa and 3-5 kPa
and the no-contact share (each session's reference frame left out); the U-Net's in-range rows at or
above :data:`SHOWN` and its blur rows (H18-ab's pointer), with their 90 % intervals; its worst
in-range ratio; the reading written before the run ("met with margin", "met on this draw" or
"missed on this draw"). Exit 0 whatever the reading, 2 on unreadable input.

    .venv/bin/python docs/scripts/rob_hr12_report.py out/rob_hr12/results.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from h15_rule import BASE, without_references, worst_ratio

from contactcal.infer.bench.accuracy import from_record
from contactcal.infer.bench.scoring import bin_row

FRAMES = 120
DATA = "rob_hr12"
#: The target's bound on an in-range error ratio.
BOUND = 2.0
#: In-range rows at or above this ratio are printed.
SHOWN = 1.5


def _pct(x: float | int | None) -> str:
    return "–" if x is None else f"{100 * float(x):.2f} %"


def errors(run: dict[str, Any], method: str) -> str:
    """One line: ``method``'s ≥ 5 kPa and 3-5 kPa errors and no-contact share."""
    frames = [from_record(r) for r in without_references(run["records"])]
    frames = [f for f in frames if f.method == method]
    hi = bin_row([f for f in frames if f.true_contact and f.pressure_kpa >= 5])
    mid = bin_row([f for f in frames if f.true_contact and 3 <= f.pressure_kpa < 5])
    every = bin_row(frames)
    return (
        f"{method}: >=5 kPa {_pct(hi['median_abs_rel_error'])} ({hi['contact_frames']} frames), "
        f"3-5 kPa {_pct(mid['median_abs_rel_error'])} ({mid['contact_frames']}), no contact "
        f"{_pct(every['no_contact_accuracy'])} ({every['no_contact_frames']})"
    )


def reading(rob: dict[str, Any]) -> str:
    """The reading written before the run, from the U-Net's worst in-range row."""
    w, where = worst_ratio(rob)
    row = max(
        (r for r in rob["rows"] if r["method"] == BASE and r["in_range"] and not r["baseline"]),
        key=lambda r: r["error_ratio"],
    )
    iv = row["error_ratio_interval"]
    upper = "–" if iv is None else f"{iv[1]:.2f}"
    if w > BOUND:
        verdict = "missed on this draw"
    elif iv is not None and iv[1] <= BOUND:
        verdict = "met with margin"
    else:
        verdict = "met on this draw"
    return f"worst in-range ratio {w:.2f}× ({where}), interval upper {upper}: {verdict}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path)
    args = ap.parse_args(argv)
    try:
        run = json.loads(args.run.read_text(encoding="utf-8"))
        rob = run["robustness"]
        n = len(rob["frames"])
        if not str(run["data"]).rstrip("/").endswith(DATA) or n != FRAMES:
            raise ValueError(f"expected {FRAMES} frames of data/{DATA}, got {n} of {run['data']}")
        for method in (BASE, "classical"):
            print(errors(run, method))
        for r in rob["rows"]:
            shown = r["method"] == BASE and r["in_range"] and not r["baseline"]
            if shown and ((r["error_ratio"] or 0) >= SHOWN or r["perturbation"] == "blur"):
                iv = r["error_ratio_interval"]
                span = "" if iv is None else f" ({iv[0]:.2f}-{iv[1]:.2f})"
                err = _pct(r["median_abs_rel_error_ge5"])
                print(f"   {r['perturbation']} {r['label']}: {r['error_ratio']:.2f}×{span}, {err}")
        print(reading(rob))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f"rob_hr12_report: {args.run}: {exc!r}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

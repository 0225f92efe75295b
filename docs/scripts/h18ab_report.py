"""H18-ab's reading (``docs/training.md``, "H18-ab"), from its two robustness runs.

Reads ``out/h18ab_rob_A/results.json`` and ``out/h18ab_rob_B/results.json`` (``contactcal bench
--robustness --robustness-frames 120`` of each model on ``data/h18ab_test``; each model as
``unet``), refuses runs of other frames or sets, and prints, per model: the median |area error|
at ≥ 5 kPa and at 3-5 kPa (contact frames, each session's reference frame left out), the
no-contact share (frames without true contact, references left out), the whole blur row with each
ratio's 90 % interval, the worst in-range ratio; then the rule's reading: "a larger blur share
helps" only if the upper end of B's blur σ 12 interval is below A's σ 12 ratio and B's ≥ 5 kPa
error is at most A's + 0.2 points. Exit 0 whatever the reading, 2 on unreadable input.

    .venv/bin/python docs/scripts/h18ab_report.py out/h18ab_rob_A/results.json \
        out/h18ab_rob_B/results.json

The follow-up on 1296-px frames (``docs/scripts/h18ab_hires.sh``): ``out/h18ab_hr_A``,
``out/h18ab_hr_B``, ``--frames 40 --data h18ab_test_hr``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from h15_rule import without_references, worst_ratio

from contactcal.infer.bench.accuracy import from_record
from contactcal.infer.bench.scoring import bin_row

FRAMES = 120
DATA = "h18ab_test"
#: B's allowed excess over A's ≥ 5 kPa error, points.
EXCESS = 0.2
#: The judged perturbation and level (σ, px at 2592 wide).
JUDGED = "blur", 12.0


def _pct(x: float | int | None) -> str:
    return "–" if x is None else f"{100 * float(x):.2f} %"


def errors(run: dict[str, Any]) -> dict[str, float | int | None]:
    """≥ 5 kPa and 3-5 kPa median |error|, no-contact share (references left out)."""
    frames = [from_record(r) for r in without_references(run["records"])]
    frames = [f for f in frames if f.method == "unet"]
    hi = bin_row([f for f in frames if f.true_contact and f.pressure_kpa >= 5])
    mid = bin_row([f for f in frames if f.true_contact and 3 <= f.pressure_kpa < 5])
    every = bin_row(frames)
    return {
        "ge5": hi["median_abs_rel_error"],
        "n_ge5": hi["contact_frames"],
        "3to5": mid["median_abs_rel_error"],
        "n_3to5": mid["contact_frames"],
        "no_contact": every["no_contact_accuracy"],
        "n_no_contact": every["no_contact_frames"],
    }


def blur_rows(run: dict[str, Any]) -> list[dict[str, Any]]:
    """The U-Net's rows of the blur perturbation, in level order."""
    return [
        r
        for r in run["robustness"]["rows"]
        if r["method"] == "unet" and r["perturbation"] == JUDGED[0]
    ]


def check(a: dict[str, Any], b: dict[str, Any], frames: int = FRAMES, data: str = DATA) -> None:
    """Refuse runs other than the script's: both on ``data/DATA``, the same ``frames`` frames."""
    for name, run in (("A", a), ("B", b)):
        n = len(run["robustness"]["frames"])
        if not str(run["data"]).rstrip("/").endswith(data) or n != frames:
            got = f"got {n} of {run['data']}"
            raise ValueError(f"{name}: expected {frames} frames of data/{data}, {got}")
    if a["robustness"]["frames"] != b["robustness"]["frames"]:
        raise ValueError("the two robustness runs perturbed different frames")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run_a", type=Path)
    ap.add_argument("run_b", type=Path)
    ap.add_argument("--frames", type=int, default=FRAMES, help=f"frames sampled (default {FRAMES})")
    ap.add_argument("--data", default=DATA, help=f"held-out set's folder name (default {DATA})")
    args = ap.parse_args(argv)
    try:
        a, b = (json.loads(p.read_text(encoding="utf-8")) for p in (args.run_a, args.run_b))
        check(a, b, args.frames, args.data)
        judged = {}
        for name, run in (("A", a), ("B", b)):
            e = errors(run)
            print(
                f"{name}: >=5 kPa {_pct(e['ge5'])} ({e['n_ge5']} frames), "
                f"3-5 kPa {_pct(e['3to5'])} ({e['n_3to5']}), "
                f"no contact {_pct(e['no_contact'])} ({e['n_no_contact']})"
            )
            for r in blur_rows(run):
                iv = r["error_ratio_interval"]
                ratio = "–" if r["error_ratio"] is None else f"{r['error_ratio']:.2f}×"
                span = "" if iv is None else f" ({iv[0]:.2f}-{iv[1]:.2f})"
                print(
                    f"   blur {r['label']}: err {_pct(r['median_abs_rel_error_ge5'])} {ratio}{span}"
                )
            w, where = worst_ratio(run["robustness"])
            print(f"   worst in-range ratio {w:.2f}× ({where})")
            row = next(r for r in blur_rows(run) if r["level"] == JUDGED[1])
            judged[name] = (row, e["ge5"])
    except (OSError, ValueError, KeyError, StopIteration) as exc:
        print(f"h18ab_report: {exc!r}", file=sys.stderr)
        return 2
    (ra, ea), (rb, eb) = judged["A"], judged["B"]
    lower = rb["error_ratio_interval"][1] < ra["error_ratio"]
    kept = 100 * eb <= 100 * ea + EXCESS
    print(
        f"rule: B's σ 12 interval upper {rb['error_ratio_interval'][1]:.2f} < A's "
        f"{ra['error_ratio']:.2f}: {lower}; B's >=5 kPa {100 * eb:.2f} <= A's {100 * ea:.2f} "
        f"+ {EXCESS}: {kept}"
    )
    print(f"a larger blur share helps: {'yes' if lower and kept else 'not shown'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

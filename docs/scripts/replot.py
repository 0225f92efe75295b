"""Draw a ``contactcal bench`` report's figures again from its ``results.json``, no re-run.

For figures whose drawing code changed after the bench run (e.g. coinciding curves now drawn in
distinct line styles): the error-vs-pressure figure from the scored frames (``records``), the
robustness figures from ``robustness``; the numbers are those of the run. ``pareto.png`` is left
as it is. Each figure is written atomically into ``OUT_DIR`` (e.g. the report's folder under
``docs/bench/``):

    .venv/bin/python docs/scripts/replot.py out/v24_final/results.json docs/bench
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from contactcal.infer.bench.plots import plot_error_vs_pressure, plot_robustness
from contactcal.infer.bench.scoring import ScoredFrame


def frames_of(records: list[dict]) -> list[ScoredFrame]:
    """The scored frames of ``results.json``'s ``records`` (derived keys dropped)."""
    names = {f.name for f in dataclasses.fields(ScoredFrame)}
    frames = []
    for rec in records:
        kw = {k: v for k, v in rec.items() if k in names}
        if kw.get("area_interval_px") is not None:
            kw["area_interval_px"] = tuple(kw["area_interval_px"])
        frames.append(ScoredFrame(**kw))
    return frames


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a bench run's results.json")
    ap.add_argument("out_dir", type=Path, help="folder of the figures (existing)")
    args = ap.parse_args()
    results = json.loads(args.results.read_text())
    plot_error_vs_pressure(args.out_dir / "error_vs_pressure.png", frames_of(results["records"]))
    written = ["error_vs_pressure.png"]
    if "robustness" in results:
        plot_robustness(args.out_dir / "robustness.png", results["robustness"])
        rob_nc = args.out_dir / "robustness_no_contact.png"
        plot_robustness(rob_nc, results["robustness"], "no_contact")
        written += ["robustness.png", "robustness_no_contact.png"]
    print(f"{args.out_dir}: {', '.join(written)}")


if __name__ == "__main__":
    main()

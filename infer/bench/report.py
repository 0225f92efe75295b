"""``results.json``, figures and ``report.md`` of ``contactcal bench`` (their tables:
:mod:`~contactcal.infer.bench.tables`)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.bench.config import SESSION_REFERENCE
from contactcal.infer.bench.markdown import Columns, md_table
from contactcal.infer.bench.onset import ONSET_COLUMNS, ONSET_NOTE, onset_shown
from contactcal.infer.bench.plots import plot_error_vs_pressure, plot_pareto, plot_robustness
from contactcal.infer.bench.robustness_text import robustness_text
from contactcal.infer.bench.scoring import ScoredFrame, not_references
from contactcal.infer.bench.tables import accuracy_tables
from contactcal.infer.bench.timing import TIMED_KPA
from contactcal.infer.files.atomic import OutputSet, run_outputs, write_json, write_text

BIN_COLUMNS: Columns = (
    ("method", "method", False),
    ("bin_kpa", "kPa", False),
    ("frames", "frames", False),
    ("contact_frames", "contact frames", False),  # the errors and the IoU are over these
    ("median_abs_rel_error", "median abs. rel. error", True),
    ("mean_rel_error", "mean rel err", True),
    ("sd_rel_error", "sd", True),
    ("median_abs_error_mm2", "median abs. error mm²", False),
    ("median_iou", "median IoU", False),
    ("contact_recall", "contact recall", True),
    ("no_contact_accuracy", "no-contact acc.", True),
)
TIMING_COLUMNS: Columns = (
    ("config", "configuration", False),
    ("threads", "threads", False),
    ("ms_compute", "ms/frame (decoded)", False),
    ("ms_end_to_end_jpg", "ms/frame incl. JPEG decode", False),
    ("ms_end_to_end_png", "ms/frame incl. PNG decode", False),
)
COVERAGE_COLUMNS: Columns = (
    ("method", "method", False),
    ("bin_kpa", "kPa", False),
    ("frames", "frames", False),
    ("coverage", "coverage", True),
    ("contact_frames", "contact frames", False),
    ("contact_coverage", "coverage (contact)", True),
    ("median_rel_width", "median rel. width", True),
)
HARD_COLUMNS: Columns = (
    ("method", "method", False),
    ("sessions", "sessions", False),
    ("n", "n", False),
    ("median_abs_rel_error_ge5", "median abs. rel. error ≥5 kPa", True),
    ("median_abs_rel_error_3to5", "median abs. rel. error 3-5 kPa", True),
    ("no_contact_accuracy", "no-contact acc.", True),
    ("median_abs_onset_error_kpa", "median abs. onset error kPa", False),
    ("onset_missing", "missed onset", False),
    ("false_onsets", "false onset", False),
)


def _digests(results: Mapping[str, Any]) -> str:
    """`` (unet sha256 974304c4…, unet[x] …)``: the measured files, from ``models`` (absent
    in results written before it was recorded)."""
    models = results.get("models") or {}
    if not models:
        return ""
    return " (" + ", ".join(f"{k} sha256 {v['sha256'][:12]}…" for k, v in models.items()) + ")"


def _timed_frames(results: Mapping[str, Any]) -> str:
    """How many frames the end-to-end timings ran on (fewer than asked on a small set)."""
    n = {int(r["frames"]) for r in results["timing"] if r["config"] != "unet network only"}
    asked = int(results["config"]["timing_frames"])
    got = max(n, default=0)
    lo, hi = TIMED_KPA
    if got == asked:
        return f"{got}"
    return f"{got} (of {asked} asked: all the set has at {lo:g}-{hi:g} kPa, or at all pressures)"


#: Fewer contact frames than this in a bin: its median is said to be indicative only.
FEW_FRAMES = 5


def _few_frames_note(bins: Sequence[Mapping[str, Any]]) -> str:
    """A sentence naming the bins whose errors are medians of 1 to ``FEW_FRAMES - 1`` frames."""
    few = [
        f"{b['method']} {b['bin_kpa']} kPa ({b['contact_frames']})"
        for b in bins
        if 0 < b["contact_frames"] < FEW_FRAMES
    ]
    if not few:
        return ""
    return (
        f" Errors over fewer than {FEW_FRAMES} contact frames are indicative only: "
        + ", ".join(few)
        + "."
    )


def _no_reference_modes(results: Mapping[str, Any]) -> str:
    """Without reference frames: a paragraph saying what each method did instead
    (``no_reference``; "" with them, or in results written before it was recorded)."""
    modes = results.get("no_reference") or {}
    if not modes:
        return ""
    lines = "\n".join(f"- {method}: {note}." for method, note in modes.items())
    return f"\n\nWithout reference frames, per method:\n\n{lines}"


def _reference_note(results: Mapping[str, Any]) -> str:
    """With reference frames: the sentence saying they are not scored ("" without)."""
    if results["reference"] != SESSION_REFERENCE:
        return ""
    return (
        "\nEach session's reference frame is not scored (it is measured against itself): the "
        "error, coverage and\nhard-case tables, the figures and the robustness sample leave it "
        "out; the onset reads whole\nsessions. Its records in `results.json` say "
        '`"reference": true`.'
    )


def report_text(results: Mapping[str, Any]) -> str:
    """``report.md`` from the results (with their ``bins``, ``hard``, ``coverage`` and
    ``onset_table`` tables)."""
    cfg = results["config"]
    w, h = cfg["full_size"]
    sections = [
        "# contactcal benchmark\n\n"
        f"Data: `{results['data']}` — {results['sessions']} sessions, {results['frames']} frames.\n"
        f"Model: `{results['model']}`{_digests(results)}. Reference frame: "
        f"{results['reference']}.{_reference_note(results)} Areas are compared in input pixels "
        "with the exact masks; relative\nerrors and the IoU of the method's outline with the "
        "mask over frames with true contact. Timing: median of "
        f"{cfg['repeats']} runs over\n{_timed_frames(results)} frames upscaled to {w}×{h}, "
        "in one process; each median leaves out\none untimed warm-up run of its "
        "configuration. Rows `(soft area)`: the same prediction measured by its\nprobability "
        "mass; rows `(session rule)`: the same frames after `calibrate`'s session rule (a region "
        "that\nshrinks at the next pressure beyond both stated intervals, and a contact left "
        "below the\ncontact range, count as no contact), i.e. what a calibration reports."
        + _no_reference_modes(results),
        "## Area error per pressure bin\n\n"
        "Bins are `[lo, hi)` kPa (a frame at 3 kPa is in 3-5; the last bin holds 20 kPa)."
        + _few_frames_note(results["bins"])
        + "\n\n"
        + md_table(results["bins"], BIN_COLUMNS)
        + "\n\n![error vs pressure](error_vs_pressure.png)",
        "## Speed\n\n"
        + md_table(results["timing"], TIMING_COLUMNS)
        + "\n\n![speed vs error](pareto.png)",
        "## Coverage of the stated area interval\n\n"
        "Share of frames whose stated interval (`area_interval_px`) contains the true area; "
        "width\nover the true area, frames with true contact.\n\n"
        + md_table(results["coverage"], COVERAGE_COLUMNS),
        "## Contact onset (estimated from each method's frames vs the mechanics' onset)\n\n"
        + f"{ONSET_NOTE}\n\n"
        + md_table(onset_shown(results["onset_table"]), ONSET_COLUMNS),
        "## Hard cases\n\n" + md_table(results["hard"], HARD_COLUMNS),
    ]
    if "robustness" in results:
        sections.append(robustness_text(results["robustness"]))
    return "\n\n".join(sections) + "\n"


#: The figures of the robustness suite (written only by a run with ``--robustness``).
ROBUSTNESS_FILES = ("robustness.png", "robustness_no_contact.png")
#: The files ``write_report`` may write into the report folder (checked before a bench runs).
REPORT_FILES = (
    "results.json",
    "error_vs_pressure.png",
    "pareto.png",
    *ROBUSTNESS_FILES,
    "report.md",
)


def write_report(
    out_dir: str | os.PathLike[str],
    results: dict[str, Any],
    frames: Sequence[ScoredFrame],
    bins: Sequence[tuple[float, float]],
    extra_text: str = "",
    outputs: OutputSet | None = None,
) -> None:
    """Add the tables of :func:`accuracy_tables` to ``results``; write ``results.json``,
    the figures (``error_vs_pressure.png``, ``pareto.png``, with ``robustness`` results also
    ``robustness.png`` and ``robustness_no_contact.png``) and ``report.md`` into ``out_dir``,
    all or nothing (:data:`REPORT_FILES`).

    Args:
        out_dir: report folder (created if missing).
        results: raw results of :func:`~contactcal.infer.bench.run.run_bench` (``records`` are
            the ``frames`` as JSON, plus ``onset``, ``timing``, ``config`` and the header keys).
        frames: the scored frames.
        bins: pressure bins, kPa, ``[lo, hi)``.
        extra_text: Markdown sections appended to ``report.md`` (the cross-check datasets).
        outputs: the enclosing run's outputs to stage into (None: this call is the run).
    """
    out = Path(out_dir)
    results.update(accuracy_tables(frames, results["onset"], bins))
    size = tuple(results["config"]["full_size"])
    text = report_text(results)
    with run_outputs(join=outputs) as outs:  # every file of the report, or none
        write_json(outs.stage(out / "results.json"), results)
        plot_error_vs_pressure(outs.stage(out / "error_vs_pressure.png"), not_references(frames))
        pareto = outs.stage(out / "pareto.png")
        plot_pareto(pareto, results["bins"], results["timing"], (size[0], size[1]))
        if "robustness" in results:
            rob = results["robustness"]
            figure, no_contact = ROBUSTNESS_FILES
            plot_robustness(outs.stage(out / figure), rob)
            plot_robustness(outs.stage(out / no_contact), rob, "no_contact")
        md = text + ("\n" + extra_text if extra_text else "")
        write_text(outs.stage(out / "report.md"), md)

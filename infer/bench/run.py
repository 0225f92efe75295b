"""``contactcal bench``: accuracy and speed of every method on held-out rendered sessions.

Accuracy (:mod:`~contactcal.infer.bench.accuracy`) is measured on the dataset's frames at their
native size against the exact masks; speed (:mod:`~contactcal.infer.bench.timing`) end to end on
the same frames upscaled to the rig's 2592×1944; optionally, robustness to perturbed frames
(:mod:`~contactcal.infer.bench.robustness`). The report (:mod:`~contactcal.infer.bench.report`)
has the tables, ``results.json`` and the figures.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.bench.accuracy import (
    evaluate,
    no_reference_modes,
    to_record,
)
from contactcal.infer.bench.config import SESSION_REFERENCE, BenchConfig
from contactcal.infer.bench.crosscheck import (
    crosscheck_text,
    labels,
    read_sessions,
    score_dataset,
    side_by_side,
)
from contactcal.infer.bench.dataset import IndexRow, check_distinct, read_index, sessions_of
from contactcal.infer.bench.models import BenchModel, load_models
from contactcal.infer.bench.onset import onset_errors
from contactcal.infer.bench.preflight import check_datasets
from contactcal.infer.bench.report import write_report
from contactcal.infer.bench.robustness import run_robustness
from contactcal.infer.bench.scoring import ScoredFrame
from contactcal.infer.bench.timing import timing
from contactcal.infer.files.atomic import OutputSet


def run_bench(
    data: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    model: str | os.PathLike[str] | None = None,
    config: BenchConfig | None = None,
    crosscheck: Sequence[str | os.PathLike[str]] = (),
    outputs: OutputSet | None = None,
    models: Sequence[BenchModel] | None = None,
) -> dict[str, Any]:
    """Run the accuracy and speed benchmarks; write ``report.md``, ``results.json`` and plots.

    Args:
        data: dataset folder written by ``contactcal synth`` (``index.csv``).
        out_dir: report folder (created if missing).
        model: ONNX model (None → the shipped one).
        config: what to measure (default :class:`BenchConfig`).
        crosscheck: further dataset folders scored the same way (no timing), reported beside
            ``data`` (:mod:`~contactcal.infer.bench.crosscheck`).
        outputs: the enclosing run's outputs to stage the report into (None: this call is the
            run).
        models: ``model`` and ``config.variants`` as
            :func:`~contactcal.infer.bench.models.load_models` read them (the CLI reads them
            among its checks); None reads them here, before any work. Every U-Net scored or
            timed, and ``models``' sha256, is of that one read of each file.

    Returns:
        The content of ``results.json``: header keys (with ``use_reference=False`` also
        ``no_reference``: what each method does without one), ``config``, ``records`` (one per
        method and frame, with the stated ``area_interval_px`` and ``covered``), ``onset``,
        ``timing``, ``bins``, ``hard`` and ``coverage`` (per method and pressure bin),
        ``onset_table`` (per method: sessions covered, onsets found, missed, false onsets); with
        ``crosscheck``
        also ``crosscheck`` (one results object per dataset, with its ``label``) and
        ``side_by_side`` (per method and bin, every dataset's error, recall and no-contact
        accuracy); with ``config.robustness_frames`` also ``robustness``
        (:func:`~contactcal.infer.bench.robustness.run_robustness`).

    Raises:
        ValueError: a missing or unusable model file (its option named), an unusable dataset
            folder (the message names the file), or a cross-check folder that is ``data`` or
            another cross-check folder, or a session without a 0 kPa
            reference frame, or a frame or mask file that is not a readable image, a mask of
            another size than its frame, or a frame of another size than its reference
            (:func:`~contactcal.infer.bench.preflight.check_datasets`).
    """
    config = config or BenchConfig()
    models = load_models(model, config.variants) if models is None else models
    names = [f"--data {data}", *(f"--crosscheck {c}" for c in crosscheck)]
    check_distinct([data, *crosscheck], names)  # a copy would be scored as "<name>#2"
    sessions = sessions_of(read_index(data))
    others = [read_sessions(c) for c in crosscheck]
    check_datasets(sessions, others, config)  # every folder checked before any work
    frames = evaluate(sessions, models, config.use_reference)
    onset = onset_errors(frames)
    results: dict[str, Any] = {
        "data": str(Path(data).resolve()),
        "model": "shipped" if model is None else os.fspath(model),
        "reference": SESSION_REFERENCE if config.use_reference else "none",
        "models": model_digests(models),
        "sessions": len(sessions),
        "frames": sum(len(v) for v in sessions.values()),
        "config": {
            "repeats": config.repeats,
            "timing_frames": config.timing_frames,
            "full_size": list(config.full_size),
        },
        "records": [to_record(f) for f in frames],
        "onset": onset,
        "timing": timing(sessions, models, config),
    }
    if not config.use_reference:  # which mode ran (a U-Net's blank placeholder or the frame)
        results["no_reference"] = no_reference_modes(models)
    if config.robustness_frames:
        results["robustness"] = run_robustness(
            sessions,
            models[0],
            config.robustness_frames,
            config.seed,
            [m.name for m in models[1:]],
        )
    extra = ""
    if crosscheck:
        extra = _crosscheck(results, data, frames, crosscheck, others, models, config)
    write_report(out_dir, results, frames, config.bins, extra, outputs)
    return results


def model_digests(models: Sequence[BenchModel]) -> dict[str, dict[str, str]]:
    """Which files were measured: ``{"unet" | "unet[label]": {"path", "sha256"}}``, the
    method names of the records (the shipped model's path is the installed file's), each
    sha256 of the content read once and scored."""
    return {m.name: {"path": os.fspath(m.path), "sha256": m.sha256} for m in models}


def _crosscheck(
    results: dict[str, Any],
    data: str | os.PathLike[str],
    frames: list[ScoredFrame],
    folders: Sequence[str | os.PathLike[str]],
    sessions: list[dict[str, list[IndexRow]]],
    models: Sequence[BenchModel],
    config: BenchConfig,
) -> str:
    """Score each cross-check set; add ``crosscheck`` and ``side_by_side`` to ``results``.

    Returns:
        The report's cross-check section (Markdown).
    """
    names = labels([data, *folders])
    scored = {names[0]: frames}
    results["crosscheck"] = []
    for name, folder, sess in zip(names[1:], folders, sessions, strict=True):
        res, scored[name] = score_dataset(
            name, folder, sess, models, config.bins, config.use_reference
        )
        results["crosscheck"].append(res)
    results["side_by_side"] = side_by_side(scored, config.bins)
    return crosscheck_text(results, names[0])

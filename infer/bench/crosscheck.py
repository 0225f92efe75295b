"""Every method on further datasets, beside the main one (``contactcal bench --crosscheck``).

A cross-check dataset (e.g. one drawn by ``contactcal procedural``, a generator independent of
the renderer) is scored exactly like the main one; the report puts the error per pressure bin of
every dataset side by side, so over-fitting to one renderer shows as a gap between columns.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.bench.accuracy import evaluate, to_record
from contactcal.infer.bench.dataset import IndexRow, read_index, sessions_of
from contactcal.infer.bench.markdown import md_table
from contactcal.infer.bench.models import BenchModel
from contactcal.infer.bench.onset import ONSET_COLUMNS, onset_errors, onset_shown
from contactcal.infer.bench.report import BIN_COLUMNS, HARD_COLUMNS
from contactcal.infer.bench.scoring import (
    ScoredFrame,
    bin_label,
    bin_row,
    covering_bins,
    not_references,
)
from contactcal.infer.bench.tables import accuracy_tables

#: Bin of the side-by-side table that pools every frame at or above 5 kPa, kPa.
POOLED_FROM_KPA = 5.0
#: Side-by-side quantities per dataset: (key, header, shown as %).
SIDE_KEYS = (
    ("median_abs_rel_error", "median abs. rel. error", True),
    ("contact_recall", "contact recall", True),
    ("no_contact_accuracy", "no-contact acc.", True),
)


def labels(folders: Sequence[str | os.PathLike[str]]) -> list[str]:
    """Short, distinct names of dataset folders: the folder name, or ``<name>#2``, ``#3``… the
    first not taken (a folder named ``set#2`` keeps its name; a later ``set`` is not it)."""
    out: list[str] = []
    for f in folders:
        name = Path(f).resolve().name or str(f)
        label, n = name, 1
        while label in out:  # distinct, so no dataset's columns overwrite another's
            n += 1
            label = f"{name}#{n}"
        out.append(label)
    return out


def read_sessions(folder: str | os.PathLike[str]) -> dict[str, list[IndexRow]]:
    """A dataset's sessions (see :func:`~contactcal.infer.bench.dataset.read_index`)."""
    return sessions_of(read_index(folder))


def score_dataset(
    label: str,
    folder: str | os.PathLike[str],
    sessions: Mapping[str, Sequence[IndexRow]],
    models: Sequence[BenchModel],
    bins: Sequence[tuple[float, float]],
    use_reference: bool = True,
) -> tuple[dict[str, Any], list[ScoredFrame]]:
    """Score every method on one cross-check dataset (with or without reference frames), the
    U-Nets built from ``models`` as read once (:func:`~contactcal.infer.bench.models.load_models`).

    Returns:
        Its results (``label``, ``data``, ``sessions``, ``frames``, ``records``, ``onset``,
        ``bins``, ``hard``, ``coverage``, ``onset_table``: the keys of the main dataset's
        results, less timing)
        and the scored frames.
    """
    frames = evaluate(sessions, models, use_reference)
    onset = onset_errors(frames)
    results = {
        "label": label,
        "data": str(Path(folder).resolve()),
        "sessions": len(sessions),
        "frames": sum(len(v) for v in sessions.values()),
        "records": [to_record(f) for f in frames],
        "onset": onset,
        **accuracy_tables(frames, onset, bins),
    }
    return results, frames


def side_by_side(
    scored: Mapping[str, Sequence[ScoredFrame]], bins: Sequence[tuple[float, float]]
) -> list[dict[str, Any]]:
    """Per method and pressure bin (plus ``≥5`` pooled): :data:`SIDE_KEYS` of every dataset.

    Args:
        scored: dataset label → its scored frames (in report order); the sessions' reference
            frames are left out (:func:`~contactcal.infer.bench.scoring.not_references`).
        bins: pressure bins, kPa, ``[lo, hi)``.

    Returns:
        Rows with ``method``, ``bin_kpa`` and ``"<key>@<label>"`` per dataset (None where a
        quantity has no frames).
    """
    scored = {label: not_references(fs) for label, fs in scored.items()}
    methods = sorted({f.method for fs in scored.values() for f in fs})
    bins = covering_bins([f.pressure_kpa for fs in scored.values() for f in fs], bins)
    ranges = [(bin_label(lo, hi), lo, hi) for lo, hi in bins]
    ranges.append((f"≥{POOLED_FROM_KPA:g}", POOLED_FROM_KPA, float("inf")))
    rows = []
    for method in methods:
        for name, lo, hi in ranges:
            row: dict[str, Any] = {"method": method, "bin_kpa": name}
            for label, frames in scored.items():
                sel = [f for f in frames if f.method == method and lo <= f.pressure_kpa < hi]
                stats = bin_row(sel)
                row.update({f"{key}@{label}": stats[key] for key, _, _ in SIDE_KEYS})
            rows.append(row)
    return rows


def crosscheck_text(results: Mapping[str, Any], main_label: str) -> str:
    """The report sections: the side-by-side table, then each cross-check dataset's tables.

    Args:
        results: the bench results with ``crosscheck`` and ``side_by_side``.
        main_label: the main dataset's label.
    """
    names = [main_label] + [c["label"] for c in results["crosscheck"]]
    head = [("method", "method", False), ("bin_kpa", "kPa", False)]
    tables = [
        f"### {h}\n\n"
        + md_table(results["side_by_side"], [*head, *((f"{k}@{n}", n, pct) for n in names)])
        for k, h, pct in SIDE_KEYS
    ]  # one table per quantity, one column per dataset: readable with many datasets
    parts = [
        "## Datasets side by side\n\n"
        f"Main dataset `{names[0]}`; cross-check datasets "
        + ", ".join(
            f"`{c['label']}` ({c['data']}: {c['sessions']} sessions, {c['frames']} frames)"
            for c in results["crosscheck"]
        )
        + ". Same methods, same scoring; a gap between columns is\nover-fitting to one "
        "generator. `≥5` pools every frame at or above 5 kPa.\n\n" + "\n\n".join(tables)
    ]
    for c in results["crosscheck"]:
        parts.append(
            f"## Cross-check `{c['label']}`: area error per pressure bin\n\n"
            + md_table(c["bins"], BIN_COLUMNS)
            + f"\n\n## Cross-check `{c['label']}`: contact onset (as the main dataset's)\n\n"
            + md_table(onset_shown(c["onset_table"]), ONSET_COLUMNS)
            + f"\n\n## Cross-check `{c['label']}`: hard cases\n\n"
            + md_table(c["hard"], HARD_COLUMNS)
        )
    return "\n\n".join(parts) + "\n"

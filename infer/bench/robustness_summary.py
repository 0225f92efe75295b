"""The robustness suite's scored frames as its rows (``contactcal bench --robustness``; the
suite itself is :mod:`~contactcal.infer.bench.robustness`).

Per method, perturbation and level: the median |relative area error| over frames with true
contact at ≥ 5 kPa, its ratio to the same perturbation's baseline level with a 90 % paired-bootstrap
interval over those frames (the ratio of two medians of ~30 frames is noisy: a ratio near the 2×
target is only as sure as its interval), and the no-contact accuracy (share of frames without true
contact, i.e. below the onset, reported as no contact).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from contactcal.infer.bench.scoring import ScoredFrame, bin_row
from contactcal.infer.bench.suite import PERTURBATIONS

#: Errors are summarised over contact frames at or above this pressure, kPa.
MIN_ERROR_KPA = 5.0
#: Paired bootstrap resamples behind each error ratio's interval (its ends wobble by ~1/√n).
RATIO_RESAMPLES = 2000
#: Two-sided level of the error ratio's interval (5th to 95th percentile).
RATIO_LEVEL = 0.9


def _median_error(frames: Sequence[ScoredFrame]) -> dict[str, Any]:
    """The bin row (:func:`~contactcal.infer.bench.scoring.bin_row`) of ``frames`` at
    ≥ :data:`MIN_ERROR_KPA`."""
    return bin_row([f for f in frames if f.pressure_kpa >= MIN_ERROR_KPA])


def ratio_interval(
    level: Sequence[ScoredFrame], base: Sequence[ScoredFrame], rng: np.random.Generator
) -> tuple[float, float] | None:
    """:data:`RATIO_LEVEL` paired-bootstrap interval of ``median |e_level| / median |e_base|``.

    The frames are resampled with replacement, each keeping its error at both levels, over the
    frames with true contact at ≥ :data:`MIN_ERROR_KPA` at both.

    Args:
        level: one method's scored frames at a level.
        base: the same method's scored frames at the baseline level, the same frames in the same
            order (the suite measures every level on the same samples).
        rng: the resampling generator.

    Returns:
        ``(low, high)``; None with fewer than 2 such frames or a zero baseline median.

    Raises:
        ValueError: ``level`` and ``base`` are not the same frames.
    """
    if [f.frame for f in level] != [f.frame for f in base]:
        raise ValueError("ratio_interval: the level's and the baseline's frames differ")
    pairs = [
        (abs(a.rel_error), abs(b.rel_error))
        for a, b in zip(level, base, strict=True)
        if a.true_contact and b.true_contact and a.pressure_kpa >= MIN_ERROR_KPA
    ]
    if len(pairs) < 2:
        return None
    e = np.asarray(pairs)  # (N, 2): |error| at the level, at the baseline
    pick = rng.integers(0, len(e), (RATIO_RESAMPLES, len(e)))
    den = np.median(e[pick, 1], axis=1)
    if not np.all(den > 0.0):
        return None
    ratios = np.median(e[pick, 0], axis=1) / den
    tail = 50.0 * (1.0 - RATIO_LEVEL)
    low, high = np.percentile(ratios, [tail, 100.0 - tail])
    return float(low), float(high)


def summary_rows(
    scored: Mapping[tuple[str, float, str], Sequence[ScoredFrame]],
    methods: Sequence[str],
    seed: int = 0,
) -> list[dict[str, Any]]:
    """Per perturbation, level (in ``levels`` order) and method: the error at ≥ 5 kPa, its ratio
    to the baseline level's with :func:`ratio_interval` (generator seeded by ``seed`` and the
    row), its change from the baseline level's (``error_change_points``: level − baseline, in
    percentage points) and the no-contact accuracy (None where no frame defines one)."""
    rows = []
    for j, p in enumerate(PERTURBATIONS):
        base = {
            m: _median_error(scored[(p.name, p.baseline, m)])["median_abs_rel_error"]
            for m in methods
        }
        for k, level in enumerate(p.levels):
            for i, method in enumerate(methods):
                frames = scored[(p.name, level, method)]
                high, every = _median_error(frames), bin_row(frames)
                err = high["median_abs_rel_error"]
                rng = np.random.default_rng([seed, j, k, i])
                interval = ratio_interval(frames, scored[(p.name, p.baseline, method)], rng)
                rows.append(
                    {
                        "perturbation": p.name,
                        "level": level,
                        "label": p.label(level),
                        "baseline": level == p.baseline,
                        "in_range": p.in_range(level),
                        "method": method,
                        "contact_frames_ge5": high["contact_frames"],
                        "median_abs_rel_error_ge5": err,
                        "error_ratio": None
                        if err is None or not base[method]
                        else err / base[method],
                        "error_ratio_interval": None if interval is None else list(interval),
                        "error_change_points": None
                        if err is None or base[method] is None
                        else 100.0 * (err - base[method]),
                        "no_contact_frames": every["no_contact_frames"],
                        "no_contact_accuracy": every["no_contact_accuracy"],
                    }
                )
    return rows

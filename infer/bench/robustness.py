"""Robustness suite of ``contactcal bench --robustness``: every method's error per level of each
perturbation (:mod:`~contactcal.infer.bench.perturb`) of a bounded sample of held-out frames.

Frames are sampled deterministically: all frames of all sessions but their reference frames (one
would be its own reference under the "same"-reference perturbations; the accuracy tables leave
them out too) ordered by pressure then session, ``n`` taken evenly spaced. Each is
perturbed at each level (its session's reference as the perturbation says), and measured by
each method from decoded arrays (``set_reference`` then ``measure``; no reduced JPEG decode).
A level's random draws come from ``numpy.random.default_rng([seed, frame, perturbation, level,
stream])``, so a run is reproducible and levels are independent of each other; a perturbation
with ``paired_draws`` (the window speck) leaves the level out, so that its levels draw the same
placement and differ in strength only.

What is reported per method, perturbation and level:
:mod:`~contactcal.infer.bench.robustness_summary`.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.bench.dataset import IndexRow
from contactcal.infer.bench.models import BenchModel
from contactcal.infer.bench.robustness_summary import summary_rows
from contactcal.infer.bench.scoring import ScoredFrame
from contactcal.infer.bench.suite import PERTURBATIONS, REFERENCE_MODES, Perturbation
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.base import Method
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.methods.unet.ring import RingFit, locate_ring


@dataclass(frozen=True)
class Sample:
    """One sampled frame, decoded, with its session's reference and ring."""

    row: IndexRow  # the frame's dataset row
    frame: np.ndarray  # (H, W) uint8
    reference: np.ndarray  # (H, W) uint8, the session's lowest-pressure frame
    mask: np.ndarray  # (H, W) uint8, 255 = contact
    ring: RingFit  # the window ring located on the unperturbed reference, px


def sample_rows(
    sessions: Mapping[str, Sequence[IndexRow]], n: int
) -> list[tuple[IndexRow, IndexRow]]:
    """``n`` (frame, reference) row pairs spread evenly over pressures and sessions, never a
    session's reference frame itself.

    Args:
        sessions: rows per session, sorted by pressure (the first is the reference).
        n: frames wanted (>= 1); all frames but the references when the dataset has fewer.

    Raises:
        ValueError: ``n < 1``, or no session has a frame besides its reference (naming the
            dataset's ``index.csv``).
    """
    if n < 1:
        raise ValueError(f"the robustness suite needs >= 1 frame, got {n}")
    pool = sorted(
        ((r, rows[0]) for rows in sessions.values() for r in rows[1:]),
        key=lambda pair: (pair[0].pressure_kpa, pair[0].session_key, str(pair[0].frame)),
    )
    if not pool:
        first = next(iter(sessions.values()))[0]
        raise ValueError(
            f"{first.dataset / 'index.csv'}: every session holds its reference frame only; the "
            "robustness suite needs frames besides each session's 0 kPa frame"
        )
    if n >= len(pool):
        return pool
    return [pool[int((i + 0.5) * len(pool) / n)] for i in range(n)]


def load_samples(pairs: Sequence[tuple[IndexRow, IndexRow]]) -> list[Sample]:
    """Decode each (frame, reference) pair's frame and mask; each session's reference is decoded
    and its ring located once, shared by the session's samples."""
    references: dict[Path, tuple[np.ndarray, RingFit]] = {}
    samples = []
    for row, reference in pairs:
        if reference.frame not in references:
            gray = load_image(reference.frame)
            references[reference.frame] = (gray, locate_ring(gray))
        ref, ring = references[reference.frame]
        samples.append(Sample(row, load_image(row.frame), ref, load_image(row.mask), ring))
    return samples


def perturbed(
    p: Perturbation, level: float, sample: Sample, seed: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray | None, float]:
    """The frame at one level, the reference the method gets, and the true area.

    Args:
        p: the perturbation.
        level: one of ``p.levels``.
        sample: the unperturbed frame.
        seed: entropy of this (frame, perturbation, level), without the level for a perturbation
            with ``paired_draws``; stream 1 is the reference's own.

    Returns:
        ``(frame (H', W') uint8, reference (H', W') uint8 or None, true area px at H'×W')``.
    """
    fn = functools.partial(p.apply, ring=sample.ring) if p.needs_ring else p.apply

    def rng(stream: int) -> np.random.Generator:
        return np.random.default_rng([*seed, stream])

    frame = fn(sample.frame, level, rng(0))
    if p.reference == "dropped":
        ref = sample.reference if level == p.baseline else None
    elif p.reference == "kept":
        ref = sample.reference
    else:
        ref = fn(sample.reference, level, rng(0 if p.reference == "same" else 1))
    if p.moves_mask:
        true = float(np.count_nonzero(fn(sample.mask, level, rng(0))))
    else:
        true = sample.row.area_px * frame.size / sample.frame.size
    return frame, ref, true


def _score(
    method: Method, sample: Sample, frame: np.ndarray, ref: np.ndarray | None, true: float
) -> ScoredFrame:
    """One method on one perturbed frame, given the reference it gets and the true area."""
    method.set_reference(ref, 1)
    res = method.measure(frame)
    return ScoredFrame(
        method=method.name,
        session=sample.row.session_key,
        frame=str(sample.row.frame),
        pressure_kpa=sample.row.pressure_kpa,
        true_area_px=true,
        area_px=float(res.area_px),
        contact=bool(res.contact),
    )


def measure_suite(
    samples: Sequence[Sample], methods: Sequence[Method], seed: int
) -> dict[tuple[str, float, str], list[ScoredFrame]]:
    """Every method on every sample at every level: scored frames per (perturbation, level,
    method)."""
    out: dict[tuple[str, float, str], list[ScoredFrame]] = {}
    for i, sample in enumerate(samples):
        for j, p in enumerate(PERTURBATIONS):
            for k, level in enumerate(p.levels):
                draws = (seed, i, j) if p.paired_draws else (seed, i, j, k)
                frame, ref, true = perturbed(p, level, sample, draws)
                for m in methods:
                    scored = _score(m, sample, frame, ref, true)
                    out.setdefault((p.name, level, m.name), []).append(scored)
    return out


def run_robustness(
    sessions: Mapping[str, Sequence[IndexRow]],
    model: BenchModel,
    frames: int,
    seed: int = 0,
    not_perturbed: Sequence[str] = (),
) -> dict[str, Any]:
    """The robustness suite on ``frames`` sampled frames (see the module docstring).

    Args:
        sessions: rows per session, sorted by pressure (the first is the reference).
        model: the U-Net's model as read once
            (:func:`~contactcal.infer.bench.models.load_models`).
        frames: frames to sample.
        seed: seed of the random perturbations.
        not_perturbed: the methods of the run the suite leaves out (``--variant`` models).

    Returns:
        ``results.json``'s ``"robustness"``: ``frames`` (the sampled files), ``seed``,
        ``perturbations`` (name, levels, labels, baseline, unit, reference handling), ``rows``
        (:func:`summary_rows`) and ``not_perturbed``.
    """
    samples = load_samples(sample_rows(sessions, frames))
    methods = [model.method(name) for name in METHODS]
    scored = measure_suite(samples, methods, seed)
    return {
        "frames": [str(s.row.frame) for s in samples],
        "seed": seed,
        "perturbations": [
            {
                "name": p.name,
                "levels": list(p.levels),
                "labels": [p.label(lv) for lv in p.levels],
                "baseline": p.baseline,
                "unit": p.unit,
                "reference": REFERENCE_MODES[p.reference],
                "randomised": None if p.randomised is None else list(p.randomised),
            }
            for p in PERTURBATIONS
        ],
        "rows": summary_rows(scored, METHODS, seed),
        "not_perturbed": list(not_perturbed),
    }

"""Gauge readings → pressure steps: readings closer than a tolerance are one step.

A manifest written from a pressure logger gives each frame the gauge's reading (5.02, 4.98,
5.01 kPa for three frames of the 5 kPa step), not the step's setpoint. Read as exact values,
every frame would be a step of its own: no repeats are pooled, the leave-one-step-out error
keeps each frame's near-twins in the fit, and the passes are no longer rising then falling.
:func:`step_labels` finds the steps (single linkage: sorted readings less than the tolerance
apart are one step, however many), :func:`pooled_pressures` gives each reading its step's
median. A manifest of setpoints at least the tolerance apart comes back unchanged. Setpoints
closer than that would chain into one step as wide as the tolerance or wider, and several
times wider than the session's other steps, which no held pressure's readings are
(:func:`is_chain`): ``read_session`` refuses such a step and names the option, so a sweep
stepped that finely is given a smaller tolerance (or 0, for setpoints).
:class:`Pooled` and :class:`AtRest` say what reading a manifest made of its steps
(:func:`~contactcal.infer.pipeline.manifest.read_session`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: kPa. Sorted readings less than this apart belong to one step. A gauge's jitter at a held
#: pressure is hundredths of a kPa, but three readings with a standard deviation of 0.03 kPa
#: leave a gap of 0.1 kPa between two of them in 0.7 % of steps (a quarter of 41-step
#: sessions), which splits the step (and may break the passes' order); at 0.2, none in
#: 200 000. Setpoints 0.25 kPa or more apart stay apart (exact ones at 0.2); readings of
#: 0.25-kPa steps that jitter by more than ~0.02 kPa can chain, and are refused (is_chain).
#: ``--step-tolerance-kpa``; 0: every distinct value is a step.
DEFAULT_STEP_TOLERANCE_KPA = 0.2
#: kPa: the largest tolerance accepted. Onset studies step 0.25-0.5 kPa; a tolerance near a
#: step would chain whole sweeps into one step.
MAX_STEP_TOLERANCE_KPA = 1.0
#: kPa: readings exactly one tolerance apart (0.1-kPa setpoints at tolerance 0.1) stay two steps
#: whatever the rounding of their difference (``0.3 - 0.2 < 0.1`` in floating point).
_ROUNDING_KPA = 1e-9
#: Decimals of a pooled step's pressure (kPa): a median of readings, without float noise.
_DECIMALS = 6


def check_tolerance(tolerance_kpa: float) -> None:
    """Raise ``ValueError`` unless ``0 <= tolerance_kpa <= MAX_STEP_TOLERANCE_KPA``."""
    if not 0.0 <= tolerance_kpa <= MAX_STEP_TOLERANCE_KPA:  # False for NaN
        raise ValueError(
            f"step tolerance {tolerance_kpa!r} kPa: expected 0 to {MAX_STEP_TOLERANCE_KPA:g} kPa "
            "(readings less than it apart are one step; 0: every distinct value is a step)"
        )


def step_labels(readings_kpa: Sequence[float], tolerance_kpa: float) -> np.ndarray:
    """Each reading's step, numbered from the lowest.

    Args:
        readings_kpa: ``(N,)`` gauge readings, kPa, any order.
        tolerance_kpa: kPa, see :func:`check_tolerance`; sorted readings less than it apart
            are one step.

    Returns:
        ``(N,) int64`` step index per reading, in the given order (0 = lowest step).

    Raises:
        ValueError: a tolerance out of range.
    """
    check_tolerance(tolerance_kpa)
    p = np.asarray(readings_kpa, dtype=np.float64)
    order = np.argsort(p, kind="stable")
    gaps = np.diff(p[order])
    new_step = (gaps > 0.0) if tolerance_kpa == 0.0 else gaps >= tolerance_kpa - _ROUNDING_KPA
    labels = np.empty(p.size, dtype=np.int64)
    labels[order] = np.concatenate([[0], np.cumsum(new_step)])[: p.size]
    return labels


#: A step is a chain when its readings span this many times a typical step's span (or the
#: tolerance, if more): jitter widens every step alike (three readings with a jitter of
#: 0.05 kPa span ~0.085 kPa, and more than 4 × that in ~1 of 10^6 steps), while a chain of
#: setpoints spans their whole run and the session's other steps span nothing.
CHAIN_FACTOR = 4.0


def is_chain(readings_kpa: Sequence[float], tolerance_kpa: float, typical_span_kpa: float) -> bool:
    """True if one step's ``(n,)`` readings (kPa) span the tolerance or more *and*
    :data:`CHAIN_FACTOR` × the session's typical step span (the median over its steps): single
    linkage chained values less than the tolerance apart into a step wider than the readings
    of one held pressure are, as setpoints finer than the tolerance, or two jittering steps,
    do. False at tolerance 0 (every distinct value is a step)."""
    p = np.asarray(readings_kpa, dtype=np.float64)
    bound = max(tolerance_kpa - _ROUNDING_KPA, CHAIN_FACTOR * typical_span_kpa)
    return tolerance_kpa > 0.0 and float(np.ptp(p)) >= bound


def pooled_pressures(readings_kpa: Sequence[float], labels: Sequence[int]) -> list[float]:
    """Each reading's step pressure: the median of its step's readings (rounded to 1e-6 kPa),
    the reading itself where its step holds one value.

    Args:
        readings_kpa: ``(N,)`` readings, kPa.
        labels: ``(N,)`` step per reading (:func:`step_labels`, or a subset's).

    Returns:
        ``N`` pressures, kPa, in the given order.
    """
    p = np.asarray(readings_kpa, dtype=np.float64)
    lab = np.asarray(labels)
    out = p.copy()
    for step in np.unique(lab):
        out[lab == step] = step_pressure(p[lab == step])
    return out.tolist()


def step_pressure(readings_kpa: Sequence[float] | np.ndarray) -> float:
    """One step's pressure from its ``(n,)`` readings (kPa, n >= 1): their median, rounded to
    1e-6 kPa (no float noise in the records), or the reading itself where all are equal."""
    p = np.asarray(readings_kpa, dtype=np.float64)
    return float(p[0]) if np.ptp(p) == 0.0 else round(float(np.median(p)), _DECIMALS)


@dataclass(frozen=True)
class Pooled:
    """The steps of a session pooled from differing gauge readings."""

    frames: int  # frames in such steps (each keeps its reading, ``pressure_kpa_read``)
    steps: int  # such steps (per pass)
    widest_kpa: tuple[float, float]  # the widest such step's lowest and highest reading, kPa


@dataclass(frozen=True)
class AtRest:
    """The steps of a session whose pressure came out below 0 kPa, given as 0 kPa (a gauge's
    offset at rest; :data:`~contactcal.infer.pipeline.manifest_rows.GAUGE_ZERO_NOISE_KPA`)."""

    frames: int  # frames in such steps (each keeps its reading, ``pressure_kpa_read``)
    lowest_kpa: float  # their lowest reading, kPa (< 0)

"""A manifest's gauge readings → its steps: each pass's readings pooled, a chain of finer
setpoints refused, a step read below 0 kPa given as 0.

:func:`pool_readings` is step 2 of :func:`~contactcal.infer.pipeline.manifest.read_session`
(after the passes, before the steps are numbered); the rules are
:mod:`~contactcal.infer.pipeline.readings`'.
"""

from __future__ import annotations

import numpy as np

from contactcal.infer.calibration.phases import PHASES
from contactcal.infer.pipeline.manifest_rows import (
    MIN_SWEEP_TOP_KPA,
    READING_COLUMN,
    Frame,
    ManifestError,
    sweep_top_warning,
    with_changes,
)
from contactcal.infer.pipeline.readings import (
    MAX_STEP_TOLERANCE_KPA,
    AtRest,
    Pooled,
    is_chain,
    step_labels,
    step_pressure,
)

#: The refusal of a step whose readings span the step tolerance or more (readings.is_chain).
CHAINED = (
    "{where}: the {phase} pass's pressures {lo:g} to {hi:g} kPa ({n} distinct values) chain "
    "into one step {span:g} kPa wide, as wide as the step tolerance {t:g} kPa or wider and "
    "wider than the session's other steps (values less than the tolerance apart are one step): "
    "for steps set this finely give --step-tolerance-kpa below their spacing (0 reads every "
    "distinct value as a step)"
)


def frame_step_labels(frames: list[Frame], tolerance_kpa: float) -> np.ndarray:
    """:func:`~contactcal.infer.pipeline.readings.step_labels` of the frames' readings; every
    distinct value its own step in a sweep whose top is below :data:`MIN_SWEEP_TOP_KPA` (bar
    or MPa read as kPa: its steps would merge into one, and
    :func:`~contactcal.infer.pipeline.manifest.check_sweep_unit` names its unit instead)."""
    readings = [f.pressure_kpa for f in frames]
    bar = 0.0 < max(readings, default=0.0) < MIN_SWEEP_TOP_KPA
    return step_labels(readings, 0.0 if bar else tolerance_kpa)


def pool_readings(
    where: str, names: list[str], frames: list[Frame], tolerance_kpa: float
) -> tuple[list[Frame], Pooled | None, AtRest | None]:
    """Each pass's steps found again among its own readings and each put at the median of
    its readings (per pass: a pass's offset from the other stays in the hysteresis, and cannot
    split a step of one pass in two), a step whose median is below 0 kPa (a gauge's offset at
    rest) at 0 kPa, every frame whose pressure so differs from its reading keeping the reading
    as :data:`READING_COLUMN`; and what was pooled and what was given as 0 kPa."""
    out = list(frames)
    moved, steps, widest = 0, 0, (0.0, 0.0)
    rest, lowest = 0, 0.0
    groups = _steps_per_pass(frames, tolerance_kpa)
    _check_chains(where, frames, groups, tolerance_kpa)
    for _, mine in groups:
        values = [frames[k].pressure_kpa for k in mine]
        lo, hi = min(values), max(values)
        median = step_pressure(values) + 0.0  # a median rounded to -0.0 is 0.0
        if lo == hi and median >= 0.0:
            continue
        level = max(median, 0.0)
        for k in mine:
            reading = (READING_COLUMN, frames[k].pressure_kpa)
            out[k] = with_changes(
                frames[k], pressure_kpa=level, extras=(*frames[k].extras, reading)
            )
        if lo != hi:
            moved, steps = moved + len(mine), steps + 1
            widest = max(widest, (lo, hi), key=lambda r: r[1] - r[0])
        if median < 0.0:
            rest, lowest = rest + len(mine), min(lowest, lo)
    if (moved or rest) and READING_COLUMN in names:
        raise ManifestError(
            f"{where}: readings less than a step tolerance apart are pooled into steps (a step "
            f"read below 0 kPa is given as 0), and each such frame's reading goes to the column "
            f"'{READING_COLUMN}', which the manifest has already; rename that column"
            + ("" if rest else " (or give --step-tolerance-kpa 0)")
        )
    pooled = Pooled(moved, steps, widest) if moved else None
    return out, pooled, AtRest(rest, lowest) if rest else None


def _steps_per_pass(frames: list[Frame], tolerance_kpa: float) -> list[tuple[str, list[int]]]:
    """``(phase, frame indices)`` of each pass's steps, found among that pass's readings."""
    groups = []
    for phase in PHASES:
        idx = [k for k, f in enumerate(frames) if f.phase == phase]
        labels = frame_step_labels([frames[k] for k in idx], tolerance_kpa)
        for step in np.unique(labels):
            groups.append((phase, [k for k, lab in zip(idx, labels, strict=True) if lab == step]))
    return groups


def _check_chains(
    where: str, frames: list[Frame], groups: list[tuple[str, list[int]]], tolerance_kpa: float
) -> None:
    """Refuse a step whose values chain (:func:`~contactcal.infer.pipeline.readings.is_chain`:
    wider than the tolerance and than the session's steps typically are), naming the option."""
    values = [[frames[k].pressure_kpa for k in mine] for _, mine in groups]
    typical = float(np.median([max(v) - min(v) for v in values])) if values else 0.0
    top = max((f.pressure_kpa for f in frames), default=0.0)
    for (phase, _), v in zip(groups, values, strict=True):
        if not is_chain(v, tolerance_kpa, typical):
            continue
        span = round(max(v) - min(v), 6)
        held = (
            f"; if they are the readings of one held pressure, give a tolerance above {span:g} kPa"
            if span < MAX_STEP_TOLERANCE_KPA
            else ""
        )
        unit = (
            "" if sweep_top_warning(top) is None else f" (and the sweep tops out at {top:g}: mbar?)"
        )
        raise ManifestError(
            CHAINED.format(
                where=where,
                phase=phase,
                lo=min(v),
                hi=max(v),
                n=len(set(v)),
                span=span,
                t=tolerance_kpa,
            )
            + held
            + unit
        )

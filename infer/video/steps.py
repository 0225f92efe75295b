"""Steady pressure steps in a pressure log: which frames of a video to calibrate with.

A log sample is *steady* when every sample over the ``settle_s`` before it (and the last sample
at or before that window's start, so the window is covered) lies in a band of ``2 ×
tolerance_kpa``: the chamber has held its pressure long enough for the membrane to settle. A
*step* is a run of consecutive steady samples whose pressures stay within that band (a slow
drift starts a new step); frames taken from its first to its last steady sample are kept, the
others (ramps, settling) are skipped. A step's pressure is the median of its samples. Steps
before the highest-pressure step, and that step, are the loading pass; those after it unloading.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from contactcal.infer.calibration.phases import LOADING, UNLOADING
from contactcal.infer.video.log import PressureLog
from contactcal.infer.video.step_config import StepConfig


@dataclass(frozen=True)
class Step:
    """One steady step.

    Attributes:
        index: 0-based, in time order.
        pressure_kpa: median of the step's log samples, kPa (a median below 0, gauge noise at
            rest, is given as 0.0).
        start_s, end_s: first and last steady sample, s since the video's first frame; frames
            with ``start_s <= t <= end_s`` belong to the step.
        phase: :data:`LOADING` or :data:`UNLOADING`.
    """

    index: int
    pressure_kpa: float
    start_s: float
    end_s: float
    phase: str

    def label(self) -> str:
        """Short description for messages, e.g. ``4 kPa (loading, 3.50-5.00 s)``."""
        return f"{self.pressure_kpa:g} kPa ({self.phase}, {self.start_s:.2f}-{self.end_s:.2f} s)"


def window_spans(log: PressureLog, window_s: float) -> np.ndarray:
    """``(N,)`` kPa: each sample's peak-to-peak over the ``window_s`` before it (and the last
    sample at or before that window's start, so the window is covered); NaN where the log does
    not cover the window."""
    t, p = log.times_s, log.pressures_kpa
    starts = np.searchsorted(t, t - window_s, side="right") - 1
    out = np.full(len(t), np.nan)
    for i, lo in enumerate(starts):
        if lo >= 0:
            out[i] = np.ptp(p[lo : i + 1])
    return out


def steady_mask(log: PressureLog, cfg: StepConfig) -> np.ndarray:
    """``(N,) bool``: whether each sample has been steady for ``cfg.settle_s`` (see module)."""
    spans = window_spans(log, cfg.settle_s)
    return np.nan_to_num(spans, nan=np.inf) <= 2 * cfg.tolerance_kpa


def _runs(log: PressureLog, steady: np.ndarray, band: float) -> list[tuple[int, int]]:
    """``(first, last)`` sample indices of runs of steady samples within ``band`` kPa."""
    runs: list[tuple[int, int]] = []
    first, lo, hi = -1, 0.0, 0.0
    for i, (ok, p) in enumerate(zip(steady, log.pressures_kpa, strict=True)):
        if ok and first >= 0 and max(hi, p) - min(lo, p) <= band:
            lo, hi = min(lo, p), max(hi, p)
            continue
        if first >= 0:
            runs.append((first, i - 1))
        first, lo, hi = (i, p, p) if ok else (-1, 0.0, 0.0)
    if first >= 0:
        runs.append((first, len(steady) - 1))
    return [(a, b) for a, b in runs if b > a]  # one sample spans no time: no frames


def detect_steps(log: PressureLog, cfg: StepConfig) -> list[Step]:
    """The log's steady steps in time order, with their phases (see the module docstring).

    Causal: steps ending before the log's last sample do not change as the log grows, so a live
    capture can decide on each frame once the log has passed its time.
    """
    steady = steady_mask(log, cfg)
    runs = _runs(log, steady, 2 * cfg.tolerance_kpa)
    pressures = [max(float(np.median(log.pressures_kpa[a : b + 1])), 0.0) for a, b in runs]
    steps = [
        Step(k, round(pressures[k], 3), float(log.times_s[a]), float(log.times_s[b]), LOADING)
        for k, (a, b) in enumerate(runs)
    ]
    return with_phases(steps)


def with_phases(steps: list[Step]) -> list[Step]:
    """``steps`` (time order) with their phases: loading up to the first highest-pressure
    step, unloading after it. Given the steps that hold frames, a frameless sliver of the log
    cannot be the top that splits the passes."""
    top = int(np.argmax([s.pressure_kpa for s in steps])) if steps else 0
    return [replace(s, phase=LOADING if k <= top else UNLOADING) for k, s in enumerate(steps)]


#: s: the shortest window :func:`hold_scatter_kpa` looks at a hold through.
SCATTER_WINDOW_S = 0.5


def hold_scatter_kpa(log: PressureLog, cfg: StepConfig) -> float:
    """kPa: how far the log's samples scatter over a settle window at a hold, as the steadiness
    test sees it: the lower quartile of every window's peak-to-peak (holds fill most of a
    sweep's time and have the smallest spans; ramps' windows are above the quartile). A band
    of ``2 × tolerance`` that this quartile fills by more than three quarters splits or loses
    holds (their noisier windows exceed it). 0.0 for a log too short for one window, or
    sampled fewer than three times a window."""
    window = max(cfg.settle_s, SCATTER_WINDOW_S)
    if len(log.times_s) < 2 or float(np.median(np.diff(log.times_s))) > window / 3:
        return 0.0  # too sparse to see a hold through a window (said otherwise)
    spans = window_spans(log, window)
    spans = spans[np.isfinite(spans)]
    return float(np.percentile(spans, 25)) if spans.size else 0.0


def step_at(steps: list[Step], time_s: float) -> Step | None:
    """The step a frame taken at ``time_s`` belongs to, or None (ramp, settling, outside)."""
    for s in steps:
        if s.start_s <= time_s <= s.end_s:
            return s
    return None


def reference_step(steps: list[Step]) -> Step:
    """The session's reference: the lowest-pressure loading step (normally 0 kPa, earliest)."""
    loading = [s for s in steps if s.phase == LOADING]
    return min(loading, key=lambda s: (s.pressure_kpa, s.index))

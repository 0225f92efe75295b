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


def steady_mask(log: PressureLog, cfg: StepConfig) -> np.ndarray:
    """``(N,) bool``: whether each sample has been steady for ``cfg.settle_s`` (see module)."""
    t, p = log.times_s, log.pressures_kpa
    starts = np.searchsorted(t, t - cfg.settle_s, side="right") - 1
    out = np.zeros(len(t), bool)
    for i, lo in enumerate(starts):
        if lo >= 0:  # the log covers the whole settle window
            out[i] = np.ptp(p[lo : i + 1]) <= 2 * cfg.tolerance_kpa
    return out


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


#: median |second difference| / σ for white noise of standard deviation σ (0.6745·√6).
_MEDIAN_DIFF2_PER_SIGMA = 1.652
#: A settle window's samples of noise σ span about 4.5 σ (50 samples): a band of 2 × tolerance
#: holds them when tolerance >= 2.25 σ.
NOISE_PER_TOLERANCE = 1 / 2.25


def log_noise_kpa(log: PressureLog) -> float:
    """The log's noise, kPa: the standard deviation white noise would need for the median
    |second difference| of consecutive samples. A hold and a steady ramp (and a staircase
    sampled once per step) have none, so only the corners between them add to it, and the
    median passes over those. 0.0 with fewer than three samples or exact values."""
    if len(log.pressures_kpa) < 3:
        return 0.0
    d2 = np.abs(np.diff(log.pressures_kpa, n=2))
    return float(np.median(d2)) / _MEDIAN_DIFF2_PER_SIGMA


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

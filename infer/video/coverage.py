"""Whether the steps found in a video's pressure log can be calibrated: every step holds a frame,
the log is one cycle, and the steps are not split, lost or merged by ``--tolerance-kpa`` and
``--settle-s`` (:func:`check_coverage`, after :func:`~.extract.extract_frames`).
"""

from __future__ import annotations

import itertools
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from contactcal.infer.calibration.phases import LOADING, UNLOADING
from contactcal.infer.video.extract import Extractor
from contactcal.infer.video.steps import SCATTER_WINDOW_S, hold_scatter_kpa


def _noise_problem(extractor: Extractor) -> str | None:
    """What makes the steps unreliable at ``--tolerance-kpa`` / ``--settle-s``, with the option
    that fixes it; None when nothing does:

    - the holds scatter more than the band takes (:func:`~.steps.hold_scatter_kpa` above 1.5 ×
      the tolerance): held pressures are split into steps, or lost;
    - they are steady over a short window but not over ``--settle-s``: the holds are shorter
      than the settle time (the scatter is the ramps', and a larger tolerance would merge steps);
    - two steps in a row lie closer than the band (2 × tolerance): neighbouring holds merge, or
      one is split, at this tolerance.
    """
    if extractor.log is None:
        return None
    cfg, log = extractor.cfg, extractor.log
    tol = cfg.tolerance_kpa
    scatter = hold_scatter_kpa(log, cfg)
    short = hold_scatter_kpa(log, replace(cfg, settle_s=0.0))  # over SCATTER_WINDOW_S only
    if scatter > 1.5 * tol and short <= 1.5 * tol:
        return (
            f"its holds are steady over {SCATTER_WINDOW_S:g} s but not over --settle-s "
            f"{cfg.settle_s:g} (~{scatter:.2f} kPa peak to peak: ramps): the holds are shorter "
            "than the settle time; give a --settle-s below the holds' length"
        )
    if scatter > 1.5 * tol:
        return (
            f"its holds scatter by ~{scatter:.2f} kPa peak to peak, too much for --tolerance-kpa "
            f"{tol:g} (a band of ±{tol:g}): held pressures are split into several steps or "
            f"lost; give --tolerance-kpa {max(math.ceil(scatter * 100) / 100, 2 * tol):g} or "
            "more (below half the spacing of the held pressures)"
        )
    p = [s.pressure_kpa for s in extractor.kept_steps()]
    split = [(a, b) for a, b in itertools.pairwise(p) if abs(b - a) < 2 * tol]
    if split:
        a, b = split[0]
        return (
            f"steps {a:g} and {b:g} kPa in a row lie closer than the band of --tolerance-kpa "
            f"{tol:g} (±{tol:g}; its holds scatter by ~{scatter:.2f} kPa): neighbouring holds "
            "merge into one step, or one hold is split, at this tolerance; give a "
            "--tolerance-kpa below half the spacing of the held pressures"
        )
    return None


def _check_noise(extractor: Extractor, where: str, live: bool) -> None:
    """Refuse a video whose steps :func:`_noise_problem` finds unreliable (ValueError: run it
    again with the option it names); for a live capture, which cannot be run again, say it on
    stderr and go on (its frames and manifest can be calibrated again)."""
    problem = _noise_problem(extractor)
    if problem is None:
        return
    if not live:
        raise ValueError(f"{where}: {problem}")
    print(f"warning: {where}: {problem}", file=sys.stderr)


def _check_one_cycle(extractor: Extractor, where: str) -> None:
    """Refuse a log that is not one cycle, rising to its highest step then falling: a second
    cycle's rise would be read as unloading (or the first cycle's fall as loading) and mixed
    into that curve and the hysteresis.

    Raises:
        ValueError: naming the log, the two steps and their times.
    """
    tol = extractor.cfg.tolerance_kpa
    for a, b in itertools.pairwise(extractor.used_steps()):
        rises = b.pressure_kpa > a.pressure_kpa + 2 * tol
        falls = b.pressure_kpa < a.pressure_kpa - 2 * tol
        if (rises and a.phase == UNLOADING) or (falls and b.phase == LOADING):
            raise ValueError(
                f"{where}: the pressure {'rises' if rises else 'falls'} from {a.label()} to "
                f"{b.label()}, so the log is not one cycle (0 kPa up to the highest step and "
                "back); expected one cycle per recording: calibrate each cycle from its own "
                "video and log"
            )


def check_coverage(extractor: Extractor, video: Path | None) -> None:
    """Every step of the log must hold a frame of the video (else the session is incomplete).

    Args:
        extractor: after :func:`extract_frames`.
        video: the video file; None for a live capture, where the steps the capture ended
            before (the log went on) are left out, said on stderr.

    Raises:
        ValueError: naming the log: no steady step, the first uncovered step and the video's
            time span, or fewer than two loading pressures among the used steps.
    """
    log = extractor.log
    where = "the log" if log is None else str(log.path)
    _check_noise(extractor, where, live=video is None)
    if not extractor.steps:
        density = ""
        if log is not None and len(log.times_s) > 1:
            dt = float(np.median(np.diff(log.times_s)))
            density = (
                f"; it has {len(log.times_s)} samples, {dt:.2f} s apart (median): a step needs "
                f"samples within the tolerance over more than the settle time "
                f"({extractor.cfg.settle_s:g} s), so log the pressure several times a second "
                "and hold each step longer than --settle-s"
            )
        raise ValueError(
            f"{where}: no steady pressure step found (each step must hold within the "
            f"tolerance for longer than the settle time){density}; check the log, "
            "--tolerance-kpa or --settle-s"
        )
    source = "the capture" if video is None else f"the video {video}"
    if log is not None and extractor.last_time_s > float(log.times_s[-1]) + 1.0:
        print(
            f"note: {source} runs to {extractor.last_time_s:.1f} s, past the end of {where} at "
            f"{float(log.times_s[-1]):.1f} s; frames after the log are not used",
            file=sys.stderr,
        )
    for s in extractor.steps:
        if s.index in extractor.kept:
            continue
        if video is None and s.start_s > extractor.last_time_s:
            print(f"note: step {s.label()} began after the capture ended", file=sys.stderr)
            continue
        gap = extractor.frame_interval_s()
        if gap is not None and s.end_s - s.start_s < 2 * gap and s.end_s < extractor.last_time_s:
            print(  # a sliver of the log between two frames (noise inside the band): no hold
                f"note: step {s.label()} of {where} lasts {s.end_s - s.start_s:.2f} s, less than "
                f"two frames of {source} ({gap:.3f} s apart): no frame to calibrate it with, "
                "left out",
                file=sys.stderr,
            )
            continue
        if s.start_s > extractor.last_time_s:  # the frames stop before the step begins
            raise ValueError(
                f"{source} ends at {extractor.last_time_s:.2f} s, before step {s.label()} of "
                f"{where}; expected frames covering every step of the log: is the video cut "
                "short (a truncated copy), the log another recording's, or its time_s not in "
                "seconds (ms)?"
            )
        raise ValueError(
            f"{where}: step {s.label()} has no frame in {source} (frames from 0 to "
            f"{extractor.last_time_s:.2f} s); expected frames covering every step of the log "
            "(trim the log, give the full video, or lower --settle-s for short steps)"
        )
    _check_one_cycle(extractor, where)
    loading = sorted({s.pressure_kpa for s in extractor.used_steps() if s.phase == LOADING})
    if len(loading) < 2:
        raise ValueError(
            f"{where}: the steady steps found hold {len(loading)} loading pressure(s) "
            f"({', '.join(f'{p:g}' for p in loading)} kPa); a calibration needs >= 2 from 0 kPa "
            "up (is the log in kPa? check --tolerance-kpa and --settle-s)"
        )

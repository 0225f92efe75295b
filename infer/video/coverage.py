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
from contactcal.infer.video.log import PressureLog
from contactcal.infer.video.steps import SCATTER_WINDOW_S, hold_scatter_kpa

#: × ``--tolerance-kpa``: hold scatter (:func:`~.steps.hold_scatter_kpa`, peak to peak) above
#: which held pressures are split or lost: three quarters of the band of 2 × tolerance.
NOISY_SCATTER = 1.5


def _dense(log: PressureLog) -> bool:
    """Whether the log is sampled at least three times a :data:`~.steps.SCATTER_WINDOW_S`
    (:func:`~.steps.hold_scatter_kpa` reads 0.0, "cannot tell", below that)."""
    t = log.times_s
    return len(t) > 1 and float(np.median(np.diff(t))) <= SCATTER_WINDOW_S / 3


def step_warnings(extractor: Extractor) -> list[str]:
    """What may make the steps unreliable at ``--tolerance-kpa`` / ``--settle-s``, each with the
    option that helps (warnings: the measures are heuristics, and a run can be right anyway):

    - the holds look steady over a short window but not over ``--settle-s``: holds shorter than
      the settle time (the scatter is then the ramps', and a larger tolerance would merge steps);
    - the holds scatter by more than :data:`NOISY_SCATTER` × the tolerance: held pressures may
      be split into steps, or lost;
    - two steps in a row closer than the band (2 × tolerance): one hold split (less than one
      tolerance apart: a glitch, or a slow ramp's tail) or neighbouring holds merged.
    """
    log, cfg = extractor.log, extractor.cfg
    if log is None:
        return []
    tol, out = cfg.tolerance_kpa, []
    scatter = hold_scatter_kpa(log, cfg)
    short = hold_scatter_kpa(log, replace(cfg, settle_s=0.0))  # over SCATTER_WINDOW_S only
    noisy = scatter > NOISY_SCATTER * tol
    if noisy and _dense(log) and short <= NOISY_SCATTER * tol:
        out.append(
            f"its holds are steady over {SCATTER_WINDOW_S:g} s but not over --settle-s "
            f"{cfg.settle_s:g} (~{scatter:.2f} kPa peak to peak: ramps): the holds may be "
            "shorter than the settle time; give a --settle-s below the holds' length"
        )
    elif noisy:
        out.append(
            f"its holds scatter by ~{scatter:.2f} kPa peak to peak, too much for --tolerance-kpa "
            f"{tol:g} (a band of ±{tol:g}): held pressures may be split into several steps or "
            f"lost; give --tolerance-kpa {max(math.ceil(scatter * 100) / 100, 2 * tol):g} or "
            "more (below half the spacing of the held pressures)"
        )
    p = [s.pressure_kpa for s in extractor.kept_steps()]
    for a, b in itertools.pairwise(p):
        if abs(b - a) < tol:
            out.append(
                f"steps {a:g} and {b:g} kPa in a row are less than --tolerance-kpa {tol:g} "
                "apart: one hold split (a glitch in the log, or a slow ramp's tail), "
                "calibrated as two steps; check the log there"
            )
        elif abs(b - a) < 2 * tol:
            out.append(
                f"steps {a:g} and {b:g} kPa in a row lie within the band of --tolerance-kpa "
                f"{tol:g} (±{tol:g}): neighbouring holds this close merge, or split, at this "
                "tolerance; give a --tolerance-kpa below half their spacing"
            )
        else:
            continue
        break  # the first such pair says it
    return out


def _one_cycle_problem(extractor: Extractor) -> str | None:
    """Why the log is not one cycle, rising to its highest step then falling (a second cycle's
    rise would be read as unloading, or the first cycle's fall as loading, and mixed into that
    curve and the hysteresis); None when it is."""
    tol = extractor.cfg.tolerance_kpa
    for a, b in itertools.pairwise(extractor.used_steps()):
        rises = b.pressure_kpa > a.pressure_kpa + 2 * tol
        falls = b.pressure_kpa < a.pressure_kpa - 2 * tol
        if (rises and a.phase == UNLOADING) or (falls and b.phase == LOADING):
            return (
                f"the pressure {'rises' if rises else 'falls'} from {a.label()} to {b.label()}, "
                "so the log is not one cycle (0 kPa up to the highest step and back); expected "
                "one cycle per recording: calibrate each cycle from its own video and log"
            )
    return None


def check_coverage(extractor: Extractor, video: Path | None) -> list[str]:
    """Every step of the log must hold a frame of the video (else the session is incomplete).

    Args:
        extractor: after :func:`extract_frames`.
        video: the video file; None for a live capture, where the steps the capture ended
            before (the log went on) are left out, said on stderr.

    Returns:
        The warning lines of :func:`step_warnings` (and, for a live capture, of a log that is
        not one cycle), for the command to print under the calibration's table.

    Raises:
        ValueError: naming the log: no steady step, the first uncovered step and the video's
            time span, a video whose log is not one cycle, or fewer than two loading pressures
            among the used steps; with :func:`step_warnings`' findings appended, which may say
            why.
    """
    where = "the log" if extractor.log is None else str(extractor.log.path)
    found = step_warnings(extractor)
    try:
        _check_steps_found(extractor, where)
        _check_steps_have_frames(extractor, video, where)
        cycle = _one_cycle_problem(extractor)
        if cycle is not None and video is not None:
            raise ValueError(f"{where}: {cycle}")
        _check_loading(extractor, where)
    except ValueError as exc:
        if not found:
            raise
        raise ValueError(f"{exc} (and {'; '.join(found)})") from None
    found += [] if cycle is None else [cycle]  # a live capture: its frames stay calibratable
    return [f"warning: {where}: {w}" for w in found]


def _check_steps_found(extractor: Extractor, where: str) -> None:
    """Refuse a log without a steady step, saying how densely it is sampled."""
    log = extractor.log
    if extractor.steps:
        return
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


def _check_steps_have_frames(extractor: Extractor, video: Path | None, where: str) -> None:
    """Refuse a step without a frame (a cut video, another recording's log); say on stderr the
    frames past the log, and the steps left out: begun after a capture ended, or a sliver of the
    log between two frames."""
    log = extractor.log
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


def _check_loading(extractor: Extractor, where: str) -> None:
    """Refuse used steps with fewer than two loading pressures (no curve)."""
    loading = sorted({s.pressure_kpa for s in extractor.used_steps() if s.phase == LOADING})
    if len(loading) < 2:
        raise ValueError(
            f"{where}: the steady steps found hold {len(loading)} loading pressure(s) "
            f"({', '.join(f'{p:g}' for p in loading)} kPa); a calibration needs >= 2 from 0 kPa "
            "up (is the log in kPa? check --tolerance-kpa and --settle-s)"
        )

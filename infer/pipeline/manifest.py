"""Session manifest: which image was taken at which pressure, in which pass.

Format: a UTF-8 CSV (a byte-order mark is tolerated) with a header naming its columns (whitespace
around the names is tolerated), then one row per frame::

    file,pressure_kpa,phase,time_s
    p00.0kpa_a.png,0.0,loading,0.0
    p00.0kpa_b.png,0.0,loading,0.1
    p02.0kpa_a.png,2.0,loading,3.0
    p00.0kpa_c.png,0.0,unloading,9.0

Required columns: ``file`` (an image path, relative to the manifest's folder or absolute, each
image on one row only) and ``pressure_kpa`` (chamber gauge pressure, kPa, 0 to
:data:`MAX_PRESSURE_KPA`; a gauge's offset at rest down to -:data:`GAUGE_ZERO_NOISE_KPA` is
accepted, and a step read below 0 is given as 0 kPa). Optional ``phase``: ``loading`` or
``unloading`` (case-insensitive). Any other column (e.g. ``timestamp``) is kept per frame
(:attr:`Frame.extras`). A pressure may repeat: the frames of one phase at one pressure are one
pressure *step*; readings less than a tolerance apart (a gauge's, of one held pressure) are read
as one step (:mod:`~contactcal.infer.pipeline.readings`). Without a ``phase`` column the passes
are read from the row order (rising then falling: the rows after the maximum are the unloading
pass; see :func:`~contactcal.infer.calibration.phases.phases_from_order`).
Blank lines are skipped. `read_manifest` returns the frames sorted by phase (loading first), then
pressure, then row; the first one, the lowest-pressure frame of the loading pass, is the session's
reference frame (normally 0 kPa, membrane at rest, no contact).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from contactcal.infer.calibration.phases import (
    FROM_COLUMN,
    LOADING,
    PHASES,
    order_slack,
    parse_phase,
    phases_from_order,
)
from contactcal.infer.pipeline.manifest_rows import (
    GAUGE_ZERO_NOISE_KPA,
    HEADER,
    MAX_PRESSURE_KPA,
    PHASE_COLUMN,
    REQUIRED_COLUMNS,
    Frame,
    ManifestError,
    check_header,
    parse_row,
    read_rows,
)
from contactcal.infer.pipeline.readings import (
    DEFAULT_STEP_TOLERANCE_KPA,
    MAX_STEP_TOLERANCE_KPA,
    AtRest,
    Pooled,
    is_chain,
    pooled_pressures,
    step_labels,
    step_pressure,
)

__all__ = [
    "GAUGE_ZERO_NOISE_KPA",
    "MAX_PRESSURE_KPA",
    "READING_COLUMN",
    "REQUIRED_COLUMNS",
    "AtRest",
    "Frame",
    "ManifestError",
    "Pooled",
    "Session",
    "beside_manifest",
    "check_sweep_top",
    "check_sweep_unit",
    "read_manifest",
    "read_session",
    "sweep_top_warning",
]

#: The extra a frame gets when its reading is read as its step's pressure: the reading.
READING_COLUMN = "pressure_kpa_read"
#: The refusal of a step whose readings span the step tolerance or more (readings.is_chain).
CHAINED = (
    "{where}: the {phase} pass's pressures {lo:g} to {hi:g} kPa ({n} distinct values) chain "
    "into one step {span:g} kPa wide, as wide as the step tolerance {t:g} kPa or wider and "
    "wider than the session's other steps (values less than the tolerance apart are one step): "
    "for steps set this finely give --step-tolerance-kpa below their spacing (0 reads every "
    "distinct value as a step)"
)
_MAX_LISTED = 5


@dataclass(frozen=True)
class Session:
    """A read manifest: its frames and how their phases were determined."""

    frames: list[Frame]  # sorted by phase (loading first), pressure, row; [0] is the reference
    phase_source: str  # phases.FROM_COLUMN, FROM_ORDER or SINGLE_PASS
    pooled: Pooled | None = None  # steps pooled from differing readings (readings.py); None: none
    at_rest: AtRest | None = None  # steps read below 0 kPa, given as 0; None: none


#: kPa: a session whose highest pressure is below this cannot be a calibration sweep of the
#: display (contact starts at ~3 kPa): its pressures are in another unit (bar: 20 kPa is 0.2;
#: MPa: 0.02), refused by :func:`check_sweep_unit`.
MIN_SWEEP_TOP_KPA = 1.0


def check_sweep_unit(where: str | os.PathLike[str], frames: Sequence[Frame]) -> None:
    """Refuse a session whose pressures all lie below :data:`MIN_SWEEP_TOP_KPA` (and not all
    0: those get the "no contact" answer): the calibration would read bar or MPa as kPa.

    Raises:
        ManifestError: naming the manifest, its highest pressure and the units it may be in.
    """
    check_sweep_top(where, max((f.pressure_kpa for f in frames), default=0.0))


def check_sweep_top(where: str | os.PathLike[str], top: float) -> None:
    """:func:`check_sweep_unit` on the sweep's highest pressure ``top`` (kPa as read) from the
    file ``where`` (a manifest, or a video run's pressure log).

    Raises:
        ManifestError: naming ``where``, ``top`` and the units it may be in.
    """
    if 0.0 < top < MIN_SWEEP_TOP_KPA:
        raise ManifestError(
            f"{where}: the highest pressure_kpa is {top:g}, below {MIN_SWEEP_TOP_KPA:g} kPa; "
            "expected kPa (the display works at 0-20 kPa, contact from ~3 kPa), not bar or MPa"
        )


#: kPa: a sweep whose highest pressure is above this is read, with a warning: the display works at
#: 0-20 kPa, so a top of 30-100 kPa is more likely mbar read as kPa (a 0-10 kPa sweep in mbar
#: tops out at 100) than a display calibrated that high; below :data:`MAX_PRESSURE_KPA` no bound
#: can tell them apart, so it is said, not refused.
HIGH_SWEEP_TOP_KPA = 30.0


def sweep_top_warning(top: float) -> str | None:
    """The warning line of a sweep whose highest pressure ``top`` (kPa as read) is above
    :data:`HIGH_SWEEP_TOP_KPA`; None below it."""
    if top <= HIGH_SWEEP_TOP_KPA:
        return None
    return (
        f"warning: the highest pressure is {top:g} kPa, far above the display's 0-20 kPa: if the "
        "pressures are in mbar (or another unit), convert them to kPa and calibrate again"
    )


def beside_manifest(path: str | os.PathLike[str], name: str = "rig.json") -> Path:
    """The file ``name`` in the folder the manifest's frame paths are resolved against: the
    manifest file's own folder, a link's target's (so a linked manifest finds the ``rig.json``
    of its frames, not of the link's folder)."""
    return Path(path).resolve().parent / name


def read_manifest(
    path: str | os.PathLike[str], step_tolerance_kpa: float = DEFAULT_STEP_TOLERANCE_KPA
) -> list[Frame]:
    """The frames of a session manifest (see `read_session`); ``frames[0]`` is the reference."""
    return read_session(path, step_tolerance_kpa).frames


def read_session(
    path: str | os.PathLike[str], step_tolerance_kpa: float = DEFAULT_STEP_TOLERANCE_KPA
) -> Session:
    """Read and validate a session manifest.

    Args:
        path: the manifest CSV.
        step_tolerance_kpa: kPa, sorted readings less than this apart are one step
            (:func:`~contactcal.infer.pipeline.readings.step_labels`); the passes are read
            from the steps' order, and each pass's frames of a step with differing readings
            get the median of those readings as ``pressure_kpa``, their reading kept in
            ``extras`` as :data:`READING_COLUMN` (:attr:`Session.pooled` says how many). 0:
            every distinct value is a step.

    Returns:
        The :class:`Session`: frames sorted by phase (loading first), pressure and row.

    Raises:
        ManifestError: with the manifest path, the row, what was expected and how to fix it.
        ValueError: a step tolerance out of range.
    """
    mpath = Path(path)
    where = str(mpath)
    rows = read_rows(mpath)
    if not rows:
        raise ManifestError(
            f"{where}: the manifest is empty; expected a header line '{HEADER}' "
            "followed by one 'image,pressure' row per frame"
        )
    header_line, header = rows[0]
    names = check_header(where, header_line, header)
    data = rows[1:]
    if not data:
        raise ManifestError(
            f"{where}: the manifest has a header but no frames; add one row "
            "'<image file>,<pressure in kPa>' per frame under the header 'file,pressure_kpa' "
            "(a calibration needs >= 2 pressure steps)"
        )
    frames = [
        parse_row(where, mpath, names, row_no, line_no, cells)
        for row_no, (line_no, cells) in enumerate(data, start=1)
    ]
    source = FROM_COLUMN
    if PHASE_COLUMN not in names:  # the passes from the steps' order (readings jitter)
        _check_phase_elsewhere(where, names, frames)
        labels = _step_labels(frames, step_tolerance_kpa)
        # A step below 0 kPa is given as 0 (_pool_readings): a rest reading of -0.3 between
        # 0 and 0.5 kPa steps is no reversal of the passes.
        levels = [max(v, 0.0) for v in pooled_pressures([f.pressure_kpa for f in frames], labels)]
        phases, source = phases_from_order(levels, order_slack(levels))
        frames = [_with(f, phase=ph) for f, ph in zip(frames, phases, strict=True)]
    frames, pooled, at_rest = _pool_readings(where, names, frames, step_tolerance_kpa)
    merged = f"readings less than {step_tolerance_kpa:g} kPa apart are one step"
    hint = "" if pooled is None else f" ({merged}: --step-tolerance-kpa)"
    frames = _number_steps(where, frames, hint)
    _check_files(where, frames, mpath.resolve().parent)
    return Session(frames, source, pooled, at_rest)


def _check_phase_elsewhere(where: str, names: list[str], frames: list[Frame]) -> None:
    """Refuse a column of another name that holds only passes (``phases``, ``pass``): read
    from the row order instead, the passes it states would be lost without a word."""
    for name in names:
        cells = [dict(f.extras).get(name, "") for f in frames]
        if name in REQUIRED_COLUMNS or not all(parse_phase(c) for c in cells):
            continue
        raise ManifestError(
            f"{where}: column '{name}' holds loading/unloading in every row, but the passes are "
            f"read from a column named '{PHASE_COLUMN}'; rename it '{PHASE_COLUMN}' (or the "
            "rows' order, rising then falling, decides the passes)"
        )


def _with(frame: Frame, **changes: object) -> Frame:
    return Frame(**{**frame.__dict__, **changes})  # type: ignore[arg-type]


def _step_labels(frames: list[Frame], tolerance_kpa: float) -> np.ndarray:
    """:func:`~contactcal.infer.pipeline.readings.step_labels` of the frames' readings; every
    distinct value its own step in a sweep whose top is below :data:`MIN_SWEEP_TOP_KPA` (bar
    or MPa read as kPa: its steps would merge into one, and :func:`check_sweep_unit` names its
    unit instead)."""
    readings = [f.pressure_kpa for f in frames]
    bar = 0.0 < max(readings, default=0.0) < MIN_SWEEP_TOP_KPA
    return step_labels(readings, 0.0 if bar else tolerance_kpa)


def _pool_readings(
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
            reading = (READING_COLUMN, repr(frames[k].pressure_kpa))
            out[k] = _with(frames[k], pressure_kpa=level, extras=(*frames[k].extras, reading))
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
        labels = _step_labels([frames[k] for k in idx], tolerance_kpa)
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


def _number_steps(where: str, frames: list[Frame], hint: str = "") -> list[Frame]:
    """Sort by phase, pressure and row; number each phase's steps; >= 2 steps per phase."""
    out: list[Frame] = []
    for phase in PHASES:
        mine = sorted(
            (f for f in frames if f.phase == phase), key=lambda f: (f.pressure_kpa, f.row)
        )
        levels = sorted({f.pressure_kpa for f in mine})
        if phase == LOADING and not mine:
            raise ManifestError(
                f"{where}: no loading frame; expected a loading pass (its lowest-pressure frame "
                "is the session's reference): mark its rows 'loading'"
            )
        if mine and len(levels) < 2:
            raise ManifestError(
                f"{where}: the {phase} pass has {len(mine)} frame(s) at {len(levels)} pressure; "
                f"a calibration needs >= 2 pressure steps per pass (including the 0 kPa "
                f"reference); rows {', '.join(str(f.row) for f in mine[:_MAX_LISTED])}; give "
                f"each row its pass in a 'phase' column (loading/unloading){hint}"
            )
        out += [_with(f, step=levels.index(f.pressure_kpa)) for f in mine]
    return out


def _check_files(where: str, frames: list[Frame], base: Path) -> None:
    """Reject missing image files and one image on two rows."""
    missing = [f for f in sorted(frames, key=lambda f: f.row) if not f.file.is_file()]
    if missing:
        listed = "; ".join(
            f"row {f.row}: {f.file}{' (a folder)' if f.file.is_dir() else ''}"
            for f in missing[:_MAX_LISTED]
        )
        more = f"; and {len(missing) - _MAX_LISTED} more" if len(missing) > _MAX_LISTED else ""
        windows = any("\\" in str(f.file) for f in missing) and os.sep != "\\"
        hint = " (written with '\\' as on Windows? use '/' between folders)" if windows else ""
        raise ManifestError(
            f"{where}: {len(missing)} image file(s) not found: {listed}{more}; relative paths "
            f"are resolved against the manifest's folder {base}{hint}"
        )
    _check_distinct_files(where, frames)


def _check_distinct_files(where: str, frames: list[Frame]) -> None:
    """Reject one image on two rows (same file after resolving links, or a hard link to it)."""
    seen: dict[tuple[int, int], Frame] = {}
    for f in sorted(frames, key=lambda f: f.row):
        st = f.file.stat()
        first = seen.setdefault((st.st_dev, st.st_ino), f)
        if first is not f:
            raise ManifestError(
                f"{where}: rows {first.row} ({first.file}) and {f.row} ({f.file}) are the same "
                "image file; expected each image on one row (a step may hold several images): list "
                "each frame once"
            )

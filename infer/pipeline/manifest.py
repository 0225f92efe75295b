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

from contactcal.infer.calibration.phases import (
    FROM_COLUMN,
    LOADING,
    PHASES,
    SINGLE_PASS,
    misplaced_rows,
    order_slack,
    parse_phase,
    phases_from_order,
)
from contactcal.infer.pipeline.manifest_files import MAX_LISTED, check_files
from contactcal.infer.pipeline.manifest_rows import (
    GAUGE_ZERO_NOISE_KPA,
    HEADER,
    HIGH_SWEEP_TOP_KPA,
    MAX_PRESSURE_KPA,
    MIN_SWEEP_TOP_KPA,
    PHASE_COLUMN,
    REQUIRED_COLUMNS,
    Frame,
    ManifestError,
    check_header,
    check_sweep_top,
    manifest_folder,
    parse_row,
    read_rows,
    sweep_top_warning,
    with_changes,
)
from contactcal.infer.pipeline.manifest_steps import (
    READING_COLUMN,
    frame_step_labels,
    pool_readings,
)
from contactcal.infer.pipeline.readings import (
    DEFAULT_STEP_TOLERANCE_KPA,
    AtRest,
    Pooled,
    pooled_pressures,
)

__all__ = [
    "GAUGE_ZERO_NOISE_KPA",
    "HIGH_SWEEP_TOP_KPA",
    "MAX_PRESSURE_KPA",
    "MIN_SWEEP_TOP_KPA",
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
    "reference_width",
    "sweep_top_warning",
]


@dataclass(frozen=True)
class Session:
    """A read manifest: its frames, how their phases were determined, its content's digest."""

    frames: list[Frame]  # sorted by phase (loading first), pressure, row; [0] is the reference
    phase_source: str  # phases.FROM_COLUMN, FROM_ORDER or SINGLE_PASS
    sha256: str  # of the manifest's content as read once and parsed (the record's digest)
    #: the folder its relative frame paths were joined to (manifest_folder, resolved once):
    #: records name the frames relative to it (manifest_rows.listed_name)
    folder: Path
    pooled: Pooled | None = None  # steps pooled from differing readings (readings.py); None: none
    at_rest: AtRest | None = None  # steps read below 0 kPa, given as 0; None: none
    #: rows that broke an otherwise rising (then falling) order, read as one pass (a typo?):
    #: "row 7 (p06.0kpa.jpg, 16 kPa)"; empty: none, or rows in no particular order
    out_of_order: tuple[str, ...] = ()


def check_sweep_unit(where: str | os.PathLike[str], frames: Sequence[Frame]) -> None:
    """Refuse a session whose pressures all lie below :data:`MIN_SWEEP_TOP_KPA` (and not all
    0: those get the "no contact" answer): the calibration would read bar or MPa as kPa.

    Raises:
        ManifestError: naming the manifest, its highest pressure and the units it may be in.
    """
    check_sweep_top(where, max((f.pressure_kpa for f in frames), default=0.0))


def beside_manifest(path: str | os.PathLike[str], name: str = "rig.json") -> Path:
    """The file ``name`` in the folder the manifest's frame paths are resolved against: the
    manifest file's own folder, a link's target's (so a linked manifest finds the ``rig.json``
    of its frames, not of the link's folder)."""
    return manifest_folder(path) / name


def reference_width(session: Session, bit_depth: int | None) -> int:
    """Width (px) of the reference frame of ``session`` (the manifest as the run read it, not
    read again), which its frames share (a run refuses others), as
    :func:`~contactcal.infer.image.read.source_size` reads it: a JPEG's from its header alone
    (the file is not read whole), another format's (or a JPEG whose header does not state it)
    decoded.

    Raises:
        ImageError: as a run reading that frame would (a JPEG's image data is left to the run).
    """
    from contactcal.infer.image.read import source_size

    return source_size(session.frames[0].file, bit_depth)[0]


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
    rows, sha256 = read_rows(mpath)
    folder = manifest_folder(mpath)
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
        parse_row(where, folder, names, row_no, line_no, cells)
        for row_no, (line_no, cells) in enumerate(data, start=1)
    ]
    source, out_of_order = FROM_COLUMN, ()
    if PHASE_COLUMN not in names:  # the passes from the steps' order (readings jitter)
        _check_phase_elsewhere(where, names, frames)
        labels = frame_step_labels(frames, step_tolerance_kpa)
        # A step below 0 kPa is given as 0 (_pool_readings): a rest reading of -0.3 between
        # 0 and 0.5 kPa steps is no reversal of the passes.
        levels = [max(v, 0.0) for v in pooled_pressures([f.pressure_kpa for f in frames], labels)]
        phases, source = phases_from_order(levels, order_slack(levels))
        out_of_order = _out_of_order(frames, levels) if source == SINGLE_PASS else ()
        frames = [with_changes(f, phase=ph) for f, ph in zip(frames, phases, strict=True)]
    frames, pooled, at_rest = pool_readings(where, names, frames, step_tolerance_kpa)
    merged = f"readings less than {step_tolerance_kpa:g} kPa apart are one step"
    hint = "" if pooled is None else f" ({merged}: --step-tolerance-kpa)"
    frames = _number_steps(where, frames, hint)
    check_files(where, frames, folder)
    return Session(frames, source, sha256, folder, pooled, at_rest, out_of_order)


#: At most this many rows, and this share of the rows, may break the order for them to be named
#: as misplaced (more: rows in no particular order, a legitimate single pass).
MISPLACED_MAX_ROWS = 2
MISPLACED_MAX_SHARE = 0.2


def _out_of_order(frames: list[Frame], levels: list[float]) -> tuple[str, ...]:
    """The rows (``"row 7 (p06.0kpa.jpg, 16 kPa)"``) without which a manifest read as one pass
    would rise, then fall, when they are few (at most :data:`MISPLACED_MAX_ROWS`, and
    :data:`MISPLACED_MAX_SHARE` of the rows): a mistyped pressure, or a frame listed in the
    wrong place. Empty otherwise."""
    rows = misplaced_rows(levels)
    if not rows or len(rows) > min(MISPLACED_MAX_ROWS, MISPLACED_MAX_SHARE * len(levels)):
        return ()
    return tuple(
        f"row {i + 1} ({frames[i].file.name}, {frames[i].pressure_kpa:g} kPa)" for i in rows
    )


def _check_phase_elsewhere(where: str, names: list[str], frames: list[Frame]) -> None:
    """Refuse a column of another name that holds only passes (``phases``, ``pass``): read
    from the row order instead, the passes it states would be lost without a word."""
    for name in names:
        cells = [str(dict(f.extras).get(name, "")) for f in frames]
        if name in REQUIRED_COLUMNS or not all(parse_phase(c) for c in cells):
            continue
        raise ManifestError(
            f"{where}: column '{name}' holds loading/unloading in every row, but the passes are "
            f"read from a column named '{PHASE_COLUMN}'; rename it '{PHASE_COLUMN}' (or the "
            "rows' order, rising then falling, decides the passes)"
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
                f"reference); rows {', '.join(str(f.row) for f in mine[:MAX_LISTED])}; give "
                f"each row its pass in a 'phase' column (loading/unloading){hint}"
            )
        out += [with_changes(f, step=levels.index(f.pressure_kpa)) for f in mine]
    return out

"""A session manifest's text → :class:`Frame` rows: the header, the cells, the pressures.

The format and what :func:`~contactcal.infer.pipeline.manifest.read_session` makes of the rows
(phases, steps, files): :mod:`contactcal.infer.pipeline.manifest`.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path

from contactcal.infer.calibration.phases import LOADING, PHASES, parse_phase
from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.files.regular import read_input_bytes

REQUIRED_COLUMNS: tuple[str, ...] = ("file", "pressure_kpa")
PHASE_COLUMN = "phase"
KNOWN_COLUMNS = (*REQUIRED_COLUMNS, PHASE_COLUMN)
#: The extra a frame gets when its reading is read as its step's pressure: the reading, a
#: number of kPa (a manifest's own column of this name is read as one too).
READING_COLUMN = "pressure_kpa_read"
HEADER = ",".join(REQUIRED_COLUMNS)
#: Highest plausible chamber gauge pressure, kPa. The display works at 0-20 kPa; 100 kPa (1 bar
#: above the atmosphere on a 70 µm membrane) is five times that, so a larger value is a unit slip
#: or a typo, not a calibration step: mbar for kPa turns a 0-20 kPa sweep's top into 200, Pa into
#: 20000. (A 0-10 kPa sweep in mbar tops out at the bound itself and passes: no bound tells it
#: from a 100 kPa display.)
MAX_PRESSURE_KPA = 100.0
#: kPa below 0 still accepted as a reading. A gauge at rest reads its noise and offset (typically
#: ±0.05 kPa); 0.5 kPa of suction is no calibration state but a sign error or a bad zero. A step
#: whose pressure comes out below 0 is given as 0 kPa (``read_session``; a video's step alike).
GAUGE_ZERO_NOISE_KPA = 0.5


class ManifestError(ValueError):
    """A session manifest is missing or malformed; the message names the file and the row."""


@dataclass(frozen=True)
class Frame:
    """One manifest row.

    Attributes:
        file: the image's absolute path as the manifest lists it: a relative entry joined to
            the folder the manifest's paths are resolved against (:func:`manifest_folder`),
            nothing resolved past that folder, so a frame that is a symbolic link keeps its
            own name (its content is read through it).
        pressure_kpa: chamber gauge pressure, kPa, >= -:data:`GAUGE_ZERO_NOISE_KPA` as read
            (``read_session`` gives a step below 0 as 0 kPa).
        row: 1-based data row number in the manifest (header and blank lines not counted).
        phase: ``"loading"`` or ``"unloading"``.
        step: 0-based index of the frame's pressure step within its phase (ascending pressure).
        extras: the row's other columns as ``(name, cell)`` pairs, in header order; the cell
            of :data:`READING_COLUMN` is a number of kPa (None: blank).
    """

    file: Path
    pressure_kpa: float
    row: int
    phase: str = LOADING
    step: int = 0
    extras: tuple[tuple[str, str | float | None], ...] = ()


def read_rows(mpath: Path) -> tuple[list[tuple[int, list[str]]], str]:
    """Non-blank CSV rows as ``(line number, cells)``, and the sha256 of the content parsed
    (read once: a record's digest is that of the rows the run used)."""
    try:
        data = read_input_bytes(
            mpath, "the manifest CSV file (e.g. session/manifest.csv)", ManifestError
        )
        reader = csv.reader(io.StringIO(data.decode("utf-8-sig"), newline=""))
        rows = [(reader.line_num, cells) for cells in reader if any(c.strip() for c in cells)]
    except FileNotFoundError:
        raise ManifestError(
            f"{mpath}: manifest not found; expected a CSV file '{HEADER}' listing the "
            "session's images (check the path)"
        ) from None
    except OSError as exc:
        raise ManifestError(
            f"{mpath}: cannot read the manifest ({exc.strerror or exc}); "
            "check the file's permissions"
        ) from None
    except UnicodeDecodeError as exc:
        raise ManifestError(
            f"{mpath}: not UTF-8 text ({exc.reason} at byte {exc.start}); "
            "save the manifest as a UTF-8 CSV"
        ) from None
    except csv.Error as exc:
        raise ManifestError(f"{mpath}: malformed CSV ({exc}); expected '{HEADER}' rows") from None
    return rows, sha256_bytes(data)


def check_header(where: str, line_no: int, header: list[str]) -> list[str]:
    """The stripped column names; required columns present, no name twice or empty."""
    names = [h.strip() for h in header]
    at = f"{where}: header (line {line_no})"
    hint = ""
    if len(names) == 1 and any(sep in names[0] for sep in (";", "\t")):
        hint = "; the manifest must be comma-separated"
    if "" in names:
        raise ManifestError(
            f"{at}: column {names.index('') + 1} has no name; an empty column or a trailing "
            "separator (as a spreadsheet may write): delete it, or name the column"
        )
    dups = sorted({n for n in names if names.count(n) > 1})
    if dups:
        raise ManifestError(
            f"{at}: column(s) {dups} appear twice; expected each column once (required: '{HEADER}')"
        )
    for name in names:
        near = [k for k in KNOWN_COLUMNS if k.lower() == name.lower() and k != name]
        if near:
            raise ManifestError(
                f"{at}: column '{name}' (did you mean '{near[0]}'? names are case-sensitive); "
                f"expected the columns {list(REQUIRED_COLUMNS)}, optionally '{PHASE_COLUMN}' and "
                f"other named columns{hint}"
            )
    for name in REQUIRED_COLUMNS:
        if name not in names:
            raise ManifestError(
                f"{at}: missing required column '{name}'; the header must name '{HEADER}' "
                f"(other columns are kept), got {','.join(names)!r}{hint}"
            )
    return names


def _parse_pressure(at: str, cell: str) -> float:
    try:
        value = float(cell) + 0.0  # "-0" reads as 0.0
    except ValueError:
        raise ManifestError(
            f"{at}: pressure_kpa {cell!r} is not a number; expected the gauge pressure in kPa, "
            "e.g. 4.0 (decimal point, no unit)"
        ) from None
    if not math.isfinite(value):
        raise ManifestError(f"{at}: pressure_kpa {cell!r} is not finite; expected a number of kPa")
    if value < -GAUGE_ZERO_NOISE_KPA:
        raise ManifestError(
            f"{at}: pressure_kpa {value:g} is below -{GAUGE_ZERO_NOISE_KPA:g} kPa; expected a "
            f"gauge pressure >= 0 kPa (a gauge at rest may read down to -{GAUGE_ZERO_NOISE_KPA:g}, "
            "its offset; more suction than that is a sign error or a bad zero: check the gauge)"
        )
    if value > MAX_PRESSURE_KPA:
        raise ManifestError(
            f"{at}: pressure_kpa {cell.strip()} is above the plausible {MAX_PRESSURE_KPA:g} kPa "
            "(the display works at 0-20 kPa); expected kPa, not mbar, Pa or another unit"
        )
    return value


def manifest_folder(manifest: str | os.PathLike[str]) -> Path:
    """The folder a manifest's relative frame paths are resolved against: the manifest file's
    own folder, resolved (a linked manifest's or folder's target), once per manifest read."""
    return Path(manifest).resolve().parent


def parse_row(
    where: str, folder: Path, names: list[str], row_no: int, line_no: int, cells: list[str]
) -> Frame:
    """One data row → a :class:`Frame` (a relative path joined to ``folder``, the
    :func:`manifest_folder`)."""
    at = f"{where}: row {row_no} (line {line_no})"
    if len(cells) != len(names):
        raise ManifestError(
            f"{at}: expected {len(names)} cells ({','.join(names)}), got {len(cells)}: "
            f"{cells!r}; quote cells that contain commas"
        )
    row = dict(zip(names, (c.strip() for c in cells), strict=True))
    if not row["file"]:
        raise ManifestError(
            f"{at}: empty 'file' cell; expected an image path relative to the manifest's folder"
        )
    pressure = _parse_pressure(at, row["pressure_kpa"])
    phase = LOADING
    if PHASE_COLUMN in row:
        parsed = parse_phase(row[PHASE_COLUMN])
        if parsed is None:
            raise ManifestError(
                f"{at}: phase {row[PHASE_COLUMN]!r}; expected one of {', '.join(PHASES)} "
                "(case-insensitive)"
            )
        phase = parsed
    file = folder / Path(row["file"]).expanduser()  # an absolute entry stays as it is
    extras = tuple(_extra(at, n, row[n]) for n in names if n not in KNOWN_COLUMNS)
    return Frame(file, pressure, row_no, phase, 0, extras)


def listed_name(folder: Path, file: str | os.PathLike[str]) -> str:
    """A frame's name in a record: as the manifest lists it, its :attr:`Frame.file` relative
    to ``folder``, the :func:`manifest_folder` its paths were joined to
    (:attr:`~contactcal.infer.pipeline.manifest.Session.folder`). A manifest reached through a
    linked folder, and a frame that is itself a link, name it as listed (``p00.0kpa.jpg``, not
    ``../real/p00.0kpa.jpg``); an absolute entry elsewhere, relative to ``folder``."""
    try:
        return str(Path(file).relative_to(folder))  # the entry, spelled as listed (".." kept)
    except ValueError:
        return os.path.relpath(file, folder)


def _extra(at: str, name: str, cell: str) -> tuple[str, str | float | None]:
    """A row's other column: :data:`READING_COLUMN` as a number of kPa (None where the cell is
    blank: a frame without a reading), any other as written."""
    if name != READING_COLUMN:
        return name, cell
    if not cell.strip():
        return name, None
    try:
        value = float(cell) + 0.0
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ManifestError(
            f"{at}: {READING_COLUMN} {cell!r} is not a number; expected the gauge reading in "
            "kPa, e.g. 4.02 (decimal point, no unit)"
        )
    return name, value


def with_changes(frame: Frame, **changes: object) -> Frame:
    """``frame`` with some fields changed."""
    return Frame(**{**frame.__dict__, **changes})  # type: ignore[arg-type]


#: kPa: a session whose highest pressure is below this cannot be a calibration sweep of the
#: display (contact starts at ~3 kPa): its pressures are in another unit (bar: 20 kPa is 0.2;
#: MPa: 0.02), refused by :func:`check_sweep_top`.
MIN_SWEEP_TOP_KPA = 1.0


def check_sweep_top(where: str | os.PathLike[str], top: float) -> None:
    """Refuse a sweep whose highest pressure ``top`` (kPa as read) is below
    :data:`MIN_SWEEP_TOP_KPA` (bar or MPa read as kPa), from the file ``where`` (a manifest,
    or a video run's pressure log).

    Raises:
        ManifestError: naming ``where``, ``top`` and the units it may be in.
    """
    if 0.0 < top < MIN_SWEEP_TOP_KPA:
        raise ManifestError(
            f"{where}: the highest pressure_kpa is {top:g}, below {MIN_SWEEP_TOP_KPA:g} kPa; "
            "expected a sweep in kPa (the display works at 0-20 kPa, contact from ~3 kPa), "
            "not bar or MPa"
        )


#: kPa: a sweep whose highest pressure is above this is read, with a warning: the display works at
#: 0-20 kPa, so a top of 30-100 kPa is more likely mbar read as kPa (a 0-10 kPa sweep in mbar
#: tops out at 100) than a display calibrated that high; below :data:`MAX_PRESSURE_KPA` no bound
#: can tell them apart, so it is said, not refused.
HIGH_SWEEP_TOP_KPA = 30.0


def sweep_top_warning(top: float, command: str = "calibrate") -> str | None:
    """The warning line of a sweep whose highest pressure ``top`` (kPa as read) is above
    :data:`HIGH_SWEEP_TOP_KPA`, advising to run ``command`` again in kPa; None below it."""
    if top <= HIGH_SWEEP_TOP_KPA:
        return None
    return (
        f"warning: the highest pressure is {top:g} kPa, far above the display's 0-20 kPa: if the "
        f"pressures are in mbar (or another unit), convert them to kPa and run {command} again"
    )

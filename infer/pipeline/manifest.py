"""Session manifest: which image was taken at which pressure.

Format: a UTF-8 CSV (a byte-order mark is tolerated) whose header is exactly ``file,pressure_kpa``
(whitespace around the names is tolerated), then one row per frame::

    file,pressure_kpa
    p00.0kpa.png,0.0
    p02.0kpa.png,2.0

``file`` is an image path, relative to the manifest's folder or absolute, each image on one row
only; ``pressure_kpa`` is the chamber gauge pressure in kPa (0 to :data:`MAX_PRESSURE_KPA`), one
frame per pressure step. Blank lines are skipped.
Rows may be in any order: `read_manifest` returns the frames sorted by pressure, and the
lowest-pressure frame is the session's reference frame (normally 0 kPa, membrane at rest, no
contact).
"""

from __future__ import annotations

import csv
import itertools
import math
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["EXPECTED_COLUMNS", "MAX_PRESSURE_KPA", "Frame", "ManifestError", "read_manifest"]

EXPECTED_COLUMNS: tuple[str, ...] = ("file", "pressure_kpa")
_HEADER = ",".join(EXPECTED_COLUMNS)
_MAX_LISTED = 5
#: Highest plausible chamber gauge pressure, kPa. The display works at 0-20 kPa; 200 kPa is ten
#: times that, so a larger value is a unit slip (Pa for kPa) or a typo, not a calibration step.
#: (Negative gauge pressure, suction, is no calibration step either: the lower bound is 0.)
MAX_PRESSURE_KPA = 200.0


class ManifestError(ValueError):
    """A session manifest is missing or malformed; the message names the file and the row."""


@dataclass(frozen=True)
class Frame:
    """One manifest row.

    Attributes:
        file: absolute image path (relative paths are resolved against the manifest's folder).
        pressure_kpa: chamber gauge pressure, kPa, >= 0.
        row: 1-based data row number in the manifest (header and blank lines not counted).
    """

    file: Path
    pressure_kpa: float
    row: int


def read_manifest(path: str | os.PathLike[str]) -> list[Frame]:
    """Read and validate a session manifest.

    Args:
        path: the manifest CSV.

    Returns:
        The frames sorted by pressure (ascending); ``frames[0]`` is the reference frame.

    Raises:
        ManifestError: with the manifest path, the row, what was expected and how to fix it.
    """
    mpath = Path(path)
    where = str(mpath)
    rows = _read_rows(mpath)
    if not rows:
        raise ManifestError(
            f"{where}: the manifest is empty; expected a header line '{_HEADER}' "
            "followed by one 'image,pressure' row per frame"
        )
    header_line, header = rows[0]
    _check_header(where, header_line, header)
    col = {name: i for i, name in enumerate(h.strip() for h in header)}
    data = rows[1:]
    if not data:
        raise ManifestError(
            f"{where}: the manifest has a header but no frames; add one row "
            "'image,pressure_kpa' per frame (a calibration needs >= 2 pressure steps)"
        )

    frames = [
        _parse_row(where, mpath, col, row_no, line_no, cells, len(header))
        for row_no, (line_no, cells) in enumerate(data, start=1)
    ]
    _check_frames(where, frames, mpath.resolve().parent)
    return frames


def _read_rows(mpath: Path) -> list[tuple[int, list[str]]]:
    """Non-blank CSV rows as ``(line number, cells)``."""
    try:
        with open(mpath, encoding="utf-8-sig", newline="") as fh:
            reader = csv.reader(fh)
            rows = []
            for cells in reader:
                if any(c.strip() for c in cells):
                    rows.append((reader.line_num, cells))
    except FileNotFoundError:
        raise ManifestError(
            f"{mpath}: manifest not found; expected a CSV file '{_HEADER}' listing the "
            "session's images (check the path)"
        ) from None
    except IsADirectoryError:
        raise ManifestError(
            f"{mpath}: is a folder; expected the manifest CSV file inside it (e.g. manifest.csv)"
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
        raise ManifestError(f"{mpath}: malformed CSV ({exc}); expected '{_HEADER}' rows") from None
    return rows


def _check_header(where: str, line_no: int, header: list[str]) -> None:
    names = [h.strip() for h in header]
    at = f"{where}: header (line {line_no})"
    hint = ""
    if len(names) == 1 and any(sep in names[0] for sep in (";", "\t")):
        hint = "; the manifest must be comma-separated"
    dups = sorted({n for n in names if names.count(n) > 1})
    if dups:
        raise ManifestError(f"{at}: column(s) {dups} appear twice; expected exactly '{_HEADER}'")
    for name in names:
        if name not in EXPECTED_COLUMNS:
            near = [e for e in EXPECTED_COLUMNS if e.lower() == name.lower()]
            did = f" (did you mean '{near[0]}'? names are case-sensitive)" if near else ""
            raise ManifestError(
                f"{at}: unknown column '{name}'{did}; expected exactly the columns "
                f"{list(EXPECTED_COLUMNS)} ('{_HEADER}'){hint}"
            )
    for name in EXPECTED_COLUMNS:
        if name not in names:
            raise ManifestError(
                f"{at}: missing required column '{name}'; the header must be '{_HEADER}', got "
                f"{','.join(names)!r}{hint}"
            )


def _parse_pressure(at: str, cell: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise ManifestError(
            f"{at}: pressure_kpa {cell!r} is not a number; expected the gauge pressure in kPa, "
            "e.g. 4.0 (decimal point, no unit)"
        ) from None
    if not math.isfinite(value):
        raise ManifestError(f"{at}: pressure_kpa {cell!r} is not finite; expected a number of kPa")
    if value < 0:
        raise ManifestError(
            f"{at}: pressure_kpa {value:g} is negative; expected a gauge pressure >= 0 kPa"
        )
    if value > MAX_PRESSURE_KPA:
        raise ManifestError(
            f"{at}: pressure_kpa {value:g} is above the plausible {MAX_PRESSURE_KPA:g} kPa "
            "(the display works at 0-20 kPa); expected kPa, not Pa or another unit"
        )
    return value


def _parse_row(
    where: str,
    mpath: Path,
    col: dict[str, int],
    row_no: int,
    line_no: int,
    cells: list[str],
    n_cols: int,
) -> Frame:
    """One data row → a :class:`Frame` (path resolved against the manifest's folder)."""
    at = f"{where}: row {row_no} (line {line_no})"
    if len(cells) != n_cols:
        raise ManifestError(
            f"{at}: expected {n_cols} cells ({_HEADER}), got {len(cells)}: {cells!r}; "
            "quote file names that contain commas"
        )
    file_cell = cells[col["file"]].strip()
    p_cell = cells[col["pressure_kpa"]].strip()
    if not file_cell:
        raise ManifestError(
            f"{at}: empty 'file' cell; expected an image path relative to the manifest's folder"
        )
    pressure = _parse_pressure(at, p_cell)
    file = Path(file_cell).expanduser()
    if not file.is_absolute():
        file = mpath.resolve().parent / file
    return Frame(file=file.resolve(), pressure_kpa=pressure, row=row_no)


def _check_frames(where: str, frames: list[Frame], base: Path) -> None:
    """Sort by pressure in place; reject repeated pressures or files, < 2 frames, missing files."""
    frames.sort(key=lambda f: f.pressure_kpa)
    for a, b in itertools.pairwise(frames):
        if a.pressure_kpa == b.pressure_kpa:
            first, second = sorted((a, b), key=lambda f: f.row)
            raise ManifestError(
                f"{where}: rows {first.row} ({first.file.name}) and {second.row} "
                f"({second.file.name}) have the same pressure {a.pressure_kpa:g} kPa; expected "
                "one frame per pressure step: remove one row or correct its pressure"
            )
    if len(frames) < 2:
        raise ManifestError(
            f"{where}: only {len(frames)} frame; a calibration needs >= 2 "
            "pressure steps (including the 0 kPa reference)"
        )
    missing = [f for f in sorted(frames, key=lambda f: f.row) if not f.file.is_file()]
    if missing:
        listed = "; ".join(f"row {f.row}: {f.file}" for f in missing[:_MAX_LISTED])
        more = f"; and {len(missing) - _MAX_LISTED} more" if len(missing) > _MAX_LISTED else ""
        raise ManifestError(
            f"{where}: {len(missing)} image file(s) not found: {listed}{more}; relative paths "
            f"are resolved against the manifest's folder {base}"
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
                "image file; expected one image per pressure step: list each frame once"
            )

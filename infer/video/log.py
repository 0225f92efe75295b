"""The pressure controller's log: when the chamber was at which pressure.

Format: a UTF-8 CSV whose header holds the columns ``time_s`` and ``pressure_kpa`` (other columns,
e.g. the controller's set-point, are allowed and not read), then one row per sample::

    time_s,pressure_kpa
    0.00,0.01
    0.05,-0.02

``time_s`` is seconds since the video's first frame (strictly increasing; samples before the
first frame may be negative); ``pressure_kpa`` the chamber gauge pressure in kPa, finite, from
``-GAUGE_ZERO_NOISE_KPA`` (a gauge reads slightly below 0 at rest) to the manifest's
:data:`~contactcal.infer.pipeline.manifest.MAX_PRESSURE_KPA`.

A log still being written (live capture) may end in a partial line: :func:`read_pressure_log` with
``complete=False`` ignores a last line without its newline. The log read records the sha256 of
the bytes it parsed (:attr:`PressureLog.sha256`, recorded in ``calibration.json``).
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.files.regular import read_input_bytes
from contactcal.infer.pipeline.manifest import GAUGE_ZERO_NOISE_KPA, MAX_PRESSURE_KPA

#: The columns a pressure log must have.
LOG_COLUMNS = ("time_s", "pressure_kpa")


class PressureLogError(ValueError):
    """A pressure log that cannot be used; the message names the file and the row."""


@dataclass(frozen=True)
class PressureLog:
    """A pressure log's samples.

    Attributes:
        path: the log file (for messages).
        times_s: ``(N,) float64`` sample times, s since the video's first frame, increasing.
        pressures_kpa: ``(N,) float64`` chamber gauge pressures, kPa.
        sha256: of the bytes parsed (:func:`read_pressure_log`; None: parsed from text, not a file).
    """

    path: Path
    times_s: np.ndarray
    pressures_kpa: np.ndarray
    sha256: str | None = None


def read_log_bytes(path: str | os.PathLike[str]) -> bytes:
    """The log file's bytes, with one clear error for a missing or unreadable file, or one that
    is not a regular file (a device or pipe, never read: it could be read or waited on forever)."""
    p = Path(path)
    try:
        return read_input_bytes(p, "the pressure log CSV file", PressureLogError)
    except FileNotFoundError:
        raise PressureLogError(
            f"{p}: pressure log not found; expected the controller's CSV "
            f"'{','.join(LOG_COLUMNS)}' (check the path)"
        ) from None
    except OSError as exc:
        raise PressureLogError(f"{p}: cannot read the pressure log ({exc.strerror})") from None


def read_pressure_log(path: str | os.PathLike[str], complete: bool = True) -> PressureLog:
    """Read the log file once, parse and validate it (see the module docstring), with the sha256
    of the bytes parsed.

    Args:
        path: the log file.
        complete: False for a log still being written: a last line without newline is left
            out (neither parsed nor hashed).

    Raises:
        PressureLogError: naming the file (and row), saying what was expected.
    """
    p = Path(path)
    data = read_log_bytes(p)
    if not complete:
        data = data[: data.rfind(b"\n") + 1]
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise PressureLogError(
            f"{p}: not UTF-8 text ({exc.reason} at byte {exc.start}); expected a CSV file"
        ) from None
    return replace(parse_log(text, p, complete), sha256=sha256_bytes(data))


def _header(where: Path, rows: list[list[str]]) -> dict[str, int]:
    if not rows:
        raise PressureLogError(
            f"{where}: the pressure log is empty; expected a header '{','.join(LOG_COLUMNS)}'"
        )
    names = [c.strip() for c in rows[0]]
    missing = [c for c in LOG_COLUMNS if c not in names]
    if missing:
        raise PressureLogError(
            f"{where}: header {','.join(names)!r} lacks column(s) {missing}; expected the "
            f"columns {list(LOG_COLUMNS)} (seconds since the video's first frame, kPa)"
        )
    return {c: names.index(c) for c in LOG_COLUMNS}


def _value(where: Path, row: int, name: str, cell: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise PressureLogError(
            f"{where}: row {row}: {name} {cell.strip()!r} is not a finite number; expected "
            f"{'seconds' if name == 'time_s' else 'kPa'} as a plain number (e.g. 1.25)"
        )
    return value


def parse_log(text: str, where: Path, complete: bool = True) -> PressureLog:
    """Parse and validate a pressure log's text.

    Args:
        text: the CSV text.
        where: the file, named in errors.
        complete: False for a log still being written: no samples yet is no error (a reader
            leaves its partial last line out first: :func:`read_pressure_log`).

    Returns:
        The :class:`PressureLog` (possibly with no samples when ``complete`` is False).

    Raises:
        PressureLogError: missing column, non-finite or implausible value, times not strictly
            increasing, or (complete log) no samples; the message names the file and row.
    """
    rows = [r for r in csv.reader(io.StringIO(text)) if any(c.strip() for c in r)]
    if not rows and not complete:
        return PressureLog(where, np.zeros(0), np.zeros(0))
    col = _header(where, rows)
    times, pressures = [], []
    for row, cells in enumerate(rows[1:], start=1):
        if len(cells) <= max(col.values()):
            raise PressureLogError(
                f"{where}: row {row}: expected {len(rows[0])} cells, got {len(cells)}: {cells!r}"
            )
        t = _value(where, row, "time_s", cells[col["time_s"]])
        p = _value(where, row, "pressure_kpa", cells[col["pressure_kpa"]])
        if not -GAUGE_ZERO_NOISE_KPA <= p <= MAX_PRESSURE_KPA:
            raise PressureLogError(
                f"{where}: row {row}: pressure_kpa {cells[col['pressure_kpa']].strip()} is "
                "outside the plausible "
                f"-{GAUGE_ZERO_NOISE_KPA:g} to {MAX_PRESSURE_KPA:g} kPa (the display works at "
                "0-20 kPa); expected the gauge pressure in kPa"
            )
        if times and t <= times[-1]:
            raise PressureLogError(
                f"{where}: row {row}: time_s {t:g} is not after the previous row's "
                f"{times[-1]:g}; expected strictly increasing times (sort the log by time)"
            )
        times.append(t)
        pressures.append(p)
    if complete and not times:
        raise PressureLogError(f"{where}: the pressure log has a header but no samples")
    return PressureLog(where, np.asarray(times, float), np.asarray(pressures, float))

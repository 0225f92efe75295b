"""Reading a rendered dataset folder (``index.csv``, docs/CONVENTIONS.md): the one reader used by
``contactcal bench`` and by training.
"""

from __future__ import annotations

import csv
import functools
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from contactcal.infer.errors import option_error
from contactcal.infer.files.regular import read_input_bytes, refuse_special

#: Columns every dataset row must have.
REQUIRED_COLUMNS = (
    "finger",
    "session",
    "frame",
    "mask",
    "pressure_kpa",
    "contact",
    "area_px",
    "mm_per_px",
    "onset_kpa",
    "hard",
)


@dataclass(frozen=True)
class IndexRow:
    """One frame of a dataset, paths resolved."""

    dataset: Path  # the dataset folder
    finger: int  # finger number (one finger = one session, one fingerprint texture)
    session: str  # session folder name
    frame: Path  # (H, W, 3) uint8 RGB frame
    mask: Path  # (H, W) uint8 exact contact mask, 255 = contact
    pressure_kpa: float  # kPa
    contact: bool  # truth: the mask is not empty
    area_px: float  # px, truth (mask pixel count)
    mm_per_px: float  # mm/px at the contact plane
    onset_kpa: float  # kPa, the mechanics' contact onset
    hard: bool  # drawn from the hard (extreme) ranges

    @functools.cached_property
    def finger_key(self) -> str:
        """``"<dataset folder, resolved>#<finger>"``: unique across datasets, and the same under
        any spelling of the folder (the key of training's split by finger, which runs record)."""
        return f"{self.dataset.resolve()}#{self.finger}"

    @property
    def session_key(self) -> str:
        """``"<dataset folder>#<session folder>"``: unique across datasets."""
        return f"{self.dataset}#{self.session}"


def spread(n: int, k: int) -> list[int]:
    """``min(k, n)`` distinct indices into ``n`` items, evenly spaced, first and last included."""
    if n < 1 or k < 1:
        return []
    return sorted(set(np.linspace(0, n - 1, min(k, n)).round().astype(int).tolist()))


def _parse(folder: Path, line: int, r: dict[str, str | None]) -> IndexRow:
    where = f"{folder / 'index.csv'} line {line}"
    if empty := [c for c in REQUIRED_COLUMNS if not r.get(c)]:  # a short row: None cells
        raise ValueError(f"{where}: no value in column(s) {', '.join(empty)}")
    try:
        row = IndexRow(
            dataset=folder,
            finger=int(float(r["finger"])),
            session=r["session"],
            frame=folder / r["frame"],
            mask=folder / r["mask"],
            pressure_kpa=float(r["pressure_kpa"]),
            contact=bool(int(float(r["contact"]))),
            area_px=float(r["area_px"]),
            mm_per_px=float(r["mm_per_px"]),
            onset_kpa=float(r["onset_kpa"]),
            hard=bool(int(float(r["hard"]))),
        )
    except (ValueError, OverflowError) as exc:  # int(float("inf")): OverflowError
        raise ValueError(f"{where}: unparsable value ({exc})") from exc
    for name in ("pressure_kpa", "area_px", "mm_per_px", "onset_kpa"):
        if not math.isfinite(getattr(row, name)):
            raise ValueError(f"{where}: {name} is {r[name]}; expected a finite number")
    if row.pressure_kpa < 0:
        raise ValueError(f"{where}: pressure_kpa is {r['pressure_kpa']}; expected >= 0 kPa")
    if row.mm_per_px <= 0:
        raise ValueError(f"{where}: mm_per_px is {r['mm_per_px']}; expected a scale > 0 mm/px")
    for p in (row.frame, row.mask):
        if not p.is_file():
            raise ValueError(f"{where}: missing file {p}")
    return row


#: What a dataset folder's ``index.csv`` must be.
_INDEX_EXPECTED = "the dataset's index.csv (a CSV file written by `contactcal synth`)"


def check_dataset_folder(folder: str | os.PathLike[str], option: str | None = None) -> None:
    """Refuse a path that is no folder holding an ``index.csv`` (cheap: before any work).

    Args:
        folder: the dataset folder.
        option: the command-line option that gave it (e.g. ``--data``), named first
            (:func:`~contactcal.infer.errors.option_error`); None: the folder alone.

    Raises:
        ValueError: ``[OPTION ]FOLDER: ...; expected a dataset folder written by
            `contactcal synth```.
    """
    root = Path(folder)
    refuse_special(root / "index.csv", _INDEX_EXPECTED, ValueError)
    if not root.is_dir():
        problem = "is not a folder" if root.exists() else "does not exist"
    elif not (root / "index.csv").is_file():
        problem = "missing index.csv"
    else:
        return
    error = ValueError(
        f"{root}: {problem}; expected a dataset folder written by `contactcal synth`"
    )
    raise error if option is None else option_error(option, root, error)


def read_index(folder: str | os.PathLike[str]) -> list[IndexRow]:
    """All rows of one dataset folder, in file order.

    Raises:
        ValueError: no folder, no ``index.csv``, missing columns, unparsable values or missing
            files; the message names the file and line.
    """
    root = Path(folder)
    check_dataset_folder(root)
    index = root / "index.csv"
    try:
        text = read_input_bytes(index, _INDEX_EXPECTED, ValueError).decode("utf-8")
        with io.StringIO(text, newline="") as fh:
            reader = csv.DictReader(fh)
            missing = [c for c in REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
            if missing:
                raise ValueError(
                    f"{index}: missing column(s) {', '.join(missing)}; "
                    f"expected at least {', '.join(REQUIRED_COLUMNS)}"
                )
            rows: list[IndexRow] = []
            seen: dict[tuple[str, float], int] = {}  # (session, kPa) → its first line
            for r in reader:
                line = reader.line_num  # the file's line (blank lines, quoted newlines)
                row = _parse(root, line, r)
                first = seen.setdefault((row.session, row.pressure_kpa), line)
                if first != line:
                    raise ValueError(
                        f"{index} line {line}: session {row.session} has a frame at "
                        f"{row.pressure_kpa:g} kPa already (line {first}); expected one frame "
                        "per pressure step"
                    )
                rows.append(row)
    except UnicodeDecodeError as exc:
        raise ValueError(f"{index}: not UTF-8 text ({exc.reason}); expected a CSV file") from exc
    if not rows:
        raise ValueError(f"{index}: no frames listed")
    return rows


def read_datasets(folders: Sequence[str | os.PathLike[str]]) -> list[IndexRow]:
    """Rows of several dataset folders, in order (see :func:`read_index`).

    Raises:
        ValueError: no folder, or one folder given twice (under any spelling: its frames would
            count twice, and its fingers could fall on both sides of a split by finger).
    """
    if not folders:
        raise ValueError("no dataset folder given")
    check_distinct(folders)
    return [row for f in folders for row in read_index(f)]


def check_distinct(
    folders: Sequence[str | os.PathLike[str]], names: Sequence[str] | None = None
) -> None:
    """Refuse a dataset folder given twice under any spelling (``./d/``, a link to ``d``).

    Args:
        folders: the dataset folders.
        names: how each is named in a message (default: the folder as given), e.g.
            ``"--crosscheck d"``.

    Raises:
        ValueError: naming both spellings of the folder.
    """
    names = [str(f) for f in folders] if names is None else names
    seen: dict[Path, int] = {}
    for i, f in enumerate(folders):
        first = seen.setdefault(Path(f).resolve(), i)
        if first != i:
            raise ValueError(
                f"{names[i]}: dataset folder given twice (also as {names[first]}); expected "
                "each folder once"
            )


def sessions_of(rows: Sequence[IndexRow]) -> dict[str, list[IndexRow]]:
    """Rows grouped by session key (sorted), each session sorted by pressure.

    The first row of each session is its reference (lowest-pressure) frame.
    """
    out: dict[str, list[IndexRow]] = {}
    for r in rows:
        out.setdefault(r.session_key, []).append(r)
    return {k: sorted(v, key=lambda r: r.pressure_kpa) for k, v in sorted(out.items())}

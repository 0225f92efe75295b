"""A session's hand labels: a folder of mask PNGs or an ImageJ ellipse CSV, matched to frames.

Masks: ``<frame stem>.png`` per labelled frame, the frame's size; 0 = background, > 0 = contact
(an all-zero mask labels a frame without contact). Other files in the folder are ignored. A
mask without a pixel 0 (no background: inverted, or a background of another value) is refused;
so is any label covering more than the window ring (:mod:`~contactcal.infer.evaluate.window`).

Ellipses: a UTF-8 CSV with (at least) the columns :data:`LABEL_COLUMNS`, one row per labelled
frame, in ImageJ's convention (:mod:`contactcal.infer.evaluate.ellipse`). ``file`` is the frame's
path relative to the manifest's folder, or its file name when that is unique in the manifest.
A row whose five numbers are all empty labels the frame as without contact.

Every label must name a frame of the manifest; frames without a label are returned as such.
Each label is rasterised at its frame's size by :mod:`~contactcal.infer.evaluate.label_raster`.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path

from contactcal.infer.evaluate.ellipse import ImageJEllipse
from contactcal.infer.evaluate.errors import LabelError
from contactcal.infer.evaluate.mask_read import MASK_FIX
from contactcal.infer.files.regular import read_input_bytes
from contactcal.infer.image.read import SUPPORTED_SUFFIXES
from contactcal.infer.pipeline.manifest import Frame
from contactcal.infer.pipeline.manifest_rows import listed_name

#: Required columns of an ellipse CSV (other columns, e.g. ImageJ's Area, are ignored).
LABEL_COLUMNS = ("file", "cx", "cy", "major", "minor", "angle_deg")
_HEADER = ",".join(LABEL_COLUMNS)


@dataclass(frozen=True)
class Label:
    """One frame's hand label."""

    frame: Path  # the labelled frame (its Frame.file)
    source: Path  # the mask PNG, or the CSV
    row: int | None  # 1-based CSV data row; None for a mask
    ellipse: ImageJEllipse | None  # CSV label; None for a mask or a no-contact row

    def where(self) -> str:
        """The label's location for messages: the mask file or ``CSV row N``."""
        return str(self.source) if self.row is None else f"{self.source} row {self.row}"


def read_labels(labels: str | os.PathLike[str], frames: list[Frame], folder: Path) -> list[Label]:
    """The labels in ``labels`` (a folder of masks or a CSV), each matched to a frame (a CSV's
    ``file`` cell as the manifest lists it: relative to ``folder``, its
    :attr:`~contactcal.infer.pipeline.manifest.Session.folder`).

    Raises:
        LabelError: unreadable labels, a label naming no frame of the manifest, two labels of
            one frame, or a malformed CSV row (the message names the file).
    """
    path = Path(labels)
    if path.is_dir():
        return _mask_labels(path, frames)
    if not path.exists():  # a device or pipe is refused by the CSV reader, unread
        raise LabelError(
            f"{path}: labels not found; expected a folder of <frame stem>.png masks or a CSV "
            f"'{_HEADER}'"
        )
    return _ellipse_labels(path, frames, folder)


def _mask_labels(folder: Path, frames: list[Frame]) -> list[Label]:
    by_stem: dict[str, list[Path]] = {}
    for f in frames:
        by_stem.setdefault(f.file.stem, []).append(f.file)
    out: list[Label] = []
    _refuse_other_images(folder, frames)
    for mask in sorted(p for p in folder.iterdir() if p.suffix.lower() == ".png"):
        match = by_stem.get(mask.stem, [])
        if not match:
            raise LabelError(
                f"{mask}: no frame of the manifest has the stem '{mask.stem}'; expected masks "
                "named like the frames (<frame stem>.png), e.g. "
                f"{frames[-1].file.stem}.png for {frames[-1].file.name}"
            )
        if len(match) > 1:
            raise LabelError(
                f"{mask}: frames {match[0]} and {match[1]} share its stem; masks are matched "
                "by stem, so give the frames distinct names"
            )
        twice = [lab.source for lab in out if lab.frame == match[0]]
        if twice:
            raise LabelError(
                f"{mask}: labels {match[0].name} like {twice[0]}; expected one mask per frame "
                "(remove one of them)"
            )
        out.append(Label(match[0], mask, None, None))
    return out


def _refuse_other_images(folder: Path, frames: list[Frame]) -> None:
    """Refuse an image in the mask folder that is neither a PNG nor a frame of the manifest (a
    mask saved as JPEG or TIFF would otherwise be skipped, leaving its frame unlabelled without
    a word); other files, and the frames themselves, are left.

    Raises:
        LabelError: the first such image, named.
    """
    own = {f.file.resolve() for f in frames}
    other = sorted(
        p
        for p in folder.iterdir()
        if p.suffix.lower() in SUPPORTED_SUFFIXES
        and p.suffix.lower() != ".png"
        and p.resolve() not in own
    )
    if other:
        raise LabelError(
            f"{other[0]}: a {other[0].suffix} image in the mask folder; {MASK_FIX} "
            f"({other[0].stem}.png)"
        )


def _read_rows(path: Path) -> tuple[dict[str, int], list[tuple[int, list[str]]]]:
    """Column index by name and the non-blank data rows ``(row number, cells)`` of a CSV."""
    try:
        text = read_input_bytes(path, f"the label CSV '{_HEADER}'", LabelError)
        with io.StringIO(text.decode("utf-8-sig"), newline="") as fh:
            rows = [r for r in csv.reader(fh) if any(c.strip() for c in r)]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise LabelError(
            f"{path}: cannot read the label CSV ({exc}); expected '{_HEADER}'"
        ) from None
    if not rows:
        raise LabelError(f"{path}: empty; expected a header '{_HEADER}' and one row per frame")
    names = [h.strip() for h in rows[0]]
    missing = [c for c in LABEL_COLUMNS if c not in names]
    if missing:
        raise LabelError(
            f"{path}: missing column(s) {', '.join(missing)}; expected the header to contain "
            f"'{_HEADER}' (got {','.join(names)!r}){_imagej_hint(names)}"
        )
    return {n: names.index(n) for n in LABEL_COLUMNS}, list(enumerate(rows[1:], start=1))


#: ImageJ's Results columns (Centroid, Fit ellipse, Display label) → this CSV's.
IMAGEJ_COLUMNS = {
    "Label": "file",
    "X": "cx",
    "Y": "cy",
    "Major": "major",
    "Minor": "minor",
    "Angle": "angle_deg",
}


def _imagej_hint(names: list[str]) -> str:
    """How to turn ImageJ's Results export into a label CSV, when ``names`` look like one."""
    if not {"X", "Y", "Major", "Minor", "Angle"} <= set(names):
        return ""
    renames = ", ".join(f"{k} → {v}" for k, v in IMAGEJ_COLUMNS.items())
    label = "" if "Label" in names else " (no Label column: tick Display label in Set Measurements)"
    return (
        f"; this looks like ImageJ's Results export: rename its columns {renames}{label}, with "
        "the scale removed (pixels; docs/evaluate.md, 'Ellipses in ImageJ')"
    )


def _number(at: str, name: str, cell: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise LabelError(f"{at}: {name} {cell!r} is not a finite number; expected pixels/degrees")
    return value


#: px, largest accepted ellipse axis: the widest accepted frame (`PixelScale`'s 100 000 px);
#: larger values are a unit mistake and would overflow the area.
MAX_AXIS_PX = 100_000.0


def _ellipse(at: str, cells: dict[str, str]) -> ImageJEllipse | None:
    """The row's ellipse; None when all five numbers are empty (a frame without contact)."""
    keys = LABEL_COLUMNS[1:]
    if not any(cells[k] for k in keys):
        return None
    v = {k: _number(at, k, cells[k]) for k in keys}
    for k in ("major", "minor"):
        if not 0 < v[k] <= MAX_AXIS_PX:
            raise LabelError(
                f"{at}: {k} {v[k]:g} is not in (0, {MAX_AXIS_PX:g}]; expected the ellipse's full "
                "axis length in pixels (leave all five numbers empty to label a frame without "
                "contact)"
            )
    if v["minor"] > v["major"]:
        raise LabelError(
            f"{at}: minor {v['minor']:g} is longer than major {v['major']:g}; ImageJ writes "
            "major >= minor, so the columns are probably swapped (an ellipse turned by 90°)"
        )
    return ImageJEllipse(v["cx"], v["cy"], v["major"], v["minor"], v["angle_deg"])


def _frame_of(at: str, name: str, frames: list[Frame], folder: Path) -> Path:
    """The frame a CSV ``file`` cell names (its path as the manifest lists it, relative to
    ``folder``, or a unique name)."""
    for f in frames:
        if Path(name) == Path(listed_name(folder, f.file)) or Path(name) == f.file:
            return f.file
    named = [f.file for f in frames if f.file.name == name]
    if len(named) == 1:
        return named[0]
    if named:
        raise LabelError(
            f"{at}: file '{name}' matches frames {named[0]} and {named[1]}; give its path "
            "relative to the manifest's folder"
        )
    stem, colon, _ = name.partition(":")
    if colon and any(f.file.name == stem for f in frames):  # ImageJ's "image.jpg:ROI" label
        raise LabelError(
            f"{at}: file '{name}' is not a frame of the manifest; remove the ':…' suffix "
            f"ImageJ adds to its labels ('{stem}')"
        )
    raise LabelError(
        f"{at}: file '{name}' is not a frame of the manifest; expected one of its file names, "
        f"e.g. {frames[-1].file.name}"
    )


def _ellipse_labels(path: Path, frames: list[Frame], folder: Path) -> list[Label]:
    col, rows = _read_rows(path)
    out: dict[Path, Label] = {}
    for row, cells in rows:
        at = f"{path}: row {row}"
        if len(cells) <= max(col.values()):
            raise LabelError(f"{at}: expected the columns '{_HEADER}', got {cells!r}")
        named = {k: cells[i].strip() for k, i in col.items()}
        frame = _frame_of(at, named["file"], frames, folder)
        if frame in out:
            raise LabelError(
                f"{at}: {frame.name} is labelled already on row {out[frame].row}; expected one "
                "ellipse per frame"
            )
        out[frame] = Label(frame, path, row, _ellipse(at, named))
    return list(out.values())

"""The files of a ``contactcal synth`` dataset folder that a run reads back, each checked.

A resumed run reads ``config.json`` (refused unless it is this config) and the finished frames'
truth JSON (and its shard's run record, :mod:`~contactcal.synth.run_record`); a damaged or
foreign file is refused in one line naming it and what was expected. :func:`check_out_folder`
refuses an ``--out`` that would mix the dataset with other files.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from contactcal.infer.errors import config_changes, few
from contactcal.infer.files.atomic import write_json
from contactcal.infer.files.jsonable import jsonable
from contactcal.infer.files.regular import read_record_json
from contactcal.infer.files.temporaries import TEMP_NAME
from contactcal.synth.layout import INDEX_COLUMNS
from contactcal.synth.variant import VARIANTS

if TYPE_CHECKING:
    from contactcal.synth.dataset import DatasetConfig

#: What changed the frames a given config renders (recorded in ``config.json``; a folder of an
#: earlier revision is not resumed, since its frames and new ones would differ).
REVISIONS = {
    1: "v2 world",
    2: "defocus, motion blur and axis offset scale with the frame width",
}
SYNTH_REVISION = max(REVISIONS)

#: Keys of a frame's truth JSON that a run reads back (the rest are ``index.csv`` columns).
FRAME_KEYS = ("finger", "pressure_kpa", "contact", "mm_per_px")


def read_frame_record(path: Path) -> dict[str, Any]:
    """A finished frame's truth JSON (its ``index.csv`` row), checked.

    Raises:
        ValueError: naming the file, what it is (not JSON, a FIFO, ...), and the remedy:
            removed, it is rendered again by a resume.
    """
    remedy = (
        "a frame record a `contactcal synth` run wrote; remove it and run the same synth "
        "command, which renders that frame again"
    )
    record = read_record_json(path, remedy)
    if not isinstance(record, dict):
        raise ValueError(f"{path}: holds no JSON object; expected {remedy}")
    missing = [k for k in FRAME_KEYS if k not in record]
    if missing:
        raise ValueError(f"{path}: has no {', '.join(missing)}; expected {remedy}")
    unknown = [k for k in record if k not in INDEX_COLUMNS]  # index.csv has no column for them
    if unknown:
        extra = ", ".join(unknown)
        raise ValueError(f"{path}: has keys no frame record has ({extra}); expected {remedy}")
    for key in ("pressure_kpa", "mm_per_px"):
        if isinstance(record[key], bool) or not isinstance(record[key], int | float):
            raise ValueError(f"{path}: {key} is {record[key]!r}, not a number; expected {remedy}")
    return record


def config_record(config: DatasetConfig) -> dict[str, Any]:
    """What ``config.json`` holds for ``config`` (as read back from JSON)."""
    return json.loads(json.dumps({**jsonable(asdict(config)), "synth_revision": SYNTH_REVISION}))


def check_config_matches(root: Path, config: DatasetConfig) -> None:
    """Write ``config.json``, or refuse to mix a different config into an existing folder.

    Raises:
        ValueError: ``config.json`` is damaged, another tool's, of another Mitsuba variant or
            synth revision, or of other arguments (the differing keys are named, old → new).
    """
    path = root / "config.json"
    new = config_record(config)
    if not path.is_file():
        write_json(path, new)
        return
    expected = (
        "the config a `contactcal synth` run wrote; render into a new --out (or remove this "
        "folder to render it again)"
    )
    old = read_record_json(path, expected)
    if not isinstance(old, dict) or not isinstance(old.get("render"), dict):
        raise ValueError(
            f"{path}: is not the config of a `contactcal synth` dataset (a training run's or "
            "another tool's?); render into a new --out"
        )
    was, now = old["render"].get("variant"), config.render.variant
    if was in VARIANTS and was != now:
        raise ValueError(
            f"{path}: rendered with the Mitsuba variant {was}, and this machine renders with "
            f"{now} (other bytes); resume where {was} works (CONTACTCAL_MI_VARIANT={was}) "
            "or render into a new --out"
        )
    if was == "auto":
        raise ValueError(
            f"{path}: rendered before the Mitsuba variant was recorded ('auto'), so a resume "
            f"could mix frames of another variant (this machine's: {now}); render into a new --out"
        )
    old.setdefault("smooth_fraction", 0.0)  # folders rendered before the options existed
    old.setdefault("speck_fraction", 0.0)
    old.setdefault("departure_fraction", 0.0)
    old.setdefault("synth_revision", 1)
    if old["synth_revision"] != SYNTH_REVISION:
        raise ValueError(
            f"{path}: this folder was rendered by synth revision {old['synth_revision']} "
            f"(now {SYNTH_REVISION}: {REVISIONS[SYNTH_REVISION]}), so new frames would not "
            "match its frames; render into a new --out"
        )
    if old != new:
        raise ValueError(
            f"{path}: this folder was rendered with a different config ({config_changes(old, new)}"
            "); use a new --out or the same arguments to resume"
        )


def is_dataset(folder: Path) -> bool:
    """Whether ``folder`` holds a synth dataset: a ``config.json`` and ``finger_*`` folders."""
    if not (folder / "config.json").is_file():
        return False
    return any(p.is_dir() for p in folder.glob("finger_[0-9]*"))


def check_out_folder(root: Path) -> None:
    """Refuse an ``--out`` inside a synth dataset, or an existing folder of other files.

    An existing folder without ``config.json`` is taken only when empty or holding nothing but
    the staged ``config.json`` of a synth run (killed, or another shard writing it now): every
    other synth file is written after ``config.json``.

    Raises:
        ValueError: naming the folder and what was expected.
    """
    for parent in root.resolve().parents:
        if is_dataset(parent):
            raise ValueError(
                f"--out {root}: inside the synth dataset {parent} (its config.json and finger_* "
                "folders); give the new dataset a folder of its own, outside that one"
            )
    if not root.is_dir() or (root / "config.json").exists():
        return
    other = sorted(
        e.name
        for e in os.scandir(root)
        if not (TEMP_NAME.match(e.name) and e.name.startswith(".config.json."))
    )
    if other:
        raise ValueError(
            f"--out {root}: holds other files ({few(other)}) and no config.json; "
            "expected a new or empty folder, or a synth dataset to resume; render into a new --out"
        )

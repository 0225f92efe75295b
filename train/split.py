"""The train/validation split by finger, and the split a run records in its ``config.json``.

Training splits its frames by finger (:func:`split_by_finger`: frames of one finger share its
fingerprint texture and would leak) and records the split (:func:`split_record`) beside its
dataset folders, resolved (``data_dirs``). The split is keyed on
:attr:`~contactcal.infer.bench.dataset.IndexRow.finger_key`, the RESOLVED folder and the finger,
so every spelling of a folder (``d``, ``./d``, ``/abs/d``) splits alike. What needs the run's
validation fingers afterwards (export's interval calibration and decision check,
``export --tune-min-area``) takes them from the record (:func:`validation_rows`) and refuses a
record that the split recomputed from ``data_dirs`` contradicts; ``train --resume`` refuses data
that would split otherwise than the record (:func:`check_same_split`).

Runs written before the split was keyed on resolved folders recorded their keys as the folders
were typed (``data/v3#4``), and the oldest their ``data_dirs`` as typed too: each key is read as the
``data_dirs`` entry it names, resolved (:func:`recorded_split`). Folders typed relative to one
parent (all ``data/...``) sort the same resolved, so those runs split as before.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from contactcal.infer.bench.dataset import IndexRow, read_datasets
from contactcal.infer.errors import few

#: A recorded split: ``{"train": [...], "val": [...]}``, each side's sorted finger keys.
Split = dict[str, list[str]]
#: The sides of a split, validation first (the one whose difference matters most).
SIDES = ("val", "train")


def split_by_finger(
    rows: Sequence[IndexRow], val_fraction: float, seed: int
) -> tuple[list[IndexRow], list[IndexRow]]:
    """Deterministic train/validation split by finger (:attr:`IndexRow.finger_key`).

    Args:
        rows: all frames.
        val_fraction: fraction of FINGERS held out (at least one when there are >= 2 fingers
            and the fraction is > 0).
        seed: split seed (numpy Generator).

    Returns:
        ``(train, val)`` rows, each in the input order; no finger appears in both.
    """
    if not 0.0 <= val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
    fingers = sorted({r.finger_key for r in rows})
    n_val = round(val_fraction * len(fingers))
    if val_fraction > 0 and len(fingers) >= 2:
        n_val = min(max(n_val, 1), len(fingers) - 1)
    order = np.random.default_rng(seed).permutation(len(fingers))
    held = {fingers[i] for i in order[:n_val]}
    train = [r for r in rows if r.finger_key not in held]
    return train, [r for r in rows if r.finger_key in held]


def split_record(train: Sequence[IndexRow], val: Sequence[IndexRow]) -> Split:
    """The split as ``config.json`` records it: each side's sorted finger keys."""
    return {
        "train": sorted({r.finger_key for r in train}),
        "val": sorted({r.finger_key for r in val}),
    }


def recorded_split(info: dict, config_path: Path) -> Split:
    """A run's recorded split, each key read as ``<its data_dirs entry, resolved>#<finger>``.

    Args:
        info: the run's ``config.json`` (``split``, ``data_dirs``; relative entries, as runs
            before the folders were resolved recorded them, resolve from the working folder,
            as :func:`validation_rows` reads them).
        config_path: that file, for the messages.

    Raises:
        ValueError: no split or data_dirs, or a key whose folder names no ``data_dirs`` entry or
            more than one (naming ``config_path`` and what was expected).
    """
    split, dirs = info.get("split"), info.get("data_dirs")
    if not (
        isinstance(split, dict)
        and all(_is_strings(split.get(side), "#") for side in SIDES)
        and _is_strings(dirs)
    ):
        raise ValueError(
            f"{config_path}: expected split and data_dirs as `contactcal train` records them "
            '(split: {"train": [...], "val": [...]}, each a list of "<dataset folder>#<finger>"; '
            "data_dirs: the list of dataset folders)"
        )
    keys = [k for side in SIDES for k in split[side]]
    named = _named_folders([k.rpartition("#")[0] for k in keys], dirs)
    for key in keys:
        entries = named[key.rpartition("#")[0]]
        if len(entries) != 1:
            which = f"{len(entries)} ({', '.join(entries)})" if entries else "none"
            raise ValueError(
                f"{config_path}: the split's key {key!r} names {which} of the run's data_dirs "
                f"({', '.join(dirs)}); expected each key to name exactly one of them "
                "(<dataset folder>#<finger>, the folder as data_dirs records it or as it was "
                "typed; one typed through a symlink or since renamed names none)"
            )
    return {
        side: sorted(
            f"{Path(named[f][0]).resolve()}#{n}"
            for f, _, n in (k.rpartition("#") for k in split[side])
        )
        for side in SIDES
    }


def _is_strings(value: object, holding: str = "") -> bool:
    """A list of strings, each holding ``holding``."""
    return isinstance(value, list) and all(isinstance(v, str) and holding in v for v in value)


def _named_folders(folders: list[str], dirs: list[str]) -> dict[str, list[str]]:
    """Each key folder's ``data_dirs`` entries: those whose path ends with the folder's parts (an
    absolute folder: the entry itself; a relative one as typed: its parts after any leading
    ``..``). When one folder names none and one entry is named by no folder (an older run's
    folder typed through a symlink or renamed since), the two are paired: a wrong pairing
    splits otherwise than the data, which :func:`check_same_split` refuses."""
    named: dict[str, list[str]] = {}
    for folder in folders:
        parts = Path(os.path.normpath(folder)).parts
        parts = parts[next((i for i, p in enumerate(parts) if p != ".."), len(parts)) :]
        named[folder] = [d for d in dirs if not parts or Path(d).parts[-len(parts) :] == parts]
    unnamed = [f for f, entries in named.items() if not entries]
    unused = [d for d in dirs if not any(d in entries for entries in named.values())]
    if len(unnamed) == 1 and len(unused) == 1:
        named[unnamed[0]] = unused
    return named


def check_same_split(recorded: Split, split: Split, where: str, fix: str) -> None:
    """Refuse ``split`` unless each side holds the fingers of the same side of ``recorded``.

    Args:
        recorded: the run's split (:func:`recorded_split`).
        split: the split recomputed (:func:`split_record`).
        where: the message's start, naming what was recomputed from what.
        fix: the message's end: what was expected and how to fix it.

    Raises:
        ValueError: naming the side and the fingers that differ.
    """
    for side in SIDES:
        only_recorded = sorted(set(recorded[side]) - set(split[side]))
        only_now = sorted(set(split[side]) - set(recorded[side]))
        if only_recorded or only_now:
            name = "validation" if side == "val" else "training"
            raise ValueError(
                f"{where}: its {name} fingers differ from those config.json records (recorded "
                f"only: {few(only_recorded)}; recomputed only: {few(only_now)}); {fix}"
            )


def validation_rows(
    run_dir: str | os.PathLike[str], info: dict, val_fraction: float, seed: int
) -> list[IndexRow]:
    """The frames of a run's validation fingers, as its ``config.json`` records them.

    Args:
        run_dir: the run folder (its ``config.json`` is named in the messages).
        info: that ``config.json`` (``split``; ``data_dirs`` found and unchanged:
            :func:`contactcal.train.export.check_data_dirs`).
        val_fraction, seed: the run's split settings.

    Returns:
        The rows of the recorded validation fingers, in ``data_dirs`` order.

    Raises:
        ValueError: an unreadable split, one that the split recomputed from ``data_dirs``
            contradicts (neither is used), or no validation fingers.
    """
    path = Path(run_dir) / "config.json"
    recorded = recorded_split(info, path)
    rows = read_datasets(info["data_dirs"])
    check_same_split(
        recorded,
        split_record(*split_by_finger(rows, val_fraction, seed)),
        f"{path}: the split recomputed from data_dirs (val_fraction {val_fraction:g}, seed {seed})",
        "expected the two to agree, so neither is used: retrain the run (an older contactcal "
        "split on the folders as typed, and one typed relative and one absolute sort otherwise "
        "than resolved)",
    )
    held = set(recorded["val"])
    if not held:
        raise ValueError(
            f"{path}: the run has no validation fingers (split val is empty); expected a run "
            "trained on >= 2 fingers (export calibrates and checks on its validation fingers)"
        )
    return [r for r in rows if r.finger_key in held]

"""A run folder: its ``config.json`` and what ``train`` may write there.

``train`` writes a new run only into a new or empty folder (or over the ``best.pt`` alone that a
run killed in its first epoch leaves), and continues (``--resume``) only a run that holds
``last.pt``: never over files it did not write (:func:`check_run_folder`). What ``--resume`` then
continues is :mod:`contactcal.train.resume`'s. No torch at import (a ``best.pt`` is read only to
tell a run killed in its first epoch): ``contactcal train`` refuses a folder before it loads the
training stack.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from contactcal.infer.errors import few
from contactcal.infer.files.atomic import TEMP_NAME, check_receiving_folder


def read_run_info(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """A run's ``config.json``.

    Raises:
        ValueError: missing, unreadable, or not a ``contactcal train`` run config.
    """
    run = Path(run_dir)
    path = run / "config.json"
    if not path.is_file():
        raise ValueError(f"{path}: missing run config (is {run} a `contactcal train` run folder?)")
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: unreadable run config ({exc})") from exc
    if not isinstance(info, dict) or "train" not in info:
        raise ValueError(
            f"{path}: not a `contactcal train` run config (no 'train' settings: a dataset's "
            f"config?); expected a run folder, e.g. runs/r1"
        )
    return info


def check_run_folder(out: Path, resume: bool) -> list[str]:
    """Refuse an ``out`` that ``train`` would write over, or could not write into (under a file
    or a link: :func:`~contactcal.infer.files.atomic.check_receiving_folder`): a new run needs a
    new or empty folder (staged temporaries of a killed write aside) or one holding only what a
    run killed in its first epoch leaves (:func:`killed_in_first_epoch`), ``resume`` a run that
    holds ``last.pt``.

    Returns:
        The leftovers a new run is to remove before it starts (``["best.pt"]`` or none).

    Raises:
        ValueError: naming the folder, what was expected and how to go on.
    """
    if resume and (out / "last.pt").is_file():
        return []
    check_receiving_folder(out)  # e.g. under a file: refused now, not after the first epoch
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: not a folder; expected a run folder, e.g. runs/r1")
    held = (
        sorted(e.name for e in os.scandir(out) if not TEMP_NAME.match(e.name))
        if out.exists()
        else []
    )
    killed = killed_in_first_epoch(out, held)
    if resume and killed:
        raise ValueError(
            f"{out}: nothing to --resume (it holds only best.pt, left by a run killed in its "
            "first epoch, before its first last.pt); start the run again without --resume (it "
            "removes that best.pt)"
        )
    if resume:
        state = f"holds {few(held)}" if held else "is empty" if out.exists() else "does not exist"
        raise ValueError(
            f"{out}: nothing to --resume (no last.pt; the folder {state}); expected an unfinished "
            "run's folder (one holding last.pt), or a new or empty folder without --resume"
        )
    if "last.pt" in held:
        raise ValueError(
            f"{out}: already holds a run (last.pt); pass --resume to continue it, or another --out"
        )
    if held and not killed:
        raise ValueError(
            f"{out}: holds {few(held)}, which a new run would mix its files with or write over; "
            "expected an empty or new folder, or --resume on an unfinished run (one holding "
            "last.pt)"
        )
    return held


def killed_in_first_epoch(out: Path, held: list[str]) -> bool:
    """Whether ``held`` (the names in ``out``) is what a run killed in its first epoch leaves:
    ``best.pt`` alone (written just before the first ``last.pt``), a checkpoint of epoch 0."""
    if held != ["best.pt"]:
        return False
    from contactcal.train.checkpoint import load_checkpoint  # torch: only for this best.pt

    try:
        ckpt = load_checkpoint(out / "best.pt")
    except ValueError:
        return False
    return isinstance(ckpt, dict) and ckpt.get("epoch") == 0 and "config" in ckpt


def remove_leftovers(out: Path, names: list[str]) -> None:
    """Remove what a run killed in its first epoch left (its ``best.pt``), saying so."""
    for name in names:
        (out / name).unlink()
        print(
            f"note: {out / name}: removed, left by a run killed in its first epoch (before its "
            "first last.pt); this run starts afresh",
            file=sys.stderr,
        )

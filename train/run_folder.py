"""A run folder: its ``config.json`` and what ``train`` may write there.

``train`` writes a new run only into a new or empty folder, and continues (``--resume``) only a
run that holds ``last.pt``: never over files it did not write, nor over a ``best.pt`` alone (a
run killed in its first epoch leaves one; so may someone keeping a checkpoint: the message says
how to go on) (:func:`check_run_folder`). What ``--resume`` then continues is
:mod:`contactcal.train.resume`'s. No torch: ``contactcal train`` refuses a folder before it loads
the training stack.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from contactcal.infer.errors import few
from contactcal.infer.files.destination import check_destination, check_receiving_folder
from contactcal.infer.files.regular import read_input_json
from contactcal.infer.files.temporaries import TEMP_NAME

#: The files ``train`` writes into its run folder, each replaced whole as the run goes on.
RUN_FILES = ("config.json", "last.pt", "best.pt", "metrics.csv", "curves.png", "val_bins.csv")


def ran_to_end(out: Path) -> bool:
    """Whether the run in ``out`` ran to its last epoch: it holds ``val_bins.csv``, written after
    it (whether or not its ``last.pt`` was kept; ``export`` needs only ``best.pt``)."""
    return (out / "val_bins.csv").is_file()


def read_run_info(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """A run's ``config.json``, read as inputs are (a folder, device or pipe there is refused
    unread).

    Raises:
        ValueError: missing, unreadable, not a regular file, or not a ``contactcal train`` run
            config.
    """
    run = Path(run_dir)
    path = run / "config.json"
    try:
        info = read_input_json(path, "the config.json a `contactcal train` run wrote", ValueError)
    except (FileNotFoundError, NotADirectoryError):
        if path.is_symlink():  # a link to nothing: the run's config is not "missing" but lost
            raise ValueError(
                f"{path}: a link to {os.readlink(path)}, which does not exist; expected the "
                "config.json a `contactcal train` run wrote (put the file there)"
            ) from None
        raise ValueError(
            f"{path}: missing run config (is {run} a `contactcal train` run folder?)"
        ) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: unreadable run config ({exc})") from exc
    if not isinstance(info, dict) or "train" not in info:
        raise ValueError(
            f"{path}: not a `contactcal train` run config (no 'train' settings: a dataset's "
            f"config?); expected a run folder, e.g. runs/r1"
        )
    return info


def check_run_folder(out: Path, resume: bool) -> None:
    """Refuse an ``out`` that ``train`` would write over, or could not write into (under a file
    or a link: :func:`~contactcal.infer.files.destination.check_receiving_folder`, checked for the
    files it writes): a new run needs a new or empty folder (staged temporaries of a killed write
    aside), ``resume`` a run that holds ``last.pt``, and, where that run is unfinished (not
    :func:`ran_to_end`), none of its :data:`RUN_FILES` a link, a folder or a pipe
    (:func:`~contactcal.infer.files.destination.check_destination`: the files it replaces).

    Raises:
        ValueError: naming the folder, what was expected and how to go on.
    """
    if resume and (out / "last.pt").is_file():
        if not ran_to_end(out):  # continued: its files replaced, none a link or a folder
            for name in RUN_FILES:  # refused now, not after an epoch (last.pt replaced by then)
                check_destination(out / name)
        return
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: not a folder; expected a run folder, e.g. runs/r1")
    check_receiving_folder(out / "last.pt")  # e.g. under a file: refused now, not after an epoch
    held = (
        sorted(e.name for e in os.scandir(out) if not TEMP_NAME.match(e.name))
        if out.exists()
        else []
    )
    if held == ["best.pt"]:  # never removed here: it may be a checkpoint someone kept
        raise ValueError(
            f"{out}: holds only best.pt, with no last.pt to --resume (a run killed in its first "
            "epoch, before its first last.pt, leaves that; so does a run whose other files were "
            f"removed); expected a new or empty folder: if it is a killed run's, remove "
            f"{out / 'best.pt'} and start the run again, otherwise choose another --out"
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
    if held:
        raise ValueError(
            f"{out}: holds {few(held)}, which a new run would mix its files with or write over; "
            "expected an empty or new folder, or --resume on an unfinished run (one holding "
            "last.pt)"
        )

"""A run folder: its ``config.json``, what ``train`` may write there, what ``--resume`` continues.

``train`` writes a new run only into a new or empty folder (or over the ``best.pt`` alone that a
run killed in its first epoch leaves), and continues (``--resume``) only a run that holds
``last.pt``: never over files it did not write (:func:`check_run_folder`); a finished run, one
that holds ``val_bins.csv`` too, it leaves as it is (:func:`finished_summary`). A resumed run
must have the run's config, data and split (:func:`resume_checkpoint`).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from contactcal.infer.errors import few
from contactcal.infer.files.atomic import TEMP_NAME
from contactcal.train.checkpoint import config_diff, load_checkpoint
from contactcal.train.config import TrainConfig, saved_train_config
from contactcal.train.split import Split, check_same_split, recorded_split


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
    """Refuse an ``out`` that ``train`` would write over: a new run needs a new or empty folder
    (staged temporaries of a killed write aside) or one holding only what a run killed in its
    first epoch leaves (:func:`killed_in_first_epoch`), ``resume`` a run that holds ``last.pt``.

    Returns:
        The leftovers a new run is to remove before it starts (``["best.pt"]`` or none).

    Raises:
        ValueError: naming the folder, what was expected and how to go on.
    """
    if resume and (out / "last.pt").is_file():
        return []
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: not a folder; expected a run folder (--out), e.g. runs/r1")
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


def finished_summary(out: Path) -> dict[str, Any] | None:
    """What ``train --resume`` returns for a finished run (one holding ``last.pt`` and
    ``val_bins.csv``, written after its last epoch), which it leaves as it is; None for any other.

    Returns:
        ``out_dir``, ``finished`` (True), ``epochs_run`` (0), ``best_epoch`` and ``best_score``.
    """
    if not ((out / "last.pt").is_file() and (out / "val_bins.csv").is_file()):
        return None
    ckpt = load_checkpoint(out / "last.pt")
    return {
        "out_dir": str(out),
        "finished": True,
        "epochs_run": 0,
        "best_epoch": int(ckpt["best_epoch"]),
        "best_score": float(ckpt["best_score"]),
    }


def killed_in_first_epoch(out: Path, held: list[str]) -> bool:
    """Whether ``held`` (the names in ``out``) is what a run killed in its first epoch leaves:
    ``best.pt`` alone (written just before the first ``last.pt``), a checkpoint of epoch 0."""
    if held != ["best.pt"]:
        return False
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


def resume_checkpoint(
    out: Path, cfg: TrainConfig, digests: tuple[str, str], split: Split
) -> dict[str, Any]:
    """``out/last.pt``, to continue with this call's config, data and split (the run's).

    Args:
        out: the run folder.
        cfg: this call's config (device and threads may differ from the run's).
        digests: this call's :func:`~contactcal.train.digest.dataset_digest` and
            :func:`~contactcal.train.digest.render_digest` (the latter compared with the run's
            ``config.json`` where it records one: runs before it did not).
        split: this call's split (:func:`~contactcal.train.split.split_record`).

    Raises:
        ValueError: another config, data or split, or a checkpoint that cannot resume exactly.
    """
    ckpt = load_checkpoint(out / "last.pt")
    saved = saved_train_config(ckpt["config"], str(out / "last.pt"))
    diff = [k for k in config_diff(saved, cfg) if k not in ("device", "num_threads")]
    if diff:
        raise ValueError(f"{out}: --resume with a different config ({', '.join(diff)})")
    if ckpt["data_digest"] != digests[0]:
        raise ValueError(f"{out}: --resume with different data (index.csv digest changed)")
    if "augment_rng" not in ckpt:
        raise ValueError(
            f"{out / 'last.pt'}: written by an older contactcal (no augmentation generator "
            "state), cannot be resumed exactly; start a new run"
        )
    if (out / "config.json").is_file():  # absent only if killed before its first config.json
        info = read_run_info(out)
        if info.get("render_digest", digests[1]) != digests[1]:
            raise ValueError(
                f"{out}: --resume with data rendered otherwise (the folders' config.json digest "
                "differs from the run's render_digest: another size, spp, seed or variant); "
                "expected the run's own renders: put them back, or start a new run"
            )
        check_same_split(
            recorded_split(info, out / "config.json"),
            split,
            f"{out}: the split of this --resume's --data",
            f"expected the run's own dataset folders: pass --data {' '.join(info['data_dirs'])} "
            "(any spelling; a run whose split an older contactcal recorded on other spellings "
            "cannot be resumed exactly: start a new run)",
        )
    return ckpt

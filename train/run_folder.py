"""A run folder: its ``config.json``, what ``train`` may write there, what ``--resume`` continues.

``train`` writes a new run only into a new or empty folder, and continues (``--resume``) only a
run that holds ``last.pt``: never over a finished run's files or files it did not write
(:func:`check_run_folder`). A resumed run must have the run's config, data and split
(:func:`resume_checkpoint`).
"""

from __future__ import annotations

import json
import os
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


def check_run_folder(out: Path, resume: bool) -> None:
    """Refuse an ``out`` that ``train`` would write over: a new run needs a new or empty folder
    (staged temporaries of a killed write aside), ``resume`` a run that holds ``last.pt``.

    Raises:
        ValueError: naming the folder and what was expected.
    """
    if resume and (out / "last.pt").is_file():
        return
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: not a folder; expected a run folder (--out), e.g. runs/r1")
    held = (
        sorted(e.name for e in os.scandir(out) if not TEMP_NAME.match(e.name))
        if out.exists()
        else []
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


def resume_checkpoint(
    out: Path, cfg: TrainConfig, digests: tuple[str, str], split: Split
) -> dict[str, Any]:
    """``out/last.pt``, to continue with this call's config, data and split (the run's).

    Args:
        out: the run folder.
        cfg: this call's config (device and threads may differ from the run's).
        digests: this call's :func:`~contactcal.train.data.dataset_digest` and
            :func:`~contactcal.train.data.render_digest` (the latter compared with the run's
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

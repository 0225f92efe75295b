"""A run folder: its ``config.json``, what ``train`` may write there, what ``--resume`` continues.

``train`` starts no new run in a folder that holds one (:func:`check_run_folder`). A resumed run
must have the run's config, data and split (:func:`resume_checkpoint`).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

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
    """Refuse a new run (no ``resume``) in a folder that holds one (``last.pt``).

    Raises:
        ValueError: naming the folder and what to do instead.
    """
    if not resume and (out / "last.pt").exists():
        raise ValueError(f"{out}: already holds a run (last.pt); pass --resume or another --out")


def resume_checkpoint(out: Path, cfg: TrainConfig, digest: str, split: Split) -> dict[str, Any]:
    """``out/last.pt``, to continue with this call's config, data and split (the run's).

    Args:
        out: the run folder.
        cfg: this call's config (device and threads may differ from the run's).
        digest: this call's :func:`~contactcal.train.data.dataset_digest`.
        split: this call's split (:func:`~contactcal.train.split.split_record`).

    Raises:
        ValueError: another config, data or split, or a checkpoint that cannot resume exactly.
    """
    ckpt = load_checkpoint(out / "last.pt")
    saved = saved_train_config(ckpt["config"], str(out / "last.pt"))
    diff = [k for k in config_diff(saved, cfg) if k not in ("device", "num_threads")]
    if diff:
        raise ValueError(f"{out}: --resume with a different config ({', '.join(diff)})")
    if ckpt["data_digest"] != digest:
        raise ValueError(f"{out}: --resume with different data (index.csv digest changed)")
    if "augment_rng" not in ckpt:
        raise ValueError(
            f"{out / 'last.pt'}: written by an older contactcal (no augmentation generator "
            "state), cannot be resumed exactly; start a new run"
        )
    if (out / "config.json").is_file():  # absent only if killed before its first config.json
        info = read_run_info(out)
        check_same_split(
            recorded_split(info, out / "config.json"),
            split,
            f"{out}: the split of this --resume's --data",
            f"expected the run's own dataset folders: pass --data {' '.join(info['data_dirs'])} "
            "(any spelling; a run whose split an older contactcal recorded on other spellings "
            "cannot be resumed exactly: start a new run)",
        )
    return ckpt

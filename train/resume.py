"""What ``train --resume`` continues: a finished run it checks, then leaves as it is
(:func:`is_finished`, :func:`finished_summary`), an unfinished one with the run's config, data
and split (:func:`resume_checkpoint`). Which folders ``train`` writes into at all is
:func:`contactcal.train.run_folder.check_run_folder`'s (no torch: the command line checks it
before the training stack is imported).
"""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

from contactcal.infer.errors import config_changes
from contactcal.train.checkpoint import config_to_dict, load_checkpoint
from contactcal.train.config import TrainConfig, saved_train_config
from contactcal.train.run_folder import ran_to_end, read_run_info
from contactcal.train.split import Split, check_same_split, recorded_split


def is_finished(out: Path) -> bool:
    """Whether ``out`` holds a finished run to check: ``last.pt``, and :func:`ran_to_end`
    (``train --resume`` checks it as any run, then leaves it as it is)."""
    return (out / "last.pt").is_file() and ran_to_end(out)


def finished_summary(out: Path, ckpt: dict[str, Any]) -> dict[str, Any]:
    """What ``train --resume`` returns for a finished run (:func:`is_finished`), from its
    ``last.pt`` as :func:`resume_checkpoint` loaded and checked it.

    Returns:
        ``out_dir``, ``finished`` (True), ``epochs_run`` (0), ``best_epoch`` and ``best_score``.
    """
    return {
        "out_dir": str(out),
        "finished": True,
        "epochs_run": 0,
        "best_epoch": int(ckpt["best_epoch"]),
        "best_score": float(ckpt["best_score"]),
    }


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
    _check_settings(out, saved, cfg)
    # absent only if killed before its first config.json
    info = read_run_info(out) if (out / "config.json").is_file() else None
    # checked first: the messages below name its data_dirs
    recorded = None if info is None else recorded_split(info, out / "config.json")
    if ckpt["data_digest"] != digests[0]:
        given = "" if info is None else f": pass {_data_option(info)}"
        raise ValueError(
            f"{out}: --resume with different data (the --data folders' index.csv digest is not "
            f"the run's data_digest); expected the run's own dataset folders, unchanged{given}"
        )
    if "augment_rng" not in ckpt:
        raise ValueError(
            f"{out / 'last.pt'}: written by an older contactcal (no augmentation generator "
            "state), cannot be resumed exactly; start a new run"
        )
    if info is not None and recorded is not None:
        if info.get("render_digest", digests[1]) != digests[1]:
            raise ValueError(
                f"{out}: --resume with data rendered otherwise (the folders' config.json digest "
                "differs from the run's render_digest: another size, spp, seed or variant); "
                "expected the run's own renders: put them back, or start a new run"
            )
        check_same_split(
            recorded,
            split,
            f"{out}: the split of this --resume's --data",
            f"expected the run's own dataset folders: pass {_data_option(info)} "
            "(any spelling; a run whose split an older contactcal recorded on other spellings "
            "cannot be resumed exactly: start a new run)",
        )
    return ckpt


def _data_option(info: dict[str, Any]) -> str:
    """``--data DIR...`` with the run's dataset folders (its ``config.json``'s ``data_dirs``),
    quoted for a shell (a folder with a space in its name is one argument)."""
    return shlex.join(["--data", *info["data_dirs"]])


def _check_settings(out: Path, saved: TrainConfig, cfg: TrainConfig) -> None:
    """Refuse settings other than the run's ``saved`` ones (its ``last.pt``'s), naming each,
    saved → given. Options left out take the saved values from the run's ``config.json``; a run
    stopped before it was written has none to take them from, so every setting is named there,
    to be given again."""
    was, now = _resumed_settings(saved), _resumed_settings(cfg)
    if was == now:
        return
    if (out / "config.json").is_file():
        changes = config_changes(was, now)
        remedy = "leave those options out (a resume takes the saved values)"
    else:
        changes = config_changes(was, now, limit=None)
        remedy = (
            "give them as options (this run was stopped before its config.json, which a resume "
            "takes them from, was written)"
        )
    raise ValueError(
        f"{out}: --resume with a different config ({changes}); expected the run's own settings: "
        f"{remedy}, or start a new run in another --out"
    )


def _resumed_settings(cfg: TrainConfig) -> dict[str, Any]:
    """``cfg`` as a dict, less what a resume may change (the device and torch's threads)."""
    settings = config_to_dict(cfg)
    for key in ("device", "num_threads"):
        settings.pop(key)
    return settings

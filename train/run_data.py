"""The frames a training run learns and validates on, and what ``--resume`` checks of them.

:func:`run_data` reads the run's dataset folders, splits their frames by finger
(:func:`split_datasets`: at least 2 training frames and 1 validation finger) and gives the data's
digests and the split as recorded, which ``config.json`` keeps and a resumed run must match.
"""

from __future__ import annotations

from pathlib import Path

from contactcal.infer.bench.dataset import IndexRow, read_datasets
from contactcal.train.config import TrainConfig
from contactcal.train.digest import dataset_digest, render_digest
from contactcal.train.split import Split, split_by_finger, split_record


def split_datasets(cfg: TrainConfig, dirs: list[Path]) -> tuple[list[IndexRow], list[IndexRow]]:
    """Read the datasets and split them by finger (>= 2 training frames)."""
    train_rows, val_rows = split_by_finger(read_datasets(dirs), cfg.val_fraction, cfg.seed)
    if len(train_rows) < 2:
        raise ValueError(
            f"{dirs[0]}: need >= 2 training frames after the split, got {len(train_rows)}"
        )
    if not val_rows:
        fingers = len({r.finger_key for r in train_rows})
        raise ValueError(
            f"{', '.join(map(str, dirs))}: {fingers} finger(s), none left for validation; "
            "expected >= 2 fingers (validation chooses best.pt, and export calibrates the "
            "area interval on the validation fingers)"
        )
    return train_rows, val_rows


def run_data(
    cfg: TrainConfig, dirs: list[Path]
) -> tuple[list[IndexRow], list[IndexRow], tuple[str, str], Split]:
    """The run's frames split by finger, the data's digests (``dataset_digest``,
    ``render_digest``) and the split as recorded, all that ``--resume`` checks against the run."""
    train_rows, val_rows = split_datasets(cfg, dirs)  # validates the folders first
    digests = (dataset_digest(dirs), render_digest(dirs))
    return train_rows, val_rows, digests, split_record(train_rows, val_rows)

"""The datasets a restating tool calibrates a model's metadata on: checked, then recorded.

:mod:`contactcal.train.interval` (``interval``) and :mod:`contactcal.train.change_gate`
(``min_change``) calibrate on validation renders, never on the model's training data. Before any
frame is read, :func:`calibration_folders` refuses (before the model is read):

* a path that is no dataset folder, or a ``contactcal procedural`` cross-check set (``--data D:
  ...``, as ``contactcal train`` says it:
  :func:`~contactcal.train.render_sets.check_render_folders`);
* a folder given twice (the same resolved path): its frames would count twice;

and :func:`calibration_data`, given the model's metadata:

* the model's training data, as far as the model records it. Its metadata's ``data_digest`` is
  :func:`~contactcal.train.digest.dataset_digest` of its training folders' ``index.csv`` files,
  concatenated in training order (a run's ``config.json`` ``data_digest``, copied by
  ``contactcal export``; the folder names are not recorded). A calibration folder, or a run of
  consecutive calibration folders as given, with that digest is refused.

Not checked, since the model records nothing that could tell: one of several training folders
given alone, the training folders in another order or with other folders between them, a copy
whose ``index.csv`` differs in any byte, the run's validation fingers (they are inside the
training folders), and benchmark or held-out check sets (no model records them). A model whose
``data_digest`` is empty gets the duplicate check only.

The written entry records what it was calibrated on (:data:`CALIBRATION_DATA_KEY`, provenance
that deployment accepts and does not interpret): per folder its name, the sha256 of its
``index.csv`` and its frame count.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from contactcal.infer.bench.dataset import read_index
from contactcal.infer.methods.unet.spec import CALIBRATION_DATA_KEY
from contactcal.train.digest import dataset_digest
from contactcal.train.render_sets import check_render_folders


def calibration_folders(data_dirs: Sequence[str | os.PathLike[str]]) -> list[Path]:
    """The ``--data`` folders as paths, each a dataset folder and given once.

    Args:
        data_dirs: the ``--data`` folders (``contactcal synth`` layout), in the order given.

    Raises:
        ValueError: a folder that is not a dataset or is a procedural cross-check set, or a
            folder given twice (the message names
            the folder and the option).
    """
    dirs = [Path(d) for d in data_dirs]
    check_render_folders(dirs)
    _refuse_repeats(dirs)
    return dirs


def calibration_data(dirs: Sequence[Path], metadata: Mapping[str, str]) -> list[dict[str, Any]]:
    """Refuse the model's training data among ``dirs`` and describe them.

    Args:
        dirs: :func:`calibration_folders`.
        metadata: the metadata of the model to be calibrated (its ``data_digest``).

    Returns:
        Per folder ``{"folder": name, "index_sha256": hex, "frames": index rows}`` (what
        :func:`with_record` writes).

    Raises:
        ValueError: the model's training data (the message names the folders and the option).
    """
    frames = [len(read_index(d)) for d in dirs]
    _refuse_training_data(dirs, metadata.get("data_digest", ""))
    return [
        {"folder": d.resolve().name, "index_sha256": dataset_digest([d]), "frames": n}
        for d, n in zip(dirs, frames, strict=True)
    ]


def _refuse_repeats(dirs: Sequence[Path]) -> None:
    """Raise ValueError naming a folder given twice (compared as resolved paths)."""
    first: dict[Path, Path] = {}
    for d in dirs:
        same = first.setdefault(d.resolve(), d)
        if same is not d:
            raise ValueError(
                f"--data {d}: the same folder as {same}, given twice (its frames would count "
                "twice); expected each dataset folder once"
            )


def _refuse_training_data(dirs: Sequence[Path], digest: str) -> None:
    """Raise ValueError when a run of consecutive ``dirs`` has the model's training ``digest``."""
    if not digest:
        return
    for i in range(len(dirs)):
        for j in range(i + 1, len(dirs) + 1):
            if dataset_digest(dirs[i:j]) == digest:
                raise ValueError(
                    f"--data {' '.join(str(d) for d in dirs[i:j])}: the model was trained on "
                    "this data (its index.csv digest is the model's data_digest); expected "
                    "validation renders it was not trained on"
                )


def with_record(entry: str, record: Sequence[dict[str, Any]]) -> str:
    """A metadata entry's text with its calibration record (:data:`CALIBRATION_DATA_KEY`).

    Args:
        entry: the entry as :meth:`ModelSpec.to_metadata` writes it: ``interval``'s JSON object
            (the record becomes one more key) or ``min_change``'s number (it becomes
            ``{"value": number, "data": record}``).
        record: :func:`calibration_data`'s record.

    Returns:
        Standard JSON (a non-finite number raises ValueError).
    """
    value = json.loads(entry)
    fields = value if isinstance(value, dict) else {"value": value}
    return json.dumps({**fields, CALIBRATION_DATA_KEY: list(record)}, allow_nan=False)

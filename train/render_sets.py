"""The ``--data`` folders that training and the tools tuned on data may read.

``contactcal train``, ``contactcal quantize`` and the restating tools
(:mod:`contactcal.train.interval`, :mod:`contactcal.train.change_gate`) learn or tune on their
``--data``. A cross-check set written by ``contactcal procedural`` has the same layout as a
``contactcal synth`` dataset, so every reader accepts it, but it exists to score a model on a
generator it never saw (``docs/crosscheck.md``): trained or tuned on, it stops being one.
:func:`check_render_folders` refuses it, before any work, by its ``config.json``: the generator's
config (``contactcal.synth.procedural.config.GeneratorConfig``: ``supersample``, no ``render``),
where a synth dataset's records its ``render`` settings. Imports no torch.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from contactcal.infer.bench.dataset import check_dataset_folder
from contactcal.infer.files.regular import read_input_json

#: A ``config.json`` key of ``contactcal procedural`` sets (its frames are drawn supersampled),
#: absent from ``contactcal synth`` datasets, whose rendering is under ``render``.
PROCEDURAL_KEY = "supersample"


def is_procedural_set(folder: Path) -> bool:
    """Whether ``folder``'s ``config.json`` is a ``contactcal procedural`` set's (an unreadable
    or absent one is not: the readers name whatever else is wrong with the folder)."""
    try:
        config = read_input_json(folder / "config.json", "the set's config.json", ValueError)
    except (OSError, ValueError):
        return False
    return isinstance(config, dict) and PROCEDURAL_KEY in config and "render" not in config


def check_render_folders(dirs: Sequence[Path]) -> None:
    """Refuse a ``--data`` folder that is no dataset, or is a procedural cross-check set.

    Args:
        dirs: the ``--data`` folders.

    Raises:
        ValueError: ``--data FOLDER: ...`` naming the folder and what was expected.
    """
    for d in dirs:
        check_dataset_folder(d, "--data")
        if is_procedural_set(d):
            raise ValueError(
                f"--data {d}: a cross-check set written by `contactcal procedural` (its "
                "config.json), for `contactcal bench --crosscheck` only: trained or tuned on, it "
                "checks nothing; expected a dataset written by `contactcal synth`"
            )

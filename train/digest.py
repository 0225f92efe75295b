"""Digests of dataset folders, recorded by a run and checked by ``export``, ``--resume`` and the
restating tools. Imports no torch: :mod:`contactcal.train.interval` and
:mod:`contactcal.train.change_gate` use them on exported models, without the training stack."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Sequence
from pathlib import Path

from contactcal.infer.files.regular import read_input_bytes, refuse_special


def dataset_digest(data_dirs: Sequence[str | os.PathLike[str]]) -> str:
    """sha256 (hex) of the concatenated index.csv files, in the given order."""
    h = hashlib.sha256()
    for d in data_dirs:
        h.update(read_input_bytes(Path(d) / "index.csv", "the dataset's index.csv", ValueError))
    return h.hexdigest()


def render_digest(data_dirs: Sequence[str | os.PathLike[str]]) -> str:
    """sha256 (hex) of the folders' ``config.json`` files (how each set was rendered: size, spp,
    seeds, Mitsuba variant), in the given order; a folder without one (a set written by another
    generator) counts as a fixed marker. :func:`dataset_digest` covers the frames' rows only, and
    a re-render at another spp or variant writes the same index.csv.
    """
    h = hashlib.sha256()
    for d in data_dirs:
        path = Path(d) / "config.json"
        refuse_special(path, "the dataset's config.json (how the set was rendered)", ValueError)
        h.update(path.read_bytes() if path.is_file() else b"(no config.json)")
        h.update(b"\0")
    return h.hexdigest()

"""The argument parser of every ``contactcal`` command line (and its ``python -m`` tools): what
an option accepts is decided here once."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def _nonempty(value: str, expected: str, hint: str = "") -> Path:
    """``value`` as a :class:`~pathlib.Path`, refusing an empty string, which ``Path`` would
    silently turn into ``.`` (the current folder: a run would read or write there).

    Args:
        value: the option's value.
        expected: what the option takes, e.g. ``"a file path"``.
        hint: appended to the refusal, e.g. how to name the current folder.

    Raises:
        argparse.ArgumentTypeError: ``value`` is empty (argparse names the option).
    """
    if not value:
        raise argparse.ArgumentTypeError(f"'': expected {expected}, got an empty string{hint}")
    return Path(value)


def path_arg(value: str) -> Path:
    """A file option's value (``type=Path`` in a :class:`Parser`) as a :class:`~pathlib.Path`,
    refusing an empty string (:func:`_nonempty`).

    Raises:
        argparse.ArgumentTypeError: ``value`` is empty.
    """
    return _nonempty(value, "a file path")


def folder_arg(value: str) -> Path:
    """The value of an option that may name a folder (``type=folder_arg``: an output folder, a
    dataset, a folder or a file) as a :class:`~pathlib.Path`, refusing an empty string
    (:func:`_nonempty`) with the hint to give ``.`` for the current folder.

    Raises:
        argparse.ArgumentTypeError: ``value`` is empty.
    """
    return _nonempty(value, "a file or folder path", " (for the current folder give '.')")


class Parser(argparse.ArgumentParser):
    """argparse without prefix matching (``--ref`` is not taken for ``--reference``), whose
    ``type=Path`` options (files) go through :func:`path_arg`; an option that may name a folder
    is declared ``type=folder_arg``.

    An abbreviation recorded in ``calibration.json``'s ``argv`` would change its meaning, or stop
    parsing, the day an option sharing its prefix is added. The subcommands' parsers are of this
    class too (``add_subparsers`` makes its parsers of the parent's class).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self.register("type", Path, path_arg)

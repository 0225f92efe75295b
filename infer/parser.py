"""The argument parser of every ``contactcal`` command line (and its ``python -m`` tools): what
an option accepts is decided here once."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def path_arg(value: str) -> Path:
    """A path option's value as a :class:`~pathlib.Path`, refusing an empty string, which
    ``Path`` would silently turn into ``.`` (the current folder: a run would read or write there).

    Raises:
        argparse.ArgumentTypeError: ``value`` is empty (argparse names the option).
    """
    if not value:
        raise argparse.ArgumentTypeError(
            "'': expected a file or folder path, got an empty string (for the current folder "
            "give '.')"
        )
    return Path(value)


class Parser(argparse.ArgumentParser):
    """argparse without prefix matching (``--ref`` is not taken for ``--reference``), whose
    ``type=Path`` options go through :func:`path_arg`.

    An abbreviation recorded in ``calibration.json``'s ``argv`` would change its meaning, or stop
    parsing, the day an option sharing its prefix is added. The subcommands' parsers are of this
    class too (``add_subparsers`` makes its parsers of the parent's class).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self.register("type", Path, path_arg)

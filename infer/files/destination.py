"""Where an output may go: never onto an input of the run, a symbolic link (or, through it, its
target) or anything that is not a regular file (a device, a folder, a pipe); and how a refused
destination names the command-line option that gave it (``--out OUT: ...``)."""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterable, Mapping
from pathlib import Path

from contactcal.infer.errors import option_error


class OutputError(ValueError):
    """An output path that must not be written (an input, a link, a device); names the path."""


class LinkOutputError(OutputError):
    """An output path that is a symbolic link; a command whose output has another form adds it
    (``measure``: ``--out -``, standard output)."""


def check_destination(path: str | os.PathLike[str], protect: Iterable[Path] = ()) -> None:
    """Refuse a destination that is a link, not a regular file, or one of the inputs.

    Args:
        path: the output path.
        protect: the run's input files (compared by device and inode, so another spelling or a
            hard link of an input is refused too).

    Raises:
        OutputError: the message names the path and says what to do instead.
    """
    p = Path(path)
    check_receiving_folder(p)
    try:
        st = os.lstat(p)
    except (FileNotFoundError, NotADirectoryError):
        return  # nothing there to replace
    if stat.S_ISLNK(st.st_mode):
        raise LinkOutputError(
            f"{p}: is a symbolic link; outputs never replace a link or its target; give a "
            "regular file path"
        )
    if not stat.S_ISREG(st.st_mode):
        raise OutputError(
            f"{p}: exists and is not a regular file (a folder, device or pipe); "
            "outputs replace only regular files"
        )
    for q in protect:
        with contextlib.suppress(OSError):
            qs = os.stat(q)
            if (qs.st_dev, qs.st_ino) == (st.st_dev, st.st_ino):
                raise OutputError(
                    f"{p}: is an input of this run ({q}); refusing to overwrite it "
                    "(choose another output path)"
                )


def check_receiving_folder(path: str | os.PathLike[str]) -> None:
    """Refuse an output whose nearest existing folder above it is a link or not a folder.

    That folder gets the new entries (the output, or the missing folders on its way).

    Raises:
        OutputError: naming that folder.
    """
    final = Path(os.path.abspath(path))
    receiving = next(p for p in (final.parent, *final.parents) if os.path.lexists(p))
    if receiving.is_symlink():
        raise OutputError(
            f"{receiving}: is a symbolic link to a folder; outputs never write "
            f"through a link into its target (give the folder itself: "
            f"{receiving.resolve()})"
        )
    if not receiving.is_dir():
        raise OutputError(f"{receiving}: is not a folder; cannot write outputs into it")


def by_option(
    path: str | os.PathLike[str], exc: Exception, options: Mapping[str, Path]
) -> Exception:
    """``exc``, a refusal to write ``path``, led by the option that gave ``path``.

    Args:
        path: the refused destination.
        exc: why it was refused (an :class:`OutputError`, or the ``OSError`` of a folder that
            could not be made).
        options: option → its value as given (``{"--out": Path("out")}``); ``path`` is that
            value or inside it; the innermost one names it.

    Returns:
        ``OPTION VALUE: ...`` (:func:`~contactcal.infer.errors.option_error`; an
        :class:`OutputError` keeps its class), or ``exc`` itself where no option gave ``path``.
    """
    final = Path(os.path.abspath(path))
    given = {o: Path(os.path.abspath(v)) for o, v in options.items()}
    under = [o for o, v in given.items() if v == final or v in final.parents]
    if not under:
        return exc
    option = max(under, key=lambda o: len(given[o].parts))
    named = option_error(option, options[option], exc)
    return type(exc)(str(named)) if isinstance(exc, OutputError) else named

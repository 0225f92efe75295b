"""Reading a user-given input file, refusing one that is not a regular file.

A device (``/dev/zero``), a FIFO or a socket, or a link to one, named where a file is expected,
would be read until memory runs out or waited on forever; it is refused unread, in one line
naming it and what was expected, as a folder is. A FIFO is never opened in blocking mode.
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO


def input_flags(platform: Any = os) -> int:
    """``os.open`` flags of an input: read-only, binary (Windows' C runtime would otherwise open
    the file in text mode, turning CR LF into LF and stopping at Ctrl-Z) and non-blocking (a FIFO
    put in place after the type check is not waited on), each where ``platform`` (the ``os``
    module) defines it: Windows has neither ``O_NONBLOCK`` nor FIFOs, POSIX no ``O_BINARY``."""
    binary, nonblocking = getattr(platform, "O_BINARY", 0), getattr(platform, "O_NONBLOCK", 0)
    return platform.O_RDONLY | binary | nonblocking


#: :func:`input_flags` of this platform.
READ_FLAGS = input_flags()


def not_regular_message(path: str | os.PathLike[str], expected: str) -> str:
    """The one line refusing ``path``, which is not a regular file; ``expected``: what the
    reader expected there, e.g. ``"the manifest CSV"``."""
    return f"{path}: not a regular file (a device, pipe or socket); expected {expected}"


def folder_message(path: str | os.PathLike[str], expected: str) -> str:
    """The one line refusing ``path``, a folder; ``expected``: what the reader expected there,
    e.g. ``"the manifest CSV"``."""
    return f"{path}: is a folder; expected {expected}"


def _special(mode: int) -> bool:
    """Whether ``mode`` is neither a regular file's nor a folder's."""
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def _refuse_mode(
    path: str | os.PathLike[str], mode: int, expected: str, error: Callable[[str], Exception]
) -> None:
    """Raise ``error(line)`` when ``mode`` (``path``'s) is not a regular file's."""
    if stat.S_ISDIR(mode):
        raise error(folder_message(path, expected))
    if _special(mode):
        raise error(not_regular_message(path, expected))


def _mode(path: str | os.PathLike[str]) -> int | None:
    """``path``'s mode, links followed; None: missing or unstatable (the caller's own open or
    check reports it)."""
    try:
        return os.stat(path).st_mode
    except (OSError, ValueError):
        return None


def refuse_special(
    path: str | os.PathLike[str], expected: str, error: Callable[[str], Exception]
) -> None:
    """Raise ``error(line)`` when ``path`` (links followed) is a device, pipe or socket; a
    missing or unstatable path passes (the caller's own open or check reports it).

    Args:
        path: the input file.
        expected: what was expected there (:func:`not_regular_message`).
        error: the caller's exception type, built from the message line.
    """
    mode = _mode(path)
    if mode is not None and _special(mode):
        raise error(not_regular_message(path, expected))


def refuse_non_file(
    path: str | os.PathLike[str], expected: str, error: Callable[[str], Exception]
) -> None:
    """Raise ``error(line)`` when ``path`` (links followed) is a folder
    (:func:`folder_message`), or a device, pipe or socket (:func:`not_regular_message`); a
    missing or unstatable path passes (the caller's own open or check reports it).

    Args:
        path: the input file.
        expected: what was expected there, e.g. ``"the manifest CSV"``.
        error: the caller's exception type, built from the message line.
    """
    mode = _mode(path)
    if mode is not None:
        _refuse_mode(path, mode, expected, error)


def open_input(
    path: str | os.PathLike[str], expected: str, error: Callable[[str], Exception]
) -> BinaryIO:
    """A user-given input file opened for binary reading, refusing a folder, device, pipe or
    socket unread (checked before opening, and on the opened file: opened non-blocking, a FIFO
    put there in between never blocks).

    Args:
        path: the input file.
        expected: what was expected there, e.g. ``"the manifest CSV"``.
        error: the caller's exception type, built from the message line.

    Raises:
        error: ``path`` is a folder or not a regular file.
        OSError: as ``open`` raises it (FileNotFoundError, PermissionError, ...), for the
            caller's own messages.
    """
    p = Path(path)
    refuse_non_file(p, expected, error)
    fd = os.open(p, READ_FLAGS)
    try:
        _refuse_mode(p, os.fstat(fd).st_mode, expected, error)
    except BaseException:
        os.close(fd)
        raise
    return os.fdopen(fd, "rb")


def read_input_bytes(
    path: str | os.PathLike[str], expected: str, error: Callable[[str], Exception]
) -> bytes:
    """The whole content of a user-given input file, read once (:func:`open_input`; raises as
    it does)."""
    with open_input(path, expected, error) as fh:
        return fh.read()


def read_input_json(
    path: str | os.PathLike[str], expected: str, error: Callable[[str], Exception]
) -> Any:
    """The JSON value in a user-given input file: its content, read once
    (:func:`read_input_bytes`), decoded as UTF-8 and parsed (:func:`parse_input_json`).

    A decode or syntax error is raised as Python's own (both are ValueError), not in the caller's
    type, and JSON no reader takes as a syntax error (:func:`parse_input_json`): each caller
    words the refusal of a damaged file its own way (or reads it as "no record there"), or
    leaves it to :func:`read_record_json`. Arguments as :func:`open_input`'s.

    Raises:
        error, OSError: as :func:`open_input` raises them.
        UnicodeDecodeError: the content is not UTF-8 text.
        json.JSONDecodeError: the text is not valid JSON, or JSON no reader takes (an integer
            over Python's digit limit, nesting deeper than its recursion limit).
    """
    return parse_input_json(read_input_bytes(path, expected, error).decode("utf-8"))


def parse_input_json(
    text: str, object_pairs_hook: Callable[[list[tuple[str, Any]]], Any] | None = None
) -> Any:
    """The JSON value in ``text``, user-given (an input file's, a model's metadata entry), as
    ``json.loads(text, object_pairs_hook=...)`` parses it; JSON no reader takes is refused as
    invalid JSON, so that each caller's refusal of invalid JSON (one line naming the input)
    covers it too.

    Raises:
        json.JSONDecodeError: the text is not valid JSON, or JSON no reader takes (an integer
            over Python's digit limit, nesting deeper than its recursion limit).
        Exception: as ``object_pairs_hook`` raises it (one that is no ValueError: a
            ValueError is taken for JSON no reader takes).
    """
    try:
        return json.loads(text, object_pairs_hook=object_pairs_hook)
    except json.JSONDecodeError:
        raise
    except (ValueError, RecursionError) as exc:  # raised as what it is: JSON no reader takes
        raise json.JSONDecodeError(f"unreadable JSON value ({exc})", text, 0) from None


def read_record_json(path: str | os.PathLike[str], expected: str) -> Any:
    """The JSON value in ``path``, a file a run wrote (a record, a config), read as every input
    is (:func:`read_input_json`), or one line refusing it: naming it, what it is, and
    ``expected`` (what a run writes there, and what to do).

    Raises:
        ValueError: ``path`` is a folder, not a regular file, cannot be read (missing, a
            permission error, ...), is not UTF-8 text, or not valid JSON.
    """
    try:
        return read_input_json(path, expected, ValueError)
    except UnicodeDecodeError:
        why = "not UTF-8 text"
    except json.JSONDecodeError as exc:
        why = f"{exc.msg}: line {exc.lineno} column {exc.colno}"
    except OSError as exc:
        raise ValueError(
            f"{path}: cannot be read ({exc.strerror or exc}); expected {expected}"
        ) from None
    raise ValueError(f"{path}: not valid JSON ({why}); expected {expected}")

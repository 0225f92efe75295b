"""Content digests of files, for records of what a run read (frames, manifests, models)."""

from __future__ import annotations

import os
from collections.abc import Callable

from contactcal.infer.files.regular import open_input

#: Read size, bytes (bounded memory for large files).
_CHUNK = 1 << 20


def sha256_file(
    path: str | os.PathLike[str],
    expected: str = "a file",
    error: Callable[[str], Exception] = ValueError,
) -> str:
    """The sha256 of a file's content, lower-case hex (64 characters), streamed; the file is
    opened as every input is (:func:`~contactcal.infer.files.regular.open_input`: a folder,
    device or pipe is refused unread, a FIFO never waited on).

    Args:
        path: the file.
        expected: what was expected there, for the refusal (e.g. ``"a video file"``).
        error: the exception type of the refusal, built from its message line.

    Raises:
        error: ``path`` is a folder, or not a regular file (a device, pipe or socket).
        OSError: missing or unreadable file (the message names it).
    """
    import hashlib  # here, not at the top: its OpenSSL start (~5 ms) is not measure's

    h = hashlib.sha256()
    with open_input(path, expected, error) as fh:
        while chunk := fh.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def sha256_bytes(data: bytes) -> str:
    """The sha256 of bytes already read, lower-case hex (64 characters): the digest of the very
    content a run decoded (a file read again could have changed in between)."""
    import hashlib

    return hashlib.sha256(data).hexdigest()

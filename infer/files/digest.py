"""Content digests of files, for records of what a run read (frames, manifests, models)."""

from __future__ import annotations

import os

#: Read size, bytes (bounded memory for large files).
_CHUNK = 1 << 20


def sha256_file(path: str | os.PathLike[str]) -> str:
    """The sha256 of a file's content, lower-case hex (64 characters).

    Raises:
        OSError: unreadable file (the message names it).
    """
    import hashlib  # here, not at the top: its OpenSSL start (~5 ms) is not measure's

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def sha256_bytes(data: bytes) -> str:
    """The sha256 of bytes already read, lower-case hex (64 characters): the digest of the very
    content a run decoded (a file read again could have changed in between)."""
    import hashlib

    return hashlib.sha256(data).hexdigest()

"""Atomic file output: write to a temporary file in the same folder, then rename.

A reader (or a resumed run) therefore sees either the complete old file, the complete new
file, or no file, never a truncated one.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` on success.

    Args:
        path: final destination. Its parent folder is created if missing.

    Yields:
        A temporary path with the same suffix (so writers that infer the format from the
        extension, like ``cv2.imwrite`` or matplotlib, still work). On an exception the
        temporary file is removed and ``path`` is left untouched.
    """
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{final.stem}.", suffix=f".tmp{final.suffix}", dir=final.parent
    )
    os.close(fd)
    tmp = Path(tmp_name)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; give the usual permissions
    try:
        yield tmp
        os.replace(tmp, final)
    finally:
        if tmp.exists():
            tmp.unlink()


def _sync(fh: IO[Any]) -> None:
    fh.flush()
    os.fsync(fh.fileno())


def write_synced(path: str | os.PathLike[str], text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` (e.g. a temporary path) and fsync it; not atomic itself."""
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
        _sync(fh)


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open a temporary file for writing; it replaces ``path`` only if the block succeeds.

    Args:
        path: final destination.
        mode: ``"w"`` (text, UTF-8, ``\\n`` newlines) or ``"wb"``.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open: expected mode 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        if mode == "w":
            with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
                yield fh
                _sync(fh)
        else:
            with open(tmp, "wb") as fh:
                yield fh
                _sync(fh)


def write_json(path: str | os.PathLike[str], obj: Any) -> None:
    """Write ``obj`` as indented JSON, atomically. Rejects NaN/inf (``allow_nan=False``)."""
    text = json.dumps(obj, indent=2, allow_nan=False)
    with atomic_open(path, "w") as fh:
        fh.write(text + "\n")


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) atomically."""
    with atomic_open(path, "w") as fh:
        fh.write(text)

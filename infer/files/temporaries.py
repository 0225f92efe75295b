"""Staging folders named by the process that writes them, and their removal once it is gone.

A run stages its outputs in a folder beside their destination, named
``.<name>.<pid>.<random>.tmp`` (:data:`TEMP_NAME`; ``name``: what it stages, ``pid``: the
writing process). A process killed with ``kill -9`` leaves its staging folder behind; the next
write into that folder removes the temporaries of processes that no longer run
(:func:`remove_stale_temporaries`); those of running processes are kept.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
from pathlib import Path

#: Names of the staging folders: ``.<name>.<pid>.<random>.tmp``.
TEMP_NAME = re.compile(r"^\..+\.(?P<pid>[0-9]+)\.[A-Za-z0-9_]+\.tmp$")


def make_staging_folder(folder: Path, name: str) -> Path:
    """Create a new, empty staging folder for ``name`` in ``folder`` (:data:`TEMP_NAME`).

    Raises:
        OSError: it cannot be created (as ``tempfile.mkdtemp`` raises it).
    """
    prefix = f".{name}.{os.getpid()}."
    return Path(tempfile.mkdtemp(prefix=prefix, suffix=".tmp", dir=folder))


def _pid_running(pid: int) -> bool:
    """Whether process ``pid`` exists (POSIX); elsewhere every pid counts as running."""
    if pid == os.getpid():
        return True
    if os.name != "posix":
        return True  # os.kill(pid, 0) would signal the process on Windows
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # exists, owned by another user
    return True


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporaries (:data:`TEMP_NAME`) of processes that no longer run in ``folder``.

    Returns:
        The removed paths.
    """
    removed: list[Path] = []
    with contextlib.suppress(FileNotFoundError, NotADirectoryError):
        for entry in os.scandir(folder):
            match = TEMP_NAME.match(entry.name)
            if match is None or _pid_running(int(match["pid"])):
                continue
            with contextlib.suppress(FileNotFoundError):  # another process removed it first
                if entry.is_dir(follow_symlinks=False):
                    shutil.rmtree(entry.path)
                else:
                    os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed

"""One run per shard at a time: the lock ``run_shard{i}of{n}.lock`` in a ``contactcal synth``
folder.

Two runs of one shard into one folder would render the same frames side by side and leave only
one of them on the shard's run record (:mod:`~contactcal.synth.run_record`). A run therefore
holds an exclusive :func:`fcntl.flock` on the shard's lock file, which holds its pid, from
before its first render to its end, and removes the file as it ends; a second run of that shard
is refused at once, naming the folder, the shard and the holder's pid. Runs of other shards lock
other files and run alongside. The system releases the lock when its process ends however it
ends, so the file a killed run left blocks nothing: the next run takes it over and says so.
Without :mod:`fcntl` (Windows) no lock is taken: run one process per shard and folder there.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows
    fcntl = None  # type: ignore[assignment]


def lock_path(root: Path, shard: tuple[int, int]) -> Path:
    """The lock of shard ``(i, n)``: ``run_shard{i}of{n}.lock``."""
    return root / f"run_shard{shard[0]}of{shard[1]}.lock"


@contextlib.contextmanager
def shard_lock(root: Path, shard: tuple[int, int]) -> Iterator[None]:
    """Hold shard ``shard`` of the dataset folder ``root`` (which exists) for this run.

    Raises:
        ValueError: another running process holds the shard (named with its pid).
        OSError: the lock file cannot be created or locked.
    """
    if fcntl is None:
        yield
        return
    path = lock_path(root, shard)
    fd = _lock(root, shard, path)
    try:
        yield
    finally:
        path.unlink(missing_ok=True)  # before the lock is released: a waiting run makes anew
        os.close(fd)


def _lock(root: Path, shard: tuple[int, int], path: Path) -> int:
    """Lock ``path`` (created if missing) and write this run's pid into it; returns its fd."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _pid_in(fd)
            os.close(fd)
            raise ValueError(
                f"--out {root}: shard {shard[0]}/{shard[1]} is being rendered by another run "
                f"({f'pid {holder}' if holder else 'pid not yet written'}; it holds {path.name}); "
                "wait for it to end, or render another --shard into this folder"
            ) from None
        if _same_file(fd, path):
            break
        os.close(fd)  # the run that held it removed it as it ended: lock the new file
    if left := _pid_in(fd):
        print(f"synth: {path} of an ended run (pid {left}) taken over", file=sys.stderr)
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()}\n".encode())
    return fd


def _pid_in(fd: int) -> str:
    """The pid the lock file ``fd`` holds ("" for none)."""
    text = os.pread(fd, 32, 0).decode("ascii", errors="replace").strip()
    return text if text.isdigit() else ""


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` is still the file open as ``fd`` (not removed or replaced since)."""
    try:
        now = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino)

"""Holding Ctrl-C back while an all-or-nothing step finishes (:mod:`.atomic`'s renames)."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) back for the block, delivered after it: the renames of a commit take
    microseconds, and a run interrupted between two of them would leave half its outputs. Only in
    the main thread on POSIX (elsewhere the block runs as is)."""
    main = threading.current_thread() is threading.main_thread()
    if not main or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)

"""Stopping a run cleanly: SIGTERM and SIGHUP handled as Ctrl-C, and all three held back while an
all-or-nothing step finishes (:mod:`.atomic`'s renames)."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

#: Signals that stop a run as Ctrl-C does: SIGTERM (``kill``, a job scheduler's stop) and SIGHUP
#: (the terminal closed), where the platform has them.
STOP_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)
)


class Terminated(KeyboardInterrupt):
    """A stop signal, raised where the run is, so that it unwinds as on Ctrl-C (outputs staged
    so far are discarded).

    Attributes:
        signum: the signal's number (exit status ``128 + signum``, as the shell reports it).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    raise Terminated(signum)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def stop_signals_interrupt() -> Iterator[None]:
    """In the block, :data:`STOP_SIGNALS` raise :class:`Terminated`; the handlers before it are
    restored after. A signal someone chose to ignore (``nohup`` ignores SIGHUP) stays ignored,
    and so does any handler other than the default. Only in the main thread (elsewhere the
    block runs as is)."""
    if not _in_main_thread():
        yield
        return
    before = {s: signal.getsignal(s) for s in STOP_SIGNALS}
    for s, handler in before.items():
        if handler is signal.SIG_DFL:
            signal.signal(s, _raise_terminated)
    try:
        yield
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


@contextlib.contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) and :data:`STOP_SIGNALS` back for the block, delivered after it: the
    renames of a commit take microseconds, and a run stopped between two of them would leave
    half its outputs. Only in the main thread on POSIX (elsewhere the block runs as is)."""
    if not _in_main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, *STOP_SIGNALS})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)

"""Standard output that names itself when it fails (a full disk, a closed pipe)."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator, Sequence
from typing import Any, TextIO


class StdoutError(OSError):
    """Writing to standard output failed: its message says so, unlike the bare OSError's
    ``[Errno 28] No space left on device``; and, where the run had already written its outputs
    (``written``: files or folders), that those are whole."""

    def __init__(
        self,
        errno: int | None,
        strerror: str | None,
        written: Sequence[str] = (),
        notes: Sequence[str] = (),
    ) -> None:
        super().__init__(errno, strerror)
        self.written = tuple(written)
        self.notes = tuple(notes)

    def __str__(self) -> str:
        said = f"writing to standard output failed ({self.strerror}): what it printed is incomplete"
        return "; ".join(s for s in (said, written_text(self.written, self.notes)) if s)


def written_text(written: Sequence[str], notes: Sequence[str]) -> str:
    """What a run stopped after its outputs were moved into place must still say: that they are
    written, whole, and the notes it had yet to print ("" when there is nothing to say)."""
    said = [f"the run's outputs were written, whole: {', '.join(written)}"] if written else []
    return "; ".join([*said, *(n.removeprefix("note: ") for n in notes)])


class _Named:
    """``stream`` with ``write`` and ``flush`` raising :class:`StdoutError`; the rest as is."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except OSError as exc:
            raise _named(exc) from exc

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as exc:
            raise _named(exc) from exc

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _named(exc: OSError) -> StdoutError:
    return StdoutError(exc.errno, exc.strerror)


@contextlib.contextmanager
def printing_after(
    written: Sequence[str | os.PathLike[str]], notes: Sequence[str | None] = ()
) -> Iterator[None]:
    """A block that prints a run's summary after the run's outputs were moved into place: a
    failed write to standard output there says that ``written`` (files or folders) are whole,
    and repeats ``notes`` the block would print that must not be lost (an earlier calibration
    replaced; None: no note). The exit status stays that of a failed standard output. The
    block's lines are flushed at its end, so that their failure surfaces here. An interrupt
    (Ctrl-C, a stop signal) there carries the same words as ``after_outputs``, which the
    command line says instead of "none was written"."""
    try:
        yield
        if sys.stdout is not None:
            sys.stdout.flush()
    except StdoutError as exc:
        names = [*exc.written, *(os.fspath(w) for w in written)]
        kept = [*exc.notes, *(n for n in notes if n is not None)]
        raise StdoutError(exc.errno, exc.strerror, names, kept) from exc
    except KeyboardInterrupt as exc:
        if not hasattr(exc, "after_outputs"):
            kept = [n for n in notes if n is not None]
            said = written_text([os.fspath(w) for w in written], kept)
            exc.after_outputs = said  # type: ignore[attr-defined]
        raise


@contextlib.contextmanager
def named_stdout() -> Iterator[None]:
    """In the block, a failed write to ``sys.stdout`` raises :class:`StdoutError`; at its end
    stdout is flushed, so that the last lines' failure surfaces here and not at exit.

    On a :class:`StdoutError` the stdout file descriptor is pointed at the null device, so that
    the interpreter's own flush at exit does not print a second, unnamed error. Without a
    stdout (``sys.stdout is None``: the process was started with it closed) nothing is wrapped
    and ``print`` stays the no-op it is then.
    """
    before = sys.stdout
    if before is None:  # no stdout at all (closed, or a pythonw-like host): print() is a no-op
        yield
        return
    sys.stdout = _Named(before)  # type: ignore[assignment]
    try:
        yield
        sys.stdout.flush()
    except StdoutError:
        _silence(before)
        raise
    finally:
        sys.stdout = before


def _silence(stream: TextIO) -> None:
    """Point ``stream``'s file descriptor at the null device (Python's advice for SIGPIPE)."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, stream.fileno())
        os.close(null)

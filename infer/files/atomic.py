"""Outputs written all or nothing: staged in a temporary folder, moved into place together.

Every output of a run is first written into a staging folder next to its destination (same file
system, so the final move is a rename). Only when the whole run succeeded are the staged files
renamed onto their destinations, in the order they were staged; on any error the staging folders
(and the output folders this run created) are removed, so nothing of the run appears and files
from an earlier run stay as they were. A reader therefore sees complete old or complete new files.

Outputs never replace an input of the run, a symbolic link (or, through it, its target) or
anything that is not a regular file (a device, a folder, a pipe):
:func:`~contactcal.infer.files.destination.check_destination`. A refused output under a
command-line option's value is named by that option (``--out OUT: ...``; ``options`` of
:func:`run_outputs`).

Staging folders are named by the writing process and the first output staged in them; those a
killed process left are removed by the next write into their folder
(:mod:`~contactcal.infer.files.temporaries`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

from contactcal.infer.files.destination import OutputError, by_option, check_destination
from contactcal.infer.files.interrupt import deferred_interrupt
from contactcal.infer.files.jsonable import json_text
from contactcal.infer.files.stdout import StdoutError
from contactcal.infer.files.temporaries import make_staging_folder, remove_stale_temporaries


class OutputSet:
    """The outputs of one run: staged files that :meth:`commit` moves into place together.

    Use through :func:`run_outputs`.

    Args:
        protect: the run's input files, never to be replaced (see :func:`check_destination`).
        options: the options that name the outputs (see :meth:`name_options`).
    """

    def __init__(
        self,
        protect: Iterable[str | os.PathLike[str] | None] = (),
        options: Mapping[str, str | os.PathLike[str] | None] | None = None,
    ) -> None:
        self._protect: list[Path] = []
        self._options: dict[str, Path] = {}
        self._staged: dict[Path, Path] = {}  # destination → staged file, in staging order
        self._stages: dict[Path, Path] = {}  # destination folder → its staging folder
        self._made: list[Path] = []  # output folders this run created, parents first
        self.protect(*protect)
        self.name_options(options or {})

    def protect(self, *paths: str | os.PathLike[str] | None) -> None:
        """Add input files that no output may replace (None entries are ignored)."""
        self._protect += [Path(p) for p in paths if p is not None]

    def name_options(self, options: Mapping[str, str | os.PathLike[str] | None]) -> None:
        """Name the outputs by the options that gave them: a refused output at or under an
        option's value (``{"--out": args.out}``; None values are ignored) says ``--out OUT:``
        first, the value as given (:func:`~contactcal.infer.files.destination.by_option`)."""
        self._options |= {o: Path(v) for o, v in options.items() if v is not None}

    def stage(self, path: str | os.PathLike[str]) -> Path:
        """The path to write destination ``path`` to (same name, in a staging folder).

        Raises:
            OutputError: ``path`` must not be written, or was staged already in this run.
            OSError: its folder cannot be created (the message names it).
            ValueError: that folder error, for a ``path`` an option gave (named by it).
        """
        try:
            return self._stage(path)
        except (OutputError, OSError) as exc:
            named = by_option(path, exc, self._options)
            if named is exc:
                raise
            raise named from None

    def _stage(self, path: str | os.PathLike[str]) -> Path:
        final = Path(os.path.abspath(path))
        check_destination(final, self._protect)
        if final in self._staged:
            raise OutputError(f"{path}: written twice by one run; give each output its own name")
        stage = self._stages.get(final.parent)
        if stage is None:
            self._make_folder(final.parent)  # its receiving folder: check_destination
            remove_stale_temporaries(final.parent)
            try:
                stage = make_staging_folder(final.parent, final.name)
            except OSError as exc:
                raise OSError(
                    f"{final}: cannot write into its folder {final.parent} ({exc.strerror})"
                ) from exc
            self._stages[final.parent] = stage
        self._staged[final] = stage / final.name
        return self._staged[final]

    def folders(self) -> list[Path]:
        """The folders the staged outputs go to, in staging order."""
        return list(self._stages)

    def _make_folder(self, folder: Path) -> None:
        missing = [p for p in (folder, *folder.parents) if not p.exists()][::-1]
        for p in missing:
            try:
                p.mkdir()
            except FileExistsError:
                pass  # made meanwhile by another process
            except OSError as exc:
                raise OSError(f"{p}: cannot create the output folder ({exc.strerror})") from exc
            else:
                self._made.append(p)
        if not folder.is_dir():
            raise OSError(f"{folder}: is not a folder; cannot write outputs into it")

    def commit(self) -> list[Path]:
        """Sync every staged file, check every destination again, then rename them into place.

        Returns:
            The destinations, in staging order.

        Raises:
            OSError: a staged file was never written (nothing is moved).
            OutputError: a destination became unwritable meanwhile (nothing is moved).
        """
        for final, staged in self._staged.items():
            if not staged.is_file():
                raise OSError(f"{final}: its writer produced no file")
            with open(staged, "rb+") as fh:
                os.fsync(fh.fileno())
            check_destination(final, self._protect)
        with deferred_interrupt():  # all renames or (on an error) the ones done so far
            for final, staged in self._staged.items():
                os.replace(staged, final)
        self._made.clear()  # the folders now hold outputs: keep them
        return list(self._staged)

    def discard(self) -> None:
        """Remove the staging folders and, if nothing was committed, the folders created."""
        for stage in self._stages.values():
            shutil.rmtree(stage, ignore_errors=True)
        for folder in reversed(self._made):
            with contextlib.suppress(OSError):
                folder.rmdir()  # only if empty


@contextlib.contextmanager
def run_outputs(
    protect: Iterable[str | os.PathLike[str] | None] = (),
    join: OutputSet | None = None,
    options: Mapping[str, str | os.PathLike[str] | None] | None = None,
) -> Iterator[OutputSet]:
    """All outputs of a run: stage them in the block, committed when the block succeeds.

    Args:
        protect: the run's input files (never replaced).
        join: an enclosing run's :class:`OutputSet` to stage into instead (the enclosing run
            commits, or discards, everything together).
        options: the command-line options that give the outputs' paths, with their values as
            given (``{"--out": args.out}``): a refused output says which
            (:meth:`OutputSet.name_options`).

    Yields:
        The :class:`OutputSet`; write each output to ``outputs.stage(destination)``.
    """
    if join is not None:
        join.protect(*protect)
        join.name_options(options or {})
        yield join
        return
    outputs = OutputSet(protect, options)
    try:
        yield outputs
        outputs.commit()
    except OSError as exc:
        named = _named(exc, outputs.folders())
        if named is exc:
            raise
        raise named from exc
    finally:
        outputs.discard()


#: errno values of a write that did not fit: the message gets the output folders, which a bare
#: ``[Errno 28] No space left on device`` does not name.
_NO_ROOM = {getattr(errno, n) for n in ("ENOSPC", "EDQUOT", "EFBIG") if hasattr(errno, n)}


def _named(exc: OSError, folders: list[Path]) -> OSError:
    """``exc``, or, for a write that found no room and names no file, an error naming the
    output folders (same ``errno``; the run's staged outputs are discarded)."""
    if exc.errno not in _NO_ROOM or exc.filename is not None or not folders:
        return exc
    if isinstance(exc, StdoutError):  # already names where it failed: standard output
        return exc
    where = ", ".join(str(f) for f in folders)
    named = OSError(f"{where}: {exc.strerror} while writing this run's outputs there")
    named.errno = exc.errno
    return named


@contextlib.contextmanager
def atomic_path(
    path: str | os.PathLike[str], protect: Iterable[str | os.PathLike[str] | None] = ()
) -> Iterator[Path]:
    """Yield a temporary path for ``path``; it is moved onto ``path`` if the block succeeds.

    Args:
        path: final destination. Its parent folder is created if missing.
        protect: input files ``path`` must not be (see :func:`check_destination`).

    Yields:
        A path with the same file name in a staging folder (so writers that infer the format
        from the extension, like ``cv2.imwrite`` or matplotlib, still work). On an exception it
        is removed and ``path`` is left untouched.
    """
    with run_outputs(protect) as outputs:
        yield outputs.stage(path)


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
    text = json_text(obj)
    with atomic_open(path, "w") as fh:
        fh.write(text)


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) atomically."""
    with atomic_open(path, "w") as fh:
        fh.write(text)

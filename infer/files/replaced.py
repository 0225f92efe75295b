"""The notes a command prints when its ``--out`` already held what it writes."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path


def replaced_note(out: Path, names: Sequence[str], what: str) -> str | None:
    """``note: replaced the {what} that OUT held (a, b)``, naming those of ``names`` that ``out``
    holds before the run (call it before the run writes them); None when it holds none.

    Args:
        out: the run's output folder.
        names: the files the run writes there.
        what: what they make up, e.g. ``"report"``.
    """
    held = [n for n in names if (out / n).is_file()]
    if not held:
        return None
    return f"note: replaced the {what} that {out} held ({', '.join(held)})"


def replaced_file_note(out: Path, held: Callable[[Path], str]) -> str | None:
    """``note: replaced OUT (what it held); give each run its own --out to keep both``, for a
    command whose ``--out`` is one file (call it before the run writes it).

    Args:
        out: the run's output file.
        held: what ``out`` holds, in a few words (e.g. ``"3 result(s)"``); called only when
            ``out`` is a file.

    Returns:
        The note; None when ``out`` is not a file (there is nothing to replace).
    """
    if not out.is_file():
        return None
    return f"note: replaced {out} ({held(out)}); give each run its own --out to keep both"

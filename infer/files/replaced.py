"""The note a report command prints when its ``--out`` already held some of its files."""

from __future__ import annotations

from collections.abc import Sequence
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

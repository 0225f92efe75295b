"""Counting a test's file reads: how many times each file was read, through which functions."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

import pytest


def count_reads(
    monkeypatch: pytest.MonkeyPatch,
    *readers: tuple[Any, str],
    only: Collection[Path] | None = None,
    after: Callable[[Path, bytes], None] | None = None,
) -> Counter[Path]:
    """Count, by path, the calls of each reading function ``getattr(owner, name)`` of
    ``readers`` (its first argument the path read; e.g. ``(Path, "read_bytes")``, or
    ``(runner, "read_input_bytes")``: the name a module looks up), for the rest of the test.

    Args:
        monkeypatch: the test's, which puts the functions back.
        readers: ``(owner, name)`` of each function to count.
        only: the paths counted (None: every path).
        after: called with each counted read's path and content, after the read (e.g. to
            replace the file, as a re-export into the same path would).

    Returns:
        The counts, filled as the test reads.
    """
    reads: Counter[Path] = Counter()

    def counting(real: Callable[..., Any]) -> Callable[..., Any]:
        def counted(path: Any, *args: Any, **kwargs: Any) -> Any:
            content = real(path, *args, **kwargs)
            p = Path(path)
            if only is None or p in only:
                reads[p] += 1
                if after is not None:
                    after(p, content)
            return content

        return counted

    for owner, name in readers:
        monkeypatch.setattr(owner, name, counting(getattr(owner, name)))
    return reads

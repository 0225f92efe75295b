"""The record of a shard's runs, ``run_shard{i}of{n}.json`` in a ``contactcal synth`` folder.

It holds the run that wrote it last (``args``; ``fingers``, the shard's; ``started`` and
``finished``, UTC; ``frames_at_start``, ``frames_rendered`` and ``frames_at_end``, the shard's
finished frames on disk before, by and after it) with the earlier runs that rendered frames
under ``earlier_runs``, oldest first: a resumed shard's ``frames_rendered`` add up to its rows
in ``index.csv``, unless frames were removed between runs (a frame rendered again counts in each
run that rendered it; a run's ``frames_at_start`` below the one before's ``frames_at_end`` shows
it). A run writes it before its first render with ``finished`` and ``frames_rendered`` null,
so a run that is interrupted or killed stays on record, and the next run counts the frames it
left from the disk (:func:`read_runs`). A run that finds every frame present leaves a record
whose latest run finished as it is.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from contactcal.infer.files.atomic import write_json
from contactcal.infer.files.regular import read_record_json


def run_record_path(root: Path, shard: tuple[int, int]) -> Path:
    """The record of the runs of shard ``(i, n)``: ``run_shard{i}of{n}.json``."""
    return root / f"run_shard{shard[0]}of{shard[1]}.json"


def read_runs(path: Path, frames_now: int) -> tuple[list[dict[str, Any]], bool]:
    """The runs in the record ``path`` that rendered frames, oldest first.

    A run that did not finish (its ``finished`` is null) is given the frames it left:
    ``frames_now``, the shard's frames on disk as this run starts, less its ``frames_at_start``.

    Returns:
        The runs, and whether the record is settled (present, its latest run finished).

    Raises:
        ValueError: ``path`` is damaged (read before the renders, so nothing is rendered).
    """
    if not path.is_file():
        return [], False
    expected = (
        "the run record a `contactcal synth` run wrote; remove it (it records only the earlier "
        "runs' arguments, times and frame counts) and run again"
    )
    record = read_record_json(path, expected)
    earlier = record.pop("earlier_runs", []) if isinstance(record, dict) else None
    if not isinstance(earlier, list) or not all(isinstance(r, dict) for r in earlier):
        raise ValueError(f"{path}: not a run record (a JSON object); expected {expected}")
    settled = record.get("finished", "unrecorded") is not None  # unrecorded: an older record
    if not settled:
        start = record.get("frames_at_start")
        if isinstance(start, bool) or not isinstance(start, int):
            raise ValueError(
                f"{path}: its unfinished run has no frames_at_start; expected {expected}"
            )
        record.update(frames_rendered=max(0, frames_now - start), frames_at_end=frames_now)
    return [r for r in (*earlier, record) if r.get("frames_rendered")], settled


@dataclass
class ShardRuns:
    """The record of a shard's runs, kept by one run: :meth:`begin`, then :meth:`end`."""

    path: Path
    run: dict[str, Any]  # this run's entry
    earlier: list[dict[str, Any]]  # the runs before it that rendered frames, oldest first
    keep: bool  # every frame was there and the record's latest run finished: left as it is

    @classmethod
    def begin(
        cls, path: Path, args: dict[str, Any], fingers: int, frames: tuple[int, int]
    ) -> ShardRuns:
        """Read the record and, where frames are to be rendered, put this run on it unfinished.

        Args:
            path: the record.
            args: this run's command line.
            fingers: the shard's fingers.
            frames: the shard's finished frames on disk now, and its frames in all.
        """
        at_start, total = frames
        earlier, settled = read_runs(path, at_start)
        run = {"args": args, "fingers": fingers, "started": _utc_now(), "finished": None}
        run.update(frames_at_start=at_start, frames_rendered=None)
        runs = cls(path, run, earlier, keep=settled and at_start == total)
        if at_start < total:
            write_json(path, runs.record())
        return runs

    def end(self, frames_rendered: int, frames_at_end: int) -> bool:
        """Record this run as finished, unless the record is kept; returns whether it wrote."""
        if self.keep:
            return False
        self.run.update(finished=_utc_now(), frames_rendered=frames_rendered)
        self.run["frames_at_end"] = frames_at_end
        write_json(self.path, self.record())
        return True

    def record(self) -> dict[str, Any]:
        """What the file holds: this run, with the earlier ones under ``earlier_runs``."""
        return {**self.run, "earlier_runs": self.earlier} if self.earlier else self.run


def _utc_now() -> str:
    """The time now, UTC, to the second (ISO 8601)."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")

"""``contactcal synth``: write a dataset of rendered sessions (layout in docs/CONVENTIONS.md).

Work is split by finger (one finger = one session = one seed). ``--shard i/n`` renders fingers
``f`` with ``f % n == i``, so a cluster job array covers the set exactly once; ``--workers K``
renders K fingers at a time in worker processes that are recycled after each finger (Mitsuba
leaks memory across scene loads). Every file is written atomically and a frame's truth JSON is
written last, so a killed run resumes by skipping frames whose JSON exists (and removes the
temporaries it left); workers stop when their run dies. Same seed, byte-identical files. One
finger's parameters and session folder: :mod:`~contactcal.synth.dataset_finger`.
"""

from __future__ import annotations

import csv
import io
import multiprocessing as mp
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from contactcal.infer.files.atomic import write_text
from contactcal.infer.files.temporaries import remove_stale_temporaries
from contactcal.synth.dataset_finger import render_finger, truth_path
from contactcal.synth.dataset_folder import SYNTH_REVISION as SYNTH_REVISION  # re-exported
from contactcal.synth.dataset_folder import (
    check_config_matches,
    check_out_folder,
    read_frame_record,
)
from contactcal.synth.layout import INDEX_COLUMNS, check_sweep, creating_dataset_folder
from contactcal.synth.run_record import ShardRuns, run_record_path
from contactcal.synth.session import RenderConfig
from contactcal.synth.shard_lock import shard_lock
from contactcal.synth.variant import choose_variant


@dataclass(frozen=True)
class DatasetConfig:
    """What ``contactcal synth`` renders (written to ``config.json``)."""

    fingers: int  # sessions in the whole set (all shards together)
    pressures_kpa: tuple[float, ...]  # pressure steps of every session, kPa
    seed: int  # dataset seed; finger f uses (seed, f)
    hard_fraction: float = 0.25  # share of sessions from the hard-case distribution
    # share of the hard sessions with a smooth coating (thin sharp ring before contact,
    # docs/synth.md); 0 keeps the v2 world the shipped model was trained on
    smooth_fraction: float = 0.0
    # share of all sessions with a bright dust speck on the window near the centre (where the
    # shipped model calls contact before contact); 0 keeps the shipped model's world
    speck_fraction: float = 0.0
    # share of all sessions whose membrane leaves the contact edge at a drawn slope, bringing the
    # inner ring onto the edge or beyond it (docs/synth.md); 0 keeps the shipped model's world
    departure_fraction: float = 0.0
    render: RenderConfig = field(default_factory=RenderConfig)  # size, spp, mesh, variant

    def __post_init__(self) -> None:
        check_sweep(self.fingers, self.pressures_kpa)
        if self.seed < 0:  # numpy seeds are >= 0; checked before config.json is written
            raise ValueError(f"--seed must be >= 0, got {self.seed}")
        if not 0.0 <= self.hard_fraction <= 1.0:
            raise ValueError(f"--hard-fraction must be in [0, 1], got {self.hard_fraction}")
        if not 0.0 <= self.smooth_fraction <= 1.0:
            raise ValueError(f"--smooth-fraction must be in [0, 1], got {self.smooth_fraction}")
        if not 0.0 <= self.speck_fraction <= 1.0:
            raise ValueError(f"--speck-fraction must be in [0, 1], got {self.speck_fraction}")
        if not 0.0 <= self.departure_fraction <= 1.0:
            raise ValueError(
                f"--departure-fraction must be in [0, 1], got {self.departure_fraction}"
            )


def shard_frames(root: Path, config: DatasetConfig, fingers: list[int]) -> int:
    """The finished frames of ``fingers`` on disk (their rows in ``index.csv``, rebuilt)."""
    return sum(truth_path(root, f, p).is_file() for f in fingers for p in config.pressures_kpa)


def _run_finger(task: tuple[str, DatasetConfig, int, int]) -> tuple[int, int]:
    out_dir, config, finger, parent_pid = task
    return finger, render_finger(out_dir, config, finger, parent_pid)


def write_index(out_dir: str | os.PathLike[str]) -> Path:
    """Rebuild ``index.csv`` from every finished frame under ``out_dir`` (sorted, atomic)."""
    root = Path(out_dir)
    rows = [read_frame_record(p) for p in sorted(root.glob("finger_*/frames/*.json"))]
    rows.sort(key=lambda r: (r["finger"], r["pressure_kpa"]))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=INDEX_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text(root / "index.csv", buf.getvalue())
    return root / "index.csv"


def shard_fingers(fingers: int, shard: tuple[int, int]) -> list[int]:
    """Fingers of shard ``(i, n)``: ``f % n == i``."""
    i, n = shard
    if not (n >= 1 and 0 <= i < n):
        raise ValueError(f"--shard must be i/n with 0 <= i < n, got {i}/{n}")
    return [f for f in range(fingers) if f % n == i]


def build_dataset(
    out_dir: str | os.PathLike[str],
    config: DatasetConfig,
    workers: int = 1,
    shard: tuple[int, int] = (0, 1),
    progress: bool = True,
    run_args: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Render this shard's fingers into ``out_dir`` (resuming), then rebuild ``index.csv``.

    The Mitsuba variant is resolved here (``auto`` → the one this machine renders with) and
    recorded in ``config.json``, so a resume or a shard that would render with another variant
    (whose frames differ in their bytes) is refused instead of mixed in. Everything is checked
    before the first render: the folder (:func:`check_out_folder`), the shard, ``config.json``,
    the finished frames' records, that no other run renders this shard into the folder now
    (:mod:`~contactcal.synth.shard_lock`) and the shard's run record.

    Args:
        out_dir: the dataset folder (new, empty, or a synth dataset to resume).
        config: what to render.
        workers: worker processes.
        shard: ``(i, n)``: render the fingers ``f % n == i``.
        progress: show a progress bar.
        run_args: the command line, to keep the shard's run record ``run_shard{i}of{n}.json``
            (:mod:`~contactcal.synth.run_record`, written before the first render and again
            at the end); None writes none.

    Raises:
        ValueError: a bad input (one line naming it), or another run renders this shard into
            ``out_dir`` now.

    Returns:
        ``fingers`` (this shard's), ``frames_rendered`` (by this run) and, with ``run_args``,
        ``run_record_written`` (False: every frame was there and the record, whose latest run
        finished, is kept as the record of the runs that rendered them).
    """
    root = Path(out_dir)
    config, fingers = _open_folder(root, config, shard)
    with shard_lock(root, shard):  # one run of this shard at a time
        runs = None
        if run_args is not None:  # before the renders: a killed run stays on record
            total = len(fingers) * len(config.pressures_kpa)
            frames = (shard_frames(root, config, fingers), total)
            runs = ShardRuns.begin(run_record_path(root, shard), run_args, len(fingers), frames)
        made = _render_fingers(root, config, fingers, workers, shard if progress else None)
        write_index(root)
        stats: dict[str, Any] = {"fingers": len(fingers), "frames_rendered": made}
        if runs is not None:
            stats["run_record_written"] = runs.end(made, shard_frames(root, config, fingers))
    return stats


def _open_folder(
    root: Path, config: DatasetConfig, shard: tuple[int, int]
) -> tuple[DatasetConfig, list[int]]:
    """Check ``root`` and the shard, write or check ``config.json`` and every frame record.

    Returns:
        The config with its Mitsuba variant resolved, and the shard's fingers.
    """
    if root.exists() and not root.is_dir():
        raise ValueError(f"{root}: is a file; expected a dataset folder for --out (new or resumed)")
    fingers = shard_fingers(config.fingers, shard)
    if not fingers:
        raise ValueError(
            f"--shard {shard[0]}/{shard[1]}: of {config.fingers} finger(s) this shard holds none "
            f"(shard i renders the fingers f % n == i); use fewer shards (at most {config.fingers})"
        )
    check_out_folder(root)
    variant = choose_variant(config.render.variant)
    config = replace(config, render=replace(config.render, variant=variant))
    with creating_dataset_folder(root):
        root.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(root)  # left by a killed run
    check_config_matches(root, config)
    for path in root.glob("finger_*/frames/*.json"):
        read_frame_record(path)  # a damaged one (any shard's: index.csv reads all) is refused now
    return config, fingers


def _render_fingers(
    root: Path,
    config: DatasetConfig,
    fingers: list[int],
    workers: int,
    bar_shard: tuple[int, int] | None,
) -> int:
    """Render ``fingers`` in ``workers`` processes; returns the frames rendered now.

    ``bar_shard``: the shard named by the progress bar; None shows no bar.
    """
    tasks = [(str(root), config, f, os.getpid()) for f in fingers]
    made = 0
    bar = None
    if bar_shard is not None:
        from tqdm import tqdm

        total = len(fingers) * len(config.pressures_kpa)
        i, n = bar_shard
        bar = tqdm(total=total, desc=f"synth shard {i}/{n}", unit="frame")
    ctx = mp.get_context("spawn")
    with ctx.Pool(max(1, workers), maxtasksperchild=1) as pool:
        for _, count in pool.imap_unordered(_run_finger, tasks):
            made += count
            if bar is not None:
                bar.update(len(config.pressures_kpa))
    if bar is not None:
        bar.close()
    return made


def parse_shard(text: str) -> tuple[int, int]:
    """``"i/n"`` → (i, n)."""
    try:
        i, n = (int(v) for v in text.split("/"))
    except ValueError:
        raise ValueError(f"--shard: expected i/n (e.g. 0/4), got {text!r}") from None
    shard_fingers(1, (i, n))
    return i, n

"""One finger of a ``contactcal synth`` dataset: its session's parameters (drawn from the seed
``(dataset seed, finger)``) and its session folder, rendered or finished (frames, masks, each
frame's truth JSON written last, manifest, rig config, session parameters)."""

from __future__ import annotations

import os
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from contactcal.infer.files.atomic import write_json, write_text
from contactcal.infer.files.jsonable import jsonable
from contactcal.infer.files.temporaries import remove_stale_temporaries
from contactcal.infer.image.write import write_image
from contactcal.synth.dataset_folder import read_frame_record
from contactcal.synth.layout import frame_name, index_row
from contactcal.synth.randomize import SessionParams, sample_session
from contactcal.synth.session import FrameOutput, render_session

if TYPE_CHECKING:
    from contactcal.synth.dataset import DatasetConfig


def session_params(config: DatasetConfig, finger: int) -> SessionParams:
    """The deterministic parameters of finger ``finger``."""
    rng = np.random.default_rng([config.seed, finger])
    hard = bool(rng.random() < config.hard_fraction)
    return sample_session(
        rng,
        hard=hard,
        smooth_fraction=config.smooth_fraction,
        speck_fraction=config.speck_fraction,
        departure_fraction=config.departure_fraction,
    )


def _truth(out: FrameOutput, finger: int, hard: bool) -> dict[str, Any]:
    """The frame's ``index.csv`` row (written next to it; the index is built from these)."""
    s = out.state
    return index_row(
        finger, out.pressure_kpa, out.mask, s.area_mm2, out.mm_per_px, s.onset_kpa, hard
    )


def stop_if_orphaned(parent_pid: int | None) -> None:
    """End this worker process if the run that started it (``parent_pid``) is gone.

    A killed ``contactcal synth`` leaves its pool workers running (they are re-parented);
    they check before every write and every render, so nothing is written after the run died.

    Raises:
        SystemExit: the parent died (not an ``Exception``: the pool does not catch it, the
            worker exits, and open atomic writers remove their temporaries on the way out).
    """
    if parent_pid is not None and os.getppid() != parent_pid:
        raise SystemExit(f"synth worker {os.getpid()}: parent {parent_pid} is gone; stopping")


def truth_path(root: Path, finger: int, pressure_kpa: float) -> Path:
    """The truth JSON of a frame, written last: the frame is finished when it exists."""
    return root / f"finger_{finger:04d}" / "frames" / f"{frame_name(pressure_kpa)}.json"


def render_finger(
    out_dir: str, config: DatasetConfig, finger: int, parent_pid: int | None = None
) -> int:
    """Render (or finish) one finger's session folder; returns the frames rendered now.

    Args:
        out_dir: the dataset folder.
        config: what to render.
        finger: the finger (session) number.
        parent_pid: in a worker process, the pid of the run that started it (the worker stops
            when that process is gone, see :func:`stop_if_orphaned`); None in the run itself.
    """
    root = Path(out_dir)
    name = f"finger_{finger:04d}"
    folder = root / name
    for sub in (folder, folder / "frames", folder / "masks"):
        remove_stale_temporaries(sub)  # left by a killed run; a resumed run starts clean
    params = session_params(config, finger)
    pressures = sorted(config.pressures_kpa)
    truth_paths = [truth_path(root, finger, p) for p in pressures]
    skip = [t.is_file() for t in truth_paths]
    for t in (t for t, done in zip(truth_paths, skip, strict=True) if done):
        read_frame_record(t)  # a damaged one is refused before any render
    made = 0
    if not all(skip):
        frames = render_session(params, pressures, config.render, (config.seed, finger), None, skip)
        for out, tpath in zip(frames, truth_paths, strict=True):
            stop_if_orphaned(parent_pid)  # after a render, before its writes
            if out is None:
                continue
            stem = frame_name(out.pressure_kpa)
            write_image(
                folder / "frames" / f"{stem}.png", np.ascontiguousarray(out.frame[:, :, ::-1])
            )
            write_image(folder / "masks" / f"{stem}.png", out.mask.astype(np.uint8) * 255)
            write_json(tpath, _truth(out, finger, params.hard))
            made += 1
            stop_if_orphaned(parent_pid)  # before the next render
    rows = [read_frame_record(t) for t in truth_paths]
    manifest = "file,pressure_kpa\n" + "".join(
        f"frames/{frame_name(r['pressure_kpa'])}.png,{r['pressure_kpa']}\n" for r in rows
    )
    write_text(folder / "manifest.csv", manifest)
    # Scale at the contact plane: the median plateau height's pixel size over contact frames.
    scales = [r["mm_per_px"] for r in rows if r["contact"]] or [r["mm_per_px"] for r in rows]
    rig = {"mm_per_px": float(np.median(scales)), "image_width_px": config.render.width}
    write_json(folder / "rig.json", rig)
    write_json(folder / "session.json", jsonable(asdict(params)))
    return made

"""``contactcal procedural``: write a procedural dataset in the ``contactcal synth`` layout.

Everything is written into a staging folder beside ``--out`` and renamed onto it at the end, so
the dataset appears complete or not at all; a killed run leaves only its staging folder, removed
by the next run. ``--out`` must not exist (the set is regenerated in seconds). Same config, same
files: finger ``f`` draws from numpy Generator ``[seed, f]``, its frame ``k`` from
``[seed, f, k]``.
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.files.atomic import write_json, write_text
from contactcal.infer.files.jsonable import jsonable
from contactcal.infer.files.temporaries import make_staging_folder, remove_stale_temporaries
from contactcal.infer.image.write import write_image
from contactcal.synth.layout import INDEX_COLUMNS, creating_dataset_folder, frame_name, index_row
from contactcal.synth.procedural.config import GeneratorConfig
from contactcal.synth.procedural.frame import Frame, session_frames
from contactcal.synth.procedural.session import Finger, finger_params


def _row(frame: Frame, finger_no: int, finger: Finger, mm_per_px: float) -> dict[str, Any]:
    onset = finger.values["onset_kpa"]
    return index_row(
        finger_no, frame.pressure_kpa, frame.mask, frame.area_mm2, mm_per_px, onset, finger.hard
    )


def write_finger(root: Path, config: GeneratorConfig, finger_no: int) -> list[dict[str, Any]]:
    """Write one session folder (frames, masks, manifest, rig, session) under ``root``.

    Returns:
        Its ``index.csv`` rows, by pressure.
    """
    finger = finger_params(config, finger_no)
    folder = root / f"finger_{finger_no:04d}"
    mm = finger.mm_per_px(config.width)
    rows = []
    for frame in session_frames(config, finger_no, finger, sorted(config.pressures_kpa)):
        stem = frame_name(frame.pressure_kpa)
        write_image(folder / "frames" / f"{stem}.png", np.ascontiguousarray(frame.rgb[:, :, ::-1]))
        write_image(folder / "masks" / f"{stem}.png", frame.mask.astype(np.uint8) * 255)
        rows.append(_row(frame, finger_no, finger, mm))
    manifest = "file,pressure_kpa\n" + "".join(
        f"frames/{frame_name(r['pressure_kpa'])}.png,{r['pressure_kpa']}\n" for r in rows
    )
    write_text(folder / "manifest.csv", manifest)
    write_json(folder / "rig.json", {"mm_per_px": mm, "image_width_px": config.width})
    write_json(folder / "session.json", jsonable(asdict(finger)))
    return rows


def _index_text(rows: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=INDEX_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def build_dataset(
    out_dir: str | os.PathLike[str],
    config: GeneratorConfig,
    progress: Callable[[int], None] | None = None,
) -> dict[str, float]:
    """Generate the whole set into ``out_dir`` (all or nothing).

    Args:
        out_dir: the dataset folder; must not exist yet.
        config: what to generate.
        progress: called with the number of frames after each finger.

    Returns:
        ``fingers``, ``frames``, ``seconds`` and ``frames_per_s``.

    Raises:
        ValueError: ``out_dir`` exists, or it or its staging folder cannot be created (the
            message names it).
    """
    out = Path(out_dir)
    if out.exists() or out.is_symlink():
        raise ValueError(f"{out}: already exists; give a new --out folder (nothing was written)")
    with creating_dataset_folder(out):
        out.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(out.parent)  # staging folders of killed runs
        stage = make_staging_folder(out.parent, out.name)
    start = time.perf_counter()
    try:
        write_json(stage / "config.json", jsonable(asdict(config)))
        rows: list[dict[str, Any]] = []
        for f in range(config.fingers):
            rows += write_finger(stage, config, f)
            if progress is not None:
                progress(len(config.pressures_kpa))
        write_text(stage / "index.csv", _index_text(rows))
        os.rename(stage, out)  # fails if a file or non-empty folder appeared there meanwhile
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    seconds = time.perf_counter() - start
    return {
        "fingers": config.fingers,
        "frames": len(rows),
        "seconds": round(seconds, 3),
        "frames_per_s": round(len(rows) / max(seconds, 1e-9), 2),
    }

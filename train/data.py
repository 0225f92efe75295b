"""Dataset folders (``index.csv`` layout, docs/CONVENTIONS.md) → validated records → cached tensors.

Every frame is preprocessed with :func:`contactcal.infer.preprocess.prepare` (the deployment
code path) using its session's lowest-pressure frame as the reference; its mask is cropped with
the same box (area resize, threshold 0.5). Train/validation split is by finger, never by frame:
frames of one finger share its fingerprint texture and would leak.
"""

from __future__ import annotations

import csv
import hashlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from contactcal.infer.io import load_image
from contactcal.infer.preprocess import CropBox, PreprocessConfig, crop_resize, prepare

#: Columns of index.csv that training needs.
REQUIRED_COLUMNS = ("finger", "session", "frame", "mask", "pressure_kpa", "contact")


@dataclass(frozen=True)
class FrameRecord:
    """One frame of a dataset (paths resolved)."""

    finger_key: str  # "<dataset folder>#<finger>": unique across datasets
    session: str  # "<dataset folder>#<session folder>"
    frame: Path
    mask: Path
    pressure_kpa: float  # kPa
    contact: bool


@dataclass
class CachedSet:
    """Preprocessed frames in memory (one row per frame)."""

    x: torch.Tensor  # (N, C, S, S) float16 network inputs
    y: torch.Tensor  # (N, 1, S, S) uint8 masks in network pixels (0/1)
    pressure_kpa: torch.Tensor  # (N,) float32, kPa
    contact: torch.Tensor  # (N,) bool, index.csv's contact flag
    area_px: torch.Tensor  # (N,) float32, true mask area in INPUT pixels
    boxes: list[CropBox]  # crop of each frame
    shapes: list[tuple[int, int]]  # input (H, W) of each frame
    fingers: list[str]  # finger_key of each frame

    def __len__(self) -> int:
        return int(self.x.shape[0])


def _read_index(folder: Path) -> list[dict[str, str]]:
    if not folder.exists():
        raise ValueError(f"{folder}: dataset folder does not exist")
    if not folder.is_dir():
        raise ValueError(f"{folder}: expected a dataset folder, got a file")
    index = folder / "index.csv"
    if not index.is_file():
        raise ValueError(f"{index}: missing index.csv (is {folder} a `contactcal synth` output?)")
    with open(index, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(
                f"{index}: missing column(s) {', '.join(missing)}; "
                f"expected at least {', '.join(REQUIRED_COLUMNS)}"
            )
        rows = list(reader)
    if not rows:
        raise ValueError(f"{index}: no frames listed")
    return rows


def load_records(data_dirs: Sequence[str | os.PathLike[str]]) -> list[FrameRecord]:
    """Read and validate the index of every dataset folder.

    Args:
        data_dirs: one or more dataset folders.

    Returns:
        All frames, in index order.

    Raises:
        ValueError: a missing folder, index.csv, column or file, or an unparsable value; the
            message names the path.
    """
    if not data_dirs:
        raise ValueError("no dataset folder given")
    records: list[FrameRecord] = []
    for d in data_dirs:
        folder = Path(d)
        for line, row in enumerate(_read_index(folder), start=2):
            where = f"{folder / 'index.csv'} line {line}"
            try:
                pressure = float(row["pressure_kpa"])
                contact = bool(int(float(row["contact"])))
                finger = int(float(row["finger"]))
            except ValueError as exc:
                raise ValueError(f"{where}: unparsable value ({exc})") from exc
            rec = FrameRecord(
                finger_key=f"{folder}#{finger}",
                session=f"{folder}#{row['session']}",
                frame=folder / row["frame"],
                mask=folder / row["mask"],
                pressure_kpa=pressure,
                contact=contact,
            )
            for p in (rec.frame, rec.mask):
                if not p.is_file():
                    raise ValueError(f"{where}: missing file {p}")
            records.append(rec)
    return records


def split_by_finger(
    records: Sequence[FrameRecord], val_fraction: float, seed: int
) -> tuple[list[FrameRecord], list[FrameRecord]]:
    """Deterministic train/validation split by finger.

    Args:
        records: all frames.
        val_fraction: fraction of FINGERS held out (at least one when there are >= 2 fingers
            and the fraction is > 0).
        seed: split seed (numpy Generator).

    Returns:
        ``(train, val)`` records; no finger appears in both.
    """
    if not 0.0 <= val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
    fingers = sorted({r.finger_key for r in records})
    n_val = round(val_fraction * len(fingers))
    if val_fraction > 0 and len(fingers) >= 2:
        n_val = min(max(n_val, 1), len(fingers) - 1)
    order = np.random.default_rng(seed).permutation(len(fingers))
    held = {fingers[i] for i in order[:n_val]}
    return [r for r in records if r.finger_key not in held], [
        r for r in records if r.finger_key in held
    ]


def dataset_digest(data_dirs: Sequence[str | os.PathLike[str]]) -> str:
    """sha256 (hex) of the concatenated index.csv files, in the given order."""
    h = hashlib.sha256()
    for d in data_dirs:
        h.update((Path(d) / "index.csv").read_bytes())
    return h.hexdigest()


def build_cache(
    records: Sequence[FrameRecord],
    config: PreprocessConfig,
    use_reference: bool,
    progress: bool = False,
) -> CachedSet:
    """Preprocess frames and masks into memory.

    Args:
        records: frames (whole sessions, so that each has its reference).
        config: preprocessing (``input_size`` = S).
        use_reference: add the session's lowest-pressure frame as a second channel.
        progress: show a tqdm bar.

    Returns:
        The cached set (empty tensors when ``records`` is empty).
    """
    s = config.input_size
    reference_of: dict[str, FrameRecord] = {}
    for r in records:
        cur = reference_of.get(r.session)
        if cur is None or r.pressure_kpa < cur.pressure_kpa:
            reference_of[r.session] = r
    ref_images: dict[str, np.ndarray] = {}
    c = 2 if use_reference else 1
    xs = torch.empty((len(records), c, s, s), dtype=torch.float16)
    ys = torch.empty((len(records), 1, s, s), dtype=torch.uint8)
    areas, boxes, shapes = [], [], []
    for i, r in enumerate(tqdm(records, desc="preprocess", disable=not progress, leave=False)):
        gray = load_image(r.frame)
        ref = None
        if use_reference:
            if r.session not in ref_images:
                ref_images[r.session] = load_image(reference_of[r.session].frame)
            ref = ref_images[r.session]
        prep = prepare(gray, ref, config)
        mask = load_image(r.mask) > 127
        if mask.shape != gray.shape:
            raise ValueError(f"{r.mask}: mask shape {mask.shape} differs from frame {gray.shape}")
        net_mask = crop_resize(mask.astype(np.float32), prep.box, s) > 0.5
        xs[i] = torch.from_numpy(prep.x)
        ys[i, 0] = torch.from_numpy(net_mask.astype(np.uint8))
        areas.append(float(mask.sum()))
        boxes.append(prep.box)
        shapes.append((int(gray.shape[0]), int(gray.shape[1])))
    return CachedSet(
        x=xs,
        y=ys,
        pressure_kpa=torch.tensor([r.pressure_kpa for r in records], dtype=torch.float32),
        contact=torch.tensor([r.contact for r in records], dtype=torch.bool),
        area_px=torch.tensor(areas, dtype=torch.float32),
        boxes=boxes,
        shapes=shapes,
        fingers=[r.finger_key for r in records],
    )

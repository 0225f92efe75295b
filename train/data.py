"""Dataset folders (``index.csv``, read by :mod:`contactcal.infer.bench.dataset`) → cached tensors.

Every frame goes through :func:`contactcal.infer.methods.unet.prepare.prepare`, the deployment
code path: its session's lowest-pressure frame (the first row of
:func:`~contactcal.infer.bench.dataset.sessions_of`) is the session reference, computed once with
:func:`~contactcal.infer.methods.unet.prepare.session_reference`; it fixes the shrink of large
frames (:func:`~contactcal.infer.methods.unet.shrink.deployed_shrink`), the crop (and, for a
2-channel model, the reference channel) of all of the session's frames. The mask is shrunk and
cropped the same way (area resize, threshold 0.5). The train/validation split (by finger, never
by frame) is :mod:`contactcal.train.split`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from tqdm import tqdm

from contactcal.infer.bench.dataset import IndexRow
from contactcal.infer.image.gray import reduce_area
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox, crop_resize
from contactcal.infer.methods.unet.prepare import SessionReference, norm_levels, prepare
from contactcal.train.sessions import session_inputs


@dataclass
class CachedSet:
    """Preprocessed frames in memory (one entry per frame, in the order of ``rows``)."""

    x: torch.Tensor  # (N, C, S, S) float32 network inputs, exactly as deployment feeds them
    y: torch.Tensor  # (N, 1, S, S) uint8 masks in network pixels (0/1)
    area_px: torch.Tensor  # (N,) float32, true mask area in INPUT pixels (of the shrunk frame)
    boxes: list[CropBox]  # crop of each frame (network → input pixels)
    shapes: list[tuple[int, int]]  # input (H, W) of each frame (after the session's shrink)
    rows: list[IndexRow]  # the index row of each frame (session, pressure, mm/px, onset, ...)
    levels: torch.Tensor  # (N, I, 2) float32: per image channel (frame[, reference]) the grey
    #   levels / 255 that its normalisation maps to 0 and 1 (``norm_levels``), for augmentation

    def __len__(self) -> int:
        return int(self.x.shape[0])


def build_cache(
    rows: Sequence[IndexRow],
    config: PreprocessConfig,
    channels: int,
    progress: bool = False,
) -> CachedSet:
    """Preprocess frames and masks into memory, exactly as deployment prepares frames.

    Args:
        rows: frames (whole sessions: each session's lowest-pressure frame is its reference).
        config: preprocessing (``input_size`` = S).
        channels: network input channels: frame [, session reference] [, ridge energy]
            (``prepare``).
        progress: show a tqdm bar.

    Returns:
        The cached set (empty tensors when ``rows`` is empty).

    Raises:
        ValueError: unreadable image, or a mask or frame of another size than its reference.
    """
    s = config.input_size
    sessions = session_inputs(rows, config)
    xs = torch.empty((len(rows), channels, s, s), dtype=torch.float32)
    ys = torch.empty((len(rows), 1, s, s), dtype=torch.uint8)
    n_img = channels - int(config.ridge_work_px > 0)
    levels = torch.empty((len(rows), n_img, 2), dtype=torch.float32)
    areas, boxes, shapes = [], [], []
    for i, r in enumerate(tqdm(rows, desc="preprocess", disable=not progress, leave=False)):
        sess = sessions[r.session_key]
        gray = sess.frame(r.frame)
        prep = prepare(gray, sess.reference, config, channels)
        mask = load_image(r.mask) > 127
        small = reduce_area(mask.astype(np.uint8) * 255, sess.shrink).astype(np.float32) / 255
        if small.shape != gray.shape:
            raise ValueError(f"{r.mask}: mask shape {mask.shape} differs from its frame's")
        net_mask = crop_resize(small, prep.box, s) > 0.5
        xs[i] = torch.from_numpy(prep.x)
        levels[i] = torch.tensor(_levels(gray, sess.reference, prep.box, config)[:n_img]) / 255
        ys[i, 0] = torch.from_numpy(net_mask.astype(np.uint8))
        areas.append(float(mask.sum()) / sess.shrink**2)
        boxes.append(prep.box)
        shapes.append((int(gray.shape[0]), int(gray.shape[1])))
    return CachedSet(
        x=xs,
        y=ys,
        area_px=torch.tensor(areas, dtype=torch.float32),
        boxes=boxes,
        shapes=shapes,
        rows=list(rows),
        levels=levels,
    )


def _levels(
    gray: np.ndarray, reference: SessionReference, box: CropBox, config: PreprocessConfig
) -> list[tuple[float, float]]:
    """Grey levels (0-255) mapped to 0 and 1 of the frame and of its reference channel, in
    ``box``: the reference frame's own, else the frame's (``no_reference`` "self"; a blank
    plane is 0 whatever its levels)."""
    frame = norm_levels(gray, box, config)
    ref = frame if reference.gray is None else norm_levels(reference.gray, box, config)
    return [frame, ref]

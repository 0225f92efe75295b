"""The dataset layout of docs/CONVENTIONS.md ("Dataset layout"): the index columns, frame names
and the command-line formats of sizes and pressures, shared by both generators (`synth` and
`synth.procedural`, which must not import each other's image models).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.image.frame import MIN_FRAME_SIDE_PX
from contactcal.infer.pipeline.manifest import MAX_PRESSURE_KPA

#: ``index.csv`` columns, in order.
INDEX_COLUMNS = tuple(
    "finger session frame mask pressure_kpa contact area_px area_mm2 area_mm2_projected"
    " mm_per_px onset_kpa width height hard".split()
)


def frame_name(p: float) -> str:
    """File stem of the frame at ``p`` kPa, e.g. ``p05.0kpa`` (0.1 kPa resolution)."""
    return f"p{p:04.1f}kpa"


def check_frame_names(pressures_kpa: tuple[float, ...]) -> None:
    """Refuse pressures whose frames would share a file name (names have 0.1 kPa resolution).

    Raises:
        ValueError: names the two pressures and the shared name (before anything is written).
    """
    seen: dict[str, float] = {}
    for p in pressures_kpa:
        name = frame_name(p)
        if name in seen and seen[name] == p:
            raise ValueError(f"--pressures: {p:g} kPa is given twice; pressures must be distinct")
        if name in seen:
            raise ValueError(
                f"--pressures: {seen[name]:g} and {p:g} kPa would both be saved as {name}.png "
                "(frame names have 0.1 kPa resolution); give pressures that differ when rounded "
                "to 0.1 kPa"
            )
        seen[name] = p


#: Largest departure of a frame's width / height from the rig camera's 4/3 (integer sizes of
#: small frames, e.g. 48x36 exact, 50x37 within).
ASPECT_TOLERANCE = 0.03


#: Largest frame, px: the rig camera's sensor. No frame the methods measure is larger, and the
#: generators' memory grows with the pixels (``procedural``, one frame here: ~3.2 GB peak,
#: ~23 s; 20000x15000 took 23 GB, 40000x30000 ended in a MemoryError).
MAX_FRAME_SIZE = (2592, 1944)


def check_frame_size(width: int, height: int) -> None:
    """Refuse a frame size that is not the rig camera's 4:3 (the window ring must fit the
    frame), has a side below :data:`MIN_FRAME_SIDE_PX` (the methods refuse such frames) or is
    above :data:`MAX_FRAME_SIZE`.

    Raises:
        ValueError: naming ``--size`` and the size given.
    """
    max_w, max_h = MAX_FRAME_SIZE
    low = MIN_FRAME_SIDE_PX
    if (
        not (low <= width <= max_w and low <= height <= max_h)
        or abs(width / height - 4 / 3) > ASPECT_TOLERANCE
    ):
        raise ValueError(
            f"--size: frames must be 4:3, at least {round(low * 4 / 3)}x{low} and at most "
            f"{max_w}x{max_h} px (the rig camera's), got {width}x{height}"
        )


def check_sweep(fingers: int, pressures_kpa: tuple[float, ...]) -> None:
    """A dataset's fingers (>= 1) and pressures (finite, 0-100 kPa, distinct frame names).

    Raises:
        ValueError: naming the option and what was expected.
    """
    if fingers < 1:
        raise ValueError(f"--fingers must be >= 1, got {fingers}")
    if not pressures_kpa or not all(
        math.isfinite(p) and 0 <= p <= MAX_PRESSURE_KPA for p in pressures_kpa
    ):
        raise ValueError(
            f"pressures must be finite, 0-{MAX_PRESSURE_KPA:g} kPa (what a manifest may hold), "
            f"got {pressures_kpa}"
        )
    check_frame_names(pressures_kpa)


def parse_pressures(text: str) -> tuple[float, ...]:
    """``"0:20:1"`` (start:stop:step, stop included) or ``"0,2.5,5"`` → kPa, in the order given.

    Raises:
        ValueError: unparsable, negative or non-finite values, or pressures sharing a frame name
            (:func:`check_frame_names`).
    """
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not step > 0 or stop < start:
                raise ValueError
            n = math.floor((stop - start) / step + 1e-9) + 1
            values = tuple(round(start + k * step, 6) for k in range(n))
        else:
            values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(
            f"--pressures: expected start:stop:step (e.g. 0:20:1) or a comma list, got {text!r}"
        ) from None
    if not all(math.isfinite(p) and 0 <= p <= MAX_PRESSURE_KPA for p in values):
        raise ValueError(
            f"--pressures: expected finite values of 0-{MAX_PRESSURE_KPA:g} kPa (what `calibrate` "
            f"reads from a manifest), got {text!r}"
        )
    check_frame_names(values)
    return values


def parse_size(text: str) -> tuple[int, int]:
    """``"320x240"`` or ``"320"`` (4:3 implied) → (width, height)."""
    try:
        if "x" in text:
            w, h = (int(v) for v in text.lower().split("x"))
        else:
            w = int(text)
            h = round(w * 3 / 4)
    except ValueError:
        raise ValueError(f"--size: expected W or WxH (4:3, e.g. 320x240), got {text!r}") from None
    return w, h


def index_row(
    finger: int,
    pressure_kpa: float,
    mask: np.ndarray,
    area_mm2: float,
    mm_per_px: float,
    onset_kpa: float,
    hard: bool,
) -> dict[str, Any]:
    """One ``index.csv`` row (:data:`INDEX_COLUMNS`) of the frame of ``finger`` at ``pressure_kpa``.

    Args:
        finger: finger number (its session folder is ``finger_XXXX``).
        pressure_kpa: kPa.
        mask: ``(H, W) bool`` exact contact mask.
        area_mm2: true contact area on the membrane, mm².
        mm_per_px: pixel scale at the contact plane, mm/px.
        onset_kpa: the session's contact onset, kPa.
        hard: the session was drawn from the hard ranges.
    """
    session = f"finger_{finger:04d}"
    name = frame_name(pressure_kpa)
    area_px = int(mask.sum())
    h, w = mask.shape
    return {
        "finger": finger,
        "session": session,
        "frame": f"{session}/frames/{name}.png",
        "mask": f"{session}/masks/{name}.png",
        "pressure_kpa": pressure_kpa,
        "contact": int(area_px > 0),
        "area_px": area_px,
        "area_mm2": round(area_mm2, 6),
        "area_mm2_projected": round(area_px * mm_per_px**2, 6),
        "mm_per_px": round(mm_per_px, 8),
        "onset_kpa": round(onset_kpa, 6),
        "width": w,
        "height": h,
        "hard": int(hard),
    }


@contextlib.contextmanager
def creating_dataset_folder(out: Path) -> Iterator[None]:
    """Make the folders of dataset ``out`` (``--out``, as given) in the block: an ``OSError``
    there (its parent read-only, a file system that takes no folders) is one line naming it.

    Raises:
        ValueError: ``--out OUT: cannot create the dataset folder (REASON); expected a folder
            that can be written``.
    """
    try:
        yield
    except OSError as exc:
        raise ValueError(
            f"--out {out}: cannot create the dataset folder ({exc.strerror}); expected a "
            "folder that can be written"
        ) from None

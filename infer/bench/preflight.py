"""Checks of every dataset of a ``contactcal bench`` run before any work (scoring, timing, the
robustness suite): each session's reference frame, and every frame's and mask's file and size,
so that a broken dataset, a cross-check set included, fails in seconds with the file named.

Every file is decoded as scoring decodes it (:func:`file_size`), so that damaged pixel data
(a header and end marker intact, the compressed data not) is found here too, not after minutes of
scoring: about 2 ms per 320×240 frame and its mask, a small part of scoring them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.dataset import IndexRow
from contactcal.infer.calibration.gate_check import REST_KPA
from contactcal.infer.image.read import load_image


def check_datasets(
    sessions: Mapping[str, Sequence[IndexRow]],
    others: Sequence[Mapping[str, Sequence[IndexRow]]],
    config: BenchConfig,
) -> None:
    """Check the main dataset's and the cross-check sets' sessions before any work.

    References are checked where they are used: the main dataset's with ``use_reference`` or
    the robustness suite (which always uses them), a cross-check set's with ``use_reference``.

    Raises:
        ValueError: :func:`check_references` or :func:`check_files`, naming the file.
    """
    main_refs = config.use_reference or bool(config.robustness_frames)
    if main_refs:
        check_references(sessions, for_robustness=not config.use_reference)
    for other in others if config.use_reference else []:
        check_references(other)
    check_files(sessions, main_refs)
    for other in others:
        check_files(other, config.use_reference)


def check_references(
    sessions: Mapping[str, Sequence[IndexRow]], for_robustness: bool = False
) -> None:
    """Refuse a session without a frame at rest (at most :data:`REST_KPA`) to be its reference.

    Args:
        sessions: rows per session, sorted by pressure (the first is the reference).
        for_robustness: the references are for the robustness suite only (``--no-reference
            --robustness``): the message's advice says so.

    Raises:
        ValueError: naming the ``index.csv``, the session and its lowest pressure.
    """
    for rows in sessions.values():
        ref = rows[0]
        if ref.pressure_kpa > REST_KPA:
            raise ValueError(
                f"{ref.dataset / 'index.csv'}: session {ref.session} has no 0 kPa frame (its "
                f"lowest pressure is {ref.pressure_kpa:g} kPa); bench needs each session's 0 kPa "
                f"frame (at most {REST_KPA:g} kPa) as reference"
                + (
                    " for the robustness suite: add one, or run without --robustness"
                    if for_robustness
                    else ": add one, or run with --no-reference (and without --robustness)"
                )
            )


def file_size(path: Path) -> tuple[int, int]:
    """``(height, width)`` of an image file in pixels, decoded by
    :func:`~contactcal.infer.image.read.load_image` as scoring reads it.

    Raises:
        ImageError: missing, unreadable, truncated, not the format its suffix names, or corrupt
            pixel data (the decoder's complaint quoted).
    """
    h, w = load_image(path).shape
    return h, w


def check_mask_size(row: IndexRow, mask: tuple[int, int], frame: tuple[int, int]) -> None:
    """Refuse a mask whose ``(H, W)`` is not its frame's (px of the files).

    Raises:
        ValueError: naming the mask, its frame and both sizes.
    """
    if mask != frame:
        (mh, mw), (fh, fw) = mask, frame
        raise ValueError(
            f"{row.mask}: {mw}x{mh} px but its frame {row.frame} is {fw}x{fh} px; expected a "
            "mask of its frame's size (render the session again)"
        )


def check_files(sessions: Mapping[str, Sequence[IndexRow]], with_reference: bool) -> None:
    """Every frame and mask of a dataset is a readable image (:func:`file_size`), each mask is of
    its frame's size and, ``with_reference``, each frame of its session's reference's size (the
    U-Net once refused another size without naming the frame).

    Args:
        sessions: rows per session, sorted by pressure (the first is the reference).
        with_reference: the frames are measured against their session's first frame.

    Raises:
        ValueError: naming the file (and the session and its reference frame).
    """
    for rows in sessions.values():
        ref = file_size(rows[0].frame)
        for r in rows:
            size = ref if r is rows[0] else file_size(r.frame)  # each file decoded once
            check_mask_size(r, file_size(r.mask), size)
            if with_reference and size != ref:
                raise ValueError(
                    f"{r.frame}: {size[1]}x{size[0]} px but the reference frame of its session "
                    f"{r.session}, {rows[0].frame}, is {ref[1]}x{ref[0]} px; expected every "
                    "frame of a session at its reference's size (render the session again, or "
                    "run with --no-reference and without --robustness)"
                )

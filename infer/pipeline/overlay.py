"""Overlays of contact outlines on frames, and montages of them (like the paper's comparison)."""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.files.atomic import OutputSet, run_outputs
from contactcal.infer.image.read import ImageFile
from contactcal.infer.image.write import write_image
from contactcal.infer.pipeline.manifest_rows import Frame
from contactcal.infer.pipeline.measure import Measured

#: Outline colours (BGR) per method.
COLOURS = {"unet": (60, 220, 60), "classical": (40, 40, 255), "truth": (255, 200, 0)}


def draw_overlay(
    gray: np.ndarray, contours: Mapping[str, np.ndarray | None], title: str = ""
) -> np.ndarray:
    """Draw each method's outline on a frame.

    Args:
        gray: ``(H, W) uint8`` frame.
        contours: method name → ``(N, 1, 2) int32`` outline in input pixels (None: no contact).
        title: text written in the top-left corner (e.g. the pressure).

    Returns:
        ``(H, W, 3) uint8`` BGR image.
    """
    img = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    h = img.shape[0]
    thick = max(1, round(h / 300))
    scale = max(0.35, h / 900)
    y = round(18 * scale / 0.5)
    if title:
        cv2.putText(img, title, (5, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), thick)
    for k, (name, contour) in enumerate(contours.items()):
        colour = COLOURS.get(name, (255, 255, 255))
        if contour is not None and len(contour) >= 2:
            cv2.drawContours(img, [contour], -1, colour, thick, cv2.LINE_AA)
        label = name if contour is not None else f"{name}: no contact"
        at = (5, h - 8 - round(k * 2.2 * y / 2))
        cv2.putText(img, label, at, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick)
    return img


def frame_title(frame: Frame) -> str:
    """A manifest frame's overlay title, its pressure and pass: ``"2.01 kPa, loading"`` (the
    same pressure may be in both passes of a session)."""
    return f"{frame.pressure_kpa:g} kPa, {frame.phase}"


def montage(images: Sequence[np.ndarray], columns: int, width: int = 400) -> np.ndarray:
    """Tile BGR images (resized to ``width`` px wide, same aspect as the first) into a grid."""
    if not images:
        raise ValueError("montage: no images")
    h0, w0 = images[0].shape[:2]
    height = round(width * h0 / w0)
    tiles = [cv2.resize(im, (width, height), interpolation=cv2.INTER_AREA) for im in images]
    rows = -(-len(tiles) // columns)
    blank = np.zeros_like(tiles[0])
    tiles += [blank] * (rows * columns - len(tiles))
    return np.vstack([np.hstack(tiles[r * columns : (r + 1) * columns]) for r in range(rows)])


def overlay_names(files: Sequence[str | os.PathLike[str]]) -> list[str]:
    """One overlay file name per input, distinct (case-insensitively) and deterministic.

    ``<stem>_overlay.png``; inputs whose names still collide get the next form, in turn:
    ``<stem>_<ext>`` (``x.jpg`` → ``x_jpg_overlay.png``), ``<folder>_<stem>_<ext>``
    (``a/x.jpg`` → ``a_x_jpg_overlay.png``), then ``<folder>_<stem>_<ext>_<n>`` with ``n`` the
    input's 1-based position (always distinct: ``n`` is the only part after the last ``_``).

    Args:
        files: the input images, in order.

    Returns:
        File names (no folder), in input order.
    """
    paths = [Path(os.path.abspath(f)) for f in files]
    forms = [
        lambda p, n: [p.stem],
        lambda p, n: [p.stem, p.suffix[1:]],
        lambda p, n: [p.parent.name, p.stem, p.suffix[1:]],
        lambda p, n: [p.parent.name, p.stem, p.suffix[1:], str(n)],
    ]
    level = [0] * len(paths)
    while True:
        names = [
            "_".join(x for x in forms[lv](p, n) if x) + "_overlay.png"
            for n, (p, lv) in enumerate(zip(paths, level, strict=True), start=1)
        ]
        seen = Counter(name.casefold() for name in names)
        clash = [k for k, name in enumerate(names) if seen[name.casefold()] > 1]
        if not clash:
            return names
        for k in clash:
            level[k] = min(level[k] + 1, len(forms) - 1)


def measured_frame(
    content: ImageFile, measured: Mapping[str, Measured], bit_depth: int | None = None
) -> np.ndarray:
    """``content`` decoded at full size to draw outlines on, refused unless it is the content
    every method measured (drawn on, another content would carry outlines not its own).

    Args:
        content: the frame as the run read it once for every method
            (:func:`~contactcal.infer.pipeline.overlay_measure.overlay_contents`): not read again.
        measured: method name → its measurement of ``content``, with the digest of the content
            measured (``digest=True``).
        bit_depth: significant bits of a 16-bit frame, as measured (None: from the file).

    Returns:
        ``(H, W) uint8`` frame.

    Raises:
        ValueError: a measurement without its digest, or of another content (a caller's error,
            not bad input: the run measures and draws one content).
    """
    sha, file = content.sha256(), content.path
    for name, m in measured.items():
        if m.sha256 is None:
            raise ValueError(f"{name}: {file} was measured without its digest (digest=True)")
        if m.sha256 != sha:
            raise ValueError(
                f"{name}: {file} was measured as the content with sha256 {m.sha256[:12]}…, "
                f"not the one given to draw on ({sha[:12]}…)"
            )
    return content.decode(bit_depth=bit_depth)


def write_overlays(
    runs: dict[str, list[Measured]],
    contents: Mapping[Path, ImageFile],
    out_dir: str | os.PathLike[str],
    titles: Sequence[str] | None = None,
    outputs: OutputSet | None = None,
    bit_depth: int | None = None,
) -> list[Path]:
    """Draw every method's outline on each frame and write one overlay PNG per frame.

    File names: :func:`overlay_names`. All or nothing (:func:`run_outputs`).

    Args:
        runs: method name → its measurements of the same files (same order), with their
            digests: each frame is drawn on only as the content every method measured
            (:func:`measured_frame`).
        contents: each frame's content as the run read it once, measured by every method
            (:func:`~contactcal.infer.pipeline.overlay_measure.overlay_contents`): drawn on, not
            read again.
        out_dir: folder for the overlays.
        titles: per-file caption (e.g. ``"8.0 kPa"``); default the file name.
        outputs: the enclosing run's outputs to stage into (None: this call is the run).
        bit_depth: significant bits of 16-bit frames, as measured (None: from the file).

    Returns:
        The destination paths, in file order.
    """
    first = next(iter(runs.values()))
    names = overlay_names([m.file for m in first])
    paths = [Path(out_dir) / name for name in names]
    with run_outputs([m.file for m in first], join=outputs) as outs:
        for k, m in enumerate(first):
            at = {name: ms[k] for name, ms in runs.items()}
            gray = measured_frame(contents[m.file], at, bit_depth)
            contours = {name: mk.result.contour for name, mk in at.items()}
            title = titles[k] if titles is not None else m.file.name
            write_image(outs.stage(paths[k]), draw_overlay(gray, contours, title))
    return paths


def earlier_overlays_note(written: Sequence[Path]) -> str | None:
    """A line naming overlays in the folder of ``written`` that this run did not write.

    A rerun with fewer or other frames leaves the earlier run's overlays beside the new ones;
    nothing is deleted (they may be someone's record), but the user is told.

    Args:
        written: this run's overlay paths (all in one folder).

    Returns:
        ``None`` when the folder holds no other ``*_overlay.png``, else a one-line note.
    """
    if not written:
        return None
    folder, mine = written[0].parent, {p.name.casefold() for p in written}
    others = sorted(
        p.name
        for p in folder.glob("*_overlay.png")
        if p.name.casefold() not in mine and p.is_file()  # as overlay_names: case-blind
    )
    if not others:
        return None
    shown = ", ".join(n if n.isprintable() else ascii(n) for n in others[:3])
    shown += ", …" if len(others) > 3 else ""
    return (
        f"note: {folder} also holds {len(others)} overlay(s) this run did not write ({shown}); "
        "they are from an earlier run (use an empty --overlay folder to keep runs apart)"
    )

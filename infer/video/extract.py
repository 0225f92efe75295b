"""Frames of a video (or camera) in steady pressure steps → a session folder with a manifest.

Each frame is decided once the pressure log has passed its time (:mod:`.steps` is causal, so a
growing log gives the same decisions as the complete one): kept frames are written as
``frames/f<index>.png`` (lossless: the calibration measures what the camera gave), the rest
(ramps, settling, before or after the log) are skipped. ``frames/manifest.csv`` lists the kept
frames of the steps the calibration uses (:meth:`Extractor.used_steps`: all, except an unloading
pass at one pressure, whose frames stay in ``frames/``) with columns
``file,pressure_kpa,phase,time_s``, several rows per step (repeats), the reference step
(:func:`.steps.reference_step`) first.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.calibration.phases import UNLOADING
from contactcal.infer.image.write import write_image
from contactcal.infer.video.log import PressureLog
from contactcal.infer.video.step_config import StepConfig
from contactcal.infer.video.steps import (
    Step,
    detect_steps,
    reference_step,
    step_at,
    with_phases,
)

#: The manifest's columns.
MANIFEST_COLUMNS = ("file", "pressure_kpa", "phase", "time_s")
#: PNG encoding of the kept frames: compression 1 (fast) writes a 5 MP frame several times faster
#: than the default 3 for ~10 % larger files, to keep up with a camera during live capture.
PNG_PARAMS = (cv2.IMWRITE_PNG_COMPRESSION, 1)


@dataclass(frozen=True)
class VideoFile:
    """A video file opened for decoding (:func:`open_video`)."""

    path: Path
    capture: cv2.VideoCapture
    fps: float  # frames/s, as the file states it
    #: sha256 of the file's content, streamed in chunks right before it was opened for decoding
    #: (recorded in ``calibration.json``)
    sha256: str
    #: (device, inode, size, modification time in ns) when it was hashed: :func:`video_frames`
    #: refuses a file that no longer matches once decoded
    stamp: tuple[int, int, int, int]


def _stamp(p: Path) -> tuple[int, int, int, int]:
    st = p.stat()
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns


def _changed(p: Path) -> ValueError:
    return ValueError(
        f"{p}: the video changed while it was read (replaced, or still being written); "
        "expected a finished recording (run again once it is complete)"
    )


def open_video(path: str | os.PathLike[str]) -> VideoFile:
    """Hash a video file (streamed, never held in memory), then open it for decoding.

    Raises:
        ValueError: missing file, a folder, not a regular file (a device or pipe), unreadable,
            changed while hashed, not a video OpenCV can decode, or no usable frame rate.
    """
    from contactcal.infer.files.digest import sha256_file
    from contactcal.infer.files.regular import refuse_non_file

    p = Path(path)
    expected = "a video file, e.g. .avi or .mp4"
    refuse_non_file(p, expected, ValueError)  # a folder, device or pipe: never hashed nor decoded
    if not p.is_file():
        raise ValueError(f"{p}: video not found (expected {expected})")
    try:
        stamp = _stamp(p)
        sha = sha256_file(p, expected, ValueError)
    except OSError as exc:
        raise ValueError(f"{p}: cannot read the video ({exc.strerror})") from None
    if _stamp(p) != stamp:
        raise _changed(p)
    cap = cv2.VideoCapture(str(p))
    fps = cap.get(cv2.CAP_PROP_FPS) if cap.isOpened() else 0.0
    if not cap.isOpened():
        raise ValueError(f"{p}: cannot be read as a video; expected a video file OpenCV decodes")
    if not (math.isfinite(fps) and fps > 0):
        cap.release()
        raise ValueError(f"{p}: the video states no frame rate (got {fps}); re-encode it")
    return VideoFile(p, cap, fps, sha, stamp)


def video_frames(video: VideoFile) -> Iterator[tuple[float, np.ndarray]]:
    """``(time_s, (H, W, 3) uint8 BGR frame)`` of an opened video file; time = index / fps.

    Raises:
        ValueError: no frame in the video, or the file changed since it was hashed (its
            :attr:`VideoFile.sha256` would not be of the frames decoded), naming the file.
    """
    try:
        index = 0
        while True:
            ok, frame = video.capture.read()
            if not ok:
                break
            yield index / video.fps, frame
            index += 1
        if index == 0:
            raise ValueError(f"{video.path}: the video has no decodable frame")
        try:
            same = _stamp(video.path) == video.stamp
        except OSError:  # removed
            same = False
        if not same:
            raise _changed(video.path)
    finally:
        video.capture.release()


@dataclass(frozen=True)
class Decision:
    """One frame's outcome."""

    index: int  # frame number in the video or capture, from 0
    time_s: float
    frame: np.ndarray  # (H, W, 3) uint8 BGR
    step: Step | None  # None: skipped (ramp, settling, outside the log)


@dataclass
class Extractor:
    """Decides on frames as the log passes their time and stages the kept ones.

    Args:
        cfg: the steadiness settings.
        frames_dir: the destination folder of the frames (``DIR/frames``).
        stage: maps a destination path to the path to write (``OutputSet.stage``).
    """

    cfg: StepConfig
    frames_dir: Path
    stage: Callable[[Path], Path]
    log: PressureLog | None = None
    steps: list[Step] = field(default_factory=list)
    kept: dict[int, list[tuple[str, float]]] = field(default_factory=dict)  # step → (file, t)
    last_time_s: float = -math.inf
    first_time_s: float = math.inf
    frames_seen: int = 0
    _log_end: float = -math.inf
    _pending: list[tuple[int, float, np.ndarray]] = field(default_factory=list)

    def frame_interval_s(self) -> float | None:
        """Mean time between the frames seen so far, s (None before two frames)."""
        if self.frames_seen < 2:
            return None
        return (self.last_time_s - self.first_time_s) / (self.frames_seen - 1)

    def update_log(self, log: PressureLog) -> None:
        """Use the log as it is now (the complete log, or a live one read again)."""
        self.log, self.steps = log, detect_steps(log, self.cfg)
        self._log_end = float(log.times_s[-1]) if len(log.times_s) else -math.inf

    def add(self, index: int, time_s: float, frame: np.ndarray) -> list[Decision]:
        """Queue a frame; return the decisions now possible (frames the log has passed)."""
        if time_s <= self.last_time_s:
            raise ValueError(f"frame {index}: time {time_s:g} s is not after the previous frame")
        self.last_time_s, self.first_time_s = time_s, min(self.first_time_s, time_s)
        self.frames_seen += 1
        self._pending.append((index, time_s, frame))
        return self._decide(lambda t: t < self._log_end)

    def finish(self) -> list[Decision]:
        """Decide on the frames still queued, against the log as it is now."""
        return self._decide(lambda t: True)

    def _decide(self, ready: Callable[[float], bool]) -> list[Decision]:
        out = []
        while self._pending and ready(self._pending[0][1]):
            index, t, frame = self._pending.pop(0)
            step = step_at(self.steps, t)
            if step is not None:
                name = f"f{index:06d}.png"
                write_image(self.stage(self.frames_dir / name), frame, PNG_PARAMS)
                self.kept.setdefault(step.index, []).append((name, t))
            out.append(Decision(index, t, frame, step))
        return out

    def kept_steps(self) -> list[Step]:
        """The steps with kept frames, in time order, their phases split at the highest of them
        (:func:`~contactcal.infer.video.steps.with_phases`: a frameless sliver is no top)."""
        return with_phases([s for s in self.steps if s.index in self.kept])

    def used_steps(self) -> list[Step]:
        """The steps with kept frames that the calibration uses, in time order: all of them,
        except an unloading pass at fewer than two pressures (e.g. a vent straight back to
        0 kPa after the top step), which is no curve (:meth:`left_out`)."""
        kept = self.kept_steps()
        unloading = {f"{s.pressure_kpa:g}" for s in kept if s.phase == UNLOADING}
        return kept if len(unloading) >= 2 else [s for s in kept if s.phase != UNLOADING]

    def left_out(self) -> list[Step]:
        """Steps with kept frames that :meth:`used_steps` leaves out (their frames stay in
        ``frames/``, outside the manifest)."""
        used = {s.index for s in self.used_steps()}
        return [s for s in self.kept_steps() if s.index not in used]

    def manifest_text(self) -> str:
        """``frames/manifest.csv``: the reference step first, then the used steps in time order."""
        used = self.used_steps()
        ref = reference_step(used)
        order = [ref, *(s for s in used if s is not ref)]
        lines = [",".join(MANIFEST_COLUMNS)]
        for s in order:
            lines += [f"{f},{s.pressure_kpa:g},{s.phase},{t:.4f}" for f, t in self.kept[s.index]]
        return "\n".join(lines) + "\n"

    def summary(self) -> str:
        """Per step: pressure, phase, frames kept and their time span (the CLI prints it)."""
        lines = ["step  pressure (kPa)  phase      frames  time (s)"]
        out = {s.index for s in self.left_out()}
        phased = {s.index: s for s in self.kept_steps()}
        for s in (phased.get(s.index, s) for s in self.steps):
            kept = self.kept.get(s.index, [])
            span = f"{kept[0][1]:.2f}-{kept[-1][1]:.2f}" if kept else "-"
            note = "  (left out: a one-pressure unloading pass is no curve)" * (s.index in out)
            lines.append(
                f"{s.index:4d}  {s.pressure_kpa:14.3f}  {s.phase:9s}  {len(kept):6d}  {span}{note}"
            )
        return "\n".join(lines)


def extract_frames(
    frames: Iterator[tuple[float, np.ndarray]],
    extractor: Extractor,
    log_feed: Callable[[], PressureLog | None],
    observe: Callable[[Decision], None] = lambda d: None,
    stop: Callable[[Extractor, float], bool] = lambda e, t: False,
) -> None:
    """Run frames through the extractor: the one loop of ``--video`` and ``--camera``.

    Args:
        frames: ``(time_s, BGR frame)`` in time order (:func:`video_frames`, or a camera).
        extractor: decides and stages.
        log_feed: the log when it changed since the last call, else None (called per frame).
        observe: called with each decision, in frame order (progress, preview).
        stop: called after each frame with the extractor and the frame's time; True ends it.
    """
    for index, (t, frame) in enumerate(frames):
        log = log_feed()
        if log is not None:
            extractor.update_log(log)
        for d in extractor.add(index, t, frame):
            observe(d)
        if stop(extractor, t):
            break
    log = log_feed()
    if log is not None:
        extractor.update_log(log)
    for d in extractor.finish():
        observe(d)

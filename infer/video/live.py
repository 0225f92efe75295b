"""Live capture: camera frames with timestamps, a growing pressure log, progress and a preview.

Any ``cv2.VideoCapture`` is a source (a camera index, or a video file, which the tests use), with
an injectable clock: a frame's time is ``clock()`` when it arrived minus that of the first frame.
The capture stops when the log has returned to rest (a step at or below
:data:`~contactcal.infer.calibration.gate_check.REST_KPA`, the rule the calibration uses for its
reference frame: a gauge may read a little above 0) after its highest step and that step has
been kept for ``settle_s`` (so it has frames too), at ``--duration-s``, or when the camera stops.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

import cv2
import numpy as np

from contactcal.infer.calibration.gate_check import REST_KPA
from contactcal.infer.image.gray import to_gray_u8
from contactcal.infer.methods.base import Method
from contactcal.infer.pipeline.overlay import draw_overlay
from contactcal.infer.video.extract import Decision, Extractor
from contactcal.infer.video.log import PressureLog, read_log_bytes, read_pressure_log
from contactcal.infer.video.preview_files import PREVIEW_FORMATS
from contactcal.infer.video.steps import reference_step


def open_camera(index: int) -> cv2.VideoCapture:
    """Open camera ``index`` (OpenCV's numbering).

    OpenCV's own messages while it tries its backends (warnings, and on some builds an error
    line) are held back, its log level restored afterwards: a camera that does not open gets the
    one line below instead.

    Raises:
        ValueError: a negative index (OpenCV's "any camera", which crashed the process with
            OpenCV 5.0), or the camera cannot be opened.
    """
    if index < 0:
        raise ValueError(f"--camera {index}: expected a camera index >= 0 (0 is the first camera)")
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        cap = cv2.VideoCapture(index)
    finally:
        cv2.utils.logging.setLogLevel(level)
    if not cap.isOpened():
        raise ValueError(
            f"camera {index}: cannot be opened; check the index (0 is the first camera) and "
            "that no other program holds the camera"
        )
    return cap


def capture_frames(
    capture: Any, clock: Callable[[], float] = time.monotonic
) -> Iterator[tuple[float, np.ndarray]]:
    """``(time_s since the first frame, (H, W, 3) uint8 BGR frame)`` until the source ends.

    Args:
        capture: an opened ``cv2.VideoCapture`` (camera or file); released at the end.
        clock: seconds, monotonic; read when each frame has arrived.
    """
    t0 = None
    try:
        while True:
            ok, frame = capture.read()
            if not ok:
                return
            now = clock()
            t0 = now if t0 is None else t0
            yield now - t0, frame
    finally:
        capture.release()


class LogPoller:
    """The pressure log as the controller writes it: read again whenever the file changed (the
    last log returned is the one the capture used, its :attr:`~.log.PressureLog.sha256` of the
    bytes parsed then)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._seen: tuple[int, int] | None = None
        read_log_bytes(path)  # fails now, clearly, for a wrong path

    def __call__(self) -> PressureLog | None:
        """The log if it changed since the last call, else None (a partial last line waits)."""
        st = os.stat(self.path)
        if (st.st_size, st.st_mtime_ns) == self._seen:
            return None
        self._seen = (st.st_size, st.st_mtime_ns)
        return read_pressure_log(self.path, complete=False)


def returned_to_zero(extractor: Extractor, _time_s: float) -> bool:
    """Whether a step at rest after the highest step has been kept for ``settle_s``.

    At rest: at or below :data:`~contactcal.infer.calibration.gate_check.REST_KPA` (kPa), as for
    the calibration's reference frame, so a gauge that reads e.g. 0.15 kPa at rest still stops
    the capture, and within the band (2 × tolerance) of the reference step, so an unloading step
    at 0.5 kPa above a 0 kPa reference does not (its 0 kPa step comes next); the highest step
    must be above it.
    """
    steps, cfg = extractor.steps, extractor.cfg
    if not steps:
        return False
    top = max(steps, key=lambda s: s.pressure_kpa)
    rest = min(REST_KPA, reference_step(steps).pressure_kpa + 2 * cfg.tolerance_kpa)
    for s in steps[top.index + 1 :]:
        kept = extractor.kept.get(s.index, [])
        if s.pressure_kpa <= rest < top.pressure_kpa and kept:
            if kept[-1][1] - kept[0][1] >= cfg.settle_s:
                return True
    return False


def preview_format(fps: float = 10.0) -> tuple[str, str]:
    """The first of :data:`PREVIEW_FORMATS` this OpenCV build can write: (suffix, fourcc)."""
    with tempfile.TemporaryDirectory() as tmp:
        for suffix, fourcc in PREVIEW_FORMATS:
            path = str(Path(tmp) / f"probe{suffix}")
            writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*fourcc), fps, (32, 32))
            ok = writer.isOpened()
            if ok:
                writer.write(np.zeros((32, 32, 3), np.uint8))
            writer.release()
            if ok and os.path.getsize(path) > 0:
                return suffix, fourcc
    raise OSError("this OpenCV build writes no video format (tried mp4v .mp4 and MJPG .avi)")


class Preview:
    """Frames with the U-Net outline (kept frames) and the pressure, to a video or a window.

    The outline is measured against the first kept frame, the first step's (normally 0 kPa):
    the preview's reference; the calibration uses its own.

    Args:
        method: the U-Net with outlines (``make_method("unet", ..., outline=True)``).
        extractor: gives the log (pressure of skipped frames).
        path: the staged preview video, or None to show a window instead.
        fourcc, fps: the video's codec and frame rate.
    """

    def __init__(
        self, method: Method, extractor: Extractor, path: Path | None, fourcc: str, fps: float
    ) -> None:
        self.method, self.extractor, self.path = method, extractor, path
        self.fourcc, self.fps = fourcc, fps
        self._writer: Any = None
        self._has_reference = False
        if path is None:
            try:
                cv2.namedWindow("contactcal")
            except cv2.error:
                raise ValueError(
                    "--show: this OpenCV build has no window support (a -headless package); "
                    "drop --show to write the preview video instead"
                ) from None

    def __call__(self, d: Decision) -> None:
        """Draw one decided frame and write or show it."""
        gray = to_gray_u8(d.frame, bgr=True)
        contours: dict[str, np.ndarray | None] = {}
        if d.step is not None:
            if not self._has_reference:
                self.method.set_reference(gray, 1)
                self._has_reference = True
            contours["unet"] = self.method.measure(gray).contour
            title = f"{d.time_s:7.2f} s  {d.step.pressure_kpa:g} kPa  kept (step {d.step.index})"
        else:
            title = f"{d.time_s:7.2f} s  {self._pressure(d.time_s)}  skipped"
        img = draw_overlay(gray, contours, title)
        if self.path is None:
            cv2.imshow("contactcal", img)
            cv2.waitKey(1)
            return
        if self._writer is None:
            size = (img.shape[1], img.shape[0])
            self._writer = cv2.VideoWriter(
                str(self.path), cv2.VideoWriter_fourcc(*self.fourcc), self.fps, size
            )
            if not self._writer.isOpened():
                raise OSError(f"{self.path}: cannot write the preview video ({self.fourcc})")
        self._writer.write(img)

    def _pressure(self, t: float) -> str:
        log = self.extractor.log
        if log is None or not len(log.times_s) or not log.times_s[0] <= t <= log.times_s[-1]:
            return "(no pressure yet)"
        return f"{float(np.interp(t, log.times_s, log.pressures_kpa)):.2f} kPa"

    def close(self) -> None:
        """Finish the video (or close the window)."""
        if self._writer is not None:
            self._writer.release()
        elif self.path is None:
            cv2.destroyWindow("contactcal")


class Progress:
    """One line per step on stderr once it is over: pressure and frames kept."""

    def __init__(self, extractor: Extractor, stream: IO[str] | None = None) -> None:
        self.extractor = extractor
        self.stream = stream if stream is not None else sys.stderr
        self._step: int | None = None
        self._count = 0

    def __call__(self, d: Decision) -> None:
        """Count a decided frame; a frame of a new step ends the previous step's line."""
        if d.step is None:
            return
        if self._step != d.step.index:
            self.close()
            self._step, self._count = d.step.index, 0
        self._count += 1

    def close(self) -> None:
        """Print the current step's line (its pressure as the log now says), if any."""
        if self._step is not None:
            step = self.extractor.steps[self._step]
            print(f"step {step.index}: {step.label()}, {self._count} frames kept", file=self.stream)
        self._step = None

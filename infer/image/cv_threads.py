"""OpenCV's worker threads, set for a block of work and restored after it."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import cv2


@contextmanager
def opencv_threads(threads: int) -> Iterator[None]:
    """Run the block with OpenCV's parallel loops on ``threads`` threads (restored after).

    OpenCV parallelises its own functions (blur, resize, morphology) over every core unless told
    otherwise, so without this a "one thread" timing of an OpenCV routine is not on one thread. The
    setting is process-wide and OpenCV's setter is not thread-safe: call this from the main thread,
    around whole commands or timed blocks, never inside parallel work.

    Args:
        threads: worker threads, >= 1 (1: everything on the calling thread).

    Raises:
        ValueError: ``threads`` < 1.
    """
    if threads < 1:
        raise ValueError(f"threads must be >= 1, got {threads}")
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        yield
    finally:
        cv2.setNumThreads(before)

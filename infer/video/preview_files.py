"""The preview file a ``calibrate --video`` / ``--camera`` run writes beside its calibration.

Constants and one folder look-up (no OpenCV video code), so that a manifest run can name what a
recording left in its ``--out`` without importing the video pipeline.
"""

from __future__ import annotations

from pathlib import Path

#: The preview's file name without its suffix: ``preview.mp4`` (or ``.avi``).
PREVIEW_STEM = "preview"
#: Preview codecs tried in order (suffix, fourcc): MPEG-4 part 2 in .mp4 plays everywhere; builds
#: without an MPEG-4 encoder still have Motion-JPEG (in .avi).
PREVIEW_FORMATS = ((".mp4", "mp4v"), (".avi", "MJPG"))
#: Every name a preview may have.
PREVIEW_FILES = tuple(PREVIEW_STEM + suffix for suffix, _ in PREVIEW_FORMATS)


def previews_in(out: Path) -> list[str]:
    """The preview files (names of :data:`PREVIEW_FILES`) folder ``out`` holds."""
    return [name for name in PREVIEW_FILES if (out / name).is_file()]

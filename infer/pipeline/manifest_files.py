"""The image files a session manifest lists: each one there, and each on one row only.

:func:`check_files` is the last step of
:func:`~contactcal.infer.pipeline.manifest.read_session` (after the steps are numbered).
"""

from __future__ import annotations

import os
from pathlib import Path

from contactcal.infer.errors import few
from contactcal.infer.files.regular import refuse_special
from contactcal.infer.pipeline.manifest_rows import Frame, ManifestError

#: At most this many rows a manifest's refusal lists (then how many more).
MAX_LISTED = 5


def check_files(where: str, frames: list[Frame], base: Path) -> None:
    """Reject a listed file that is a device, pipe or socket (unread), missing image files and
    one image on two rows.

    Args:
        where: the manifest, for the message.
        frames: its frames.
        base: the folder its relative frame paths were joined to.

    Raises:
        ManifestError: naming the rows and files, and how relative paths are resolved.
    """
    by_row = sorted(frames, key=lambda f: f.row)
    for f in by_row:
        refuse_special(f.file, f"an image file (row {f.row} of {where})", ManifestError)
    missing = [f for f in by_row if not f.file.is_file()]
    if missing:
        listed = few(
            [f"row {f.row}: {f.file}{' (a folder)' if f.file.is_dir() else ''}" for f in missing],
            MAX_LISTED,
            "; ",
        )
        windows = any("\\" in str(f.file) for f in missing) and os.sep != "\\"
        hint = " (written with '\\' as on Windows? use '/' between folders)" if windows else ""
        raise ManifestError(
            f"{where}: {len(missing)} image file(s) not found: {listed}; relative paths "
            f"are resolved against the manifest's folder {base}{hint}"
        )
    _check_distinct_files(where, frames)


def _check_distinct_files(where: str, frames: list[Frame]) -> None:
    """Reject one image on two rows (same file after resolving links, or a hard link to it)."""
    seen: dict[tuple[int, int], Frame] = {}
    for f in sorted(frames, key=lambda f: f.row):
        st = f.file.stat()
        first = seen.setdefault((st.st_dev, st.st_ino), f)
        if first is not f:
            raise ManifestError(
                f"{where}: rows {first.row} ({first.file}) and {f.row} ({f.file}) are the same "
                "image file; expected each image on one row (a step may hold several images): list "
                "each frame once"
            )

"""An ``--out`` folder fresh for a ``calibrate --video`` / ``--camera`` run: one holding an
earlier recording's outputs (frames, a preview) is refused before any work."""

from __future__ import annotations

from pathlib import Path


def check_fresh_recording(out: Path) -> None:
    """Refuse an ``--out`` holding an earlier recording's outputs, before any work: frames in
    ``frames/`` (:func:`check_fresh_frames`), or a preview (``preview.mp4`` or ``.avi``), which
    a run without ``--preview`` (or writing the other format) would leave beside its calibration.

    Raises:
        ValueError: naming the folder or file and what to do.
    """
    from contactcal.infer.video.preview_files import previews_in

    check_fresh_frames(out / "frames")
    stale = [str(out / name) for name in previews_in(out)]
    if stale:
        raise ValueError(
            f"{' and '.join(stale)}: the preview of an earlier recording; expected a new --out "
            "folder for each recording (or remove "
            f"{'that file' if len(stale) == 1 else 'those files'} first)"
        )


def check_fresh_frames(frames_dir: Path) -> None:
    """Refuse a ``frames/`` folder that already holds files: an earlier recording's frames would
    stay beside this one's, outside its manifest.

    The staging entries of a killed run (:data:`~contactcal.infer.files.temporaries.TEMP_NAME`,
    their process gone) are no frames: they are removed first, as the next write into the
    folder would (:func:`~contactcal.infer.files.temporaries.remove_stale_temporaries`). Those of a
    run still going are another recording into the same folder: refused, said so.

    Raises:
        ValueError: naming the folder and what to do.
    """
    from contactcal.infer.files.temporaries import TEMP_NAME, remove_stale_temporaries

    if not frames_dir.is_dir():
        return
    remove_stale_temporaries(frames_dir)
    names = [p.name for p in frames_dir.iterdir()]
    if not names:
        return
    staging = [m for m in map(TEMP_NAME.match, names) if m is not None]
    if len(staging) == len(names):
        pids = sorted({m["pid"] for m in staging})
        raise ValueError(
            f"{frames_dir}: another run (process {', '.join(pids)}) is writing a recording into "
            "it; expected a new --out folder for each recording"
        )
    raise ValueError(
        f"{frames_dir}: holds the frames of an earlier recording; expected a new --out "
        "folder for each recording (or remove that folder first)"
    )

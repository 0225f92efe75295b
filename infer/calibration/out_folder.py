"""What ``calibrate``'s ``--out`` may already hold, checked before a run measures anything.

A run into a folder that holds a calibration replaces it whole, with a note
(:func:`~contactcal.infer.calibration.record.earlier_record_note`): a re-calibration of the same
display. It is refused where that would lose another display's record (the device ids differ)
or leave a recording's ``frames/`` and preview beside a calibration made of other frames.
"""

from __future__ import annotations

import os
from pathlib import Path

from contactcal.infer.calibration.record import HeldRecord, earlier_record_note, held_record
from contactcal.infer.files.temporaries import TEMP_NAME
from contactcal.infer.video.preview_files import previews_in


def check_reused_out(out: Path, device_id: str | None, manifest: Path | None) -> str | None:
    """Refuse an ``--out`` this run must not write into; else the note on what it replaces.

    Args:
        out: the run's output folder, before the run.
        device_id: this run's ``--device-id`` (None: not given).
        manifest: the still frames' manifest (None: a video or camera run, whose own check
            refuses an earlier recording's frames or preview:
            :func:`~contactcal.infer.video.command.check_fresh_recording`).

    Returns:
        The note :func:`~contactcal.infer.calibration.record.earlier_record_note` gives (None:
        nothing replaced), from the ``calibration.json`` read once for both.

    Raises:
        ValueError: ``out`` holds another display's calibration, or (a manifest run) an earlier
            recording's frames or preview; one line naming it and what to do.
    """
    held = held_record(out)
    check_same_device(held, device_id)
    if manifest is not None:
        check_no_recording(out, manifest)
    return earlier_record_note(out, held)


def _recorded_device(held: HeldRecord) -> str | None:
    """The device id a held ``calibration.json`` names; None: none, or not a record (which a
    run replaces with a note, as before)."""
    device = None if held.data is None else held.data.get("device_id")
    return None if device is None else str(device)


def check_same_device(
    held: HeldRecord | None, device_id: str | None, takes_device_id: bool = True
) -> None:
    """Refuse to replace a calibration that names another display than this run's.

    A record with a device id is replaced only by a run with that id (a re-calibration). A run
    without ``--device-id`` cannot say it calibrates the same display, so it is refused too:
    a typo in ``--out`` would otherwise lose that display's curve.

    Args:
        held: the ``--out`` folder's ``calibration.json`` as read before the run
            (:func:`~contactcal.infer.calibration.record.held_record`; None: none).
        device_id: this run's ``--device-id`` (None: not given).
        takes_device_id: whether the command has ``--device-id`` (``demo`` has none: the
            message then does not suggest it).

    Raises:
        ValueError: the record's id differs from ``device_id`` or ``device_id`` is None.
    """
    if held is None:
        return
    recorded = _recorded_device(held)
    if recorded is None or recorded == device_id:
        return
    this = "gives no --device-id" if device_id is None else f"is for --device-id {device_id!r}"
    again = f"to re-calibrate {recorded!r}, give --device-id {recorded!r}; "
    again = again if takes_device_id else ""
    raise ValueError(
        f"{held.path}: holds the calibration of device id {recorded!r}, and this run {this}; "
        f"expected another --out for this display ({again}"
        "to replace that record deliberately, remove it first)"
    )


def check_no_recording(out: Path, manifest: Path) -> None:
    """Refuse a still-frame run into the folder of a ``calibrate --video`` / ``--camera`` run:
    its ``frames/`` and preview would stay beside a calibration of other frames.

    Calibrating that recording's own ``frames/manifest.csv`` again into its folder is allowed:
    the calibration is then of those frames. Staging entries a killed run left in ``frames/``
    (:data:`~contactcal.infer.files.temporaries.TEMP_NAME`) are no recording.

    Raises:
        ValueError: naming the folder and what it holds.
    """
    frames = out / "frames"
    if manifest.resolve() == (frames / "manifest.csv").resolve():
        return
    held = [f"{n} (a recording's preview)" for n in previews_in(out)]
    if frames.is_dir() and any(TEMP_NAME.match(n) is None for n in os.listdir(frames)):
        held.insert(0, "frames/ (a recording's frames)")
    if held:
        raise ValueError(
            f"{out}: holds {' and '.join(held)} of an earlier calibrate --video/--camera run, "
            f"which would stay beside a calibration of {manifest}; expected another --out "
            "(or remove that run's files first)"
        )

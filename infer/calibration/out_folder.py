"""What ``calibrate``'s ``--out`` may already hold, checked before a run measures anything.

A run into a folder that holds a calibration replaces it whole, with a note
(:func:`earlier_record_note`): a re-calibration of the same display. It is refused where that
would lose another display's record (the device ids differ), replace a record in mm² with one in
px (this run has no pixel scale), or leave a recording's ``frames/`` and preview beside a
calibration made of other frames. The ``calibration.json`` held is read once, as inputs are
(:func:`held_record`), for the checks and the note; one that is no calibration record (a
folder, a device or pipe, unreadable, not JSON, or JSON without the record's ``format``) is
refused, as its device id, which the device check needs, is unknown.
"""

from __future__ import annotations

import os
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.calibration.curve import MM2
from contactcal.infer.calibration.load import FORMAT
from contactcal.infer.files.regular import read_record_json
from contactcal.infer.files.temporaries import TEMP_NAME
from contactcal.infer.video.preview_files import previews_in

#: What a ``calibration.json`` in ``--out`` must be for a run to replace it, and what to do
#: otherwise (a typo in ``--out`` could lose another display's record, damaged or hand-edited).
HELD_EXPECTED = (
    "a calibration record, whose device id tells whether this run may replace it; move it away "
    "or give another --out"
)


@dataclass(frozen=True)
class HeldRecord:
    """The ``calibration.json`` an output folder holds before a run, read once
    (:func:`held_record`): the device check and the note on what the run replaces both see it."""

    #: Its path.
    path: Path
    #: Its JSON object, a calibration record of any format version.
    data: dict[str, Any]


def held_record(out_dir: str | os.PathLike[str]) -> HeldRecord | None:
    """The ``calibration.json`` ``out_dir`` holds, read once as inputs are; None: none.

    Any record ``contactcal`` wrote is one (its ``format``, whatever its version and fields).

    Raises:
        ValueError: it is no calibration record: a folder, a device or pipe (refused unread),
            unreadable, not JSON, or JSON without the record's ``format``; one line naming it,
            what it is, and what to do (:data:`HELD_EXPECTED`).
    """
    path = Path(out_dir) / "calibration.json"
    if not os.path.lexists(path):  # none there (a link to nothing is refused, unreadable)
        return None
    data = read_record_json(path, HELD_EXPECTED)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        found = f'not a contactcal calibration record (no "format": "{FORMAT}")'
        raise ValueError(f"{path}: {found}; expected {HELD_EXPECTED}")
    return HeldRecord(path, data)


def earlier_record_note(out_dir: str | os.PathLike[str], held: HeldRecord | None) -> str | None:
    """A line naming the calibration ``out_dir`` holds before a run writes its own (None: none).

    A run into the same ``--out`` replaces ``calibration.json``, ``.csv`` and ``curve.png``
    whole (the earlier files stay until the new ones are complete); the user is told which
    record went, so that an earlier display's curve is not lost without a word.

    Args:
        out_dir: the run's output folder, before the run.
        held: its ``calibration.json`` as read before the run (:func:`held_record`).

    Returns:
        ``None`` without an earlier ``calibration.json``, ``.csv`` or ``curve.png``, else a
        one-line note naming the record's creation time and device id, or, without a
        ``calibration.json``, the files replaced.
    """
    if held is None:
        held_files = [n for n in ("calibration.csv", "curve.png") if (Path(out_dir) / n).is_file()]
        if not held_files:
            return None
        return (
            f"note: replaced the {' and '.join(held_files)} that {out_dir} held (no "
            f"calibration.json beside {'them' if len(held_files) > 1 else 'it'}: not a "
            "contactcal record); give each run its own --out to keep both"
        )
    created, device = held.data.get("created"), held.data.get("device_id")
    when = "no creation time" if created is None else f"created {created}"
    named = "no device id" if device is None else f"device id {device!r}"
    what = f"{when}, {named}"
    return (
        f"note: replaced the calibration that {out_dir} held ({what}); give each run its own --out "
        "to keep both"
    )


def check_reused_out(
    out: Path, device_id: str | None, manifest: Path | None, no_scale: str | None
) -> str | None:
    """Refuse an ``--out`` this run must not write into; else the note on what it replaces.

    Args:
        out: the run's output folder, before the run.
        device_id: this run's ``--device-id`` (None: not given).
        manifest: the still frames' manifest (None: a video or camera run, whose own check
            refuses an earlier recording's frames or preview:
            :func:`~contactcal.infer.video.fresh_out.check_fresh_recording`).
        no_scale: where this run looked for a pixel scale and found none (as
            :data:`~contactcal.infer.pipeline.args.NO_SCALE_NOTE` says it); None: it has one.

    Returns:
        The note :func:`earlier_record_note` gives (None: nothing replaced), from the
        ``calibration.json`` read once for both.

    Raises:
        ValueError: ``out`` holds a ``calibration.json`` that is no record
            (:func:`held_record`), another display's calibration, one in mm² that this run
            without a scale would replace with one in px, or (a manifest run) an earlier
            recording's frames or preview; one line naming it and what to do.
    """
    held = held_record(out)
    check_same_device(held, device_id)
    check_same_unit(held, no_scale, "give the --rig or --mm-per-px it used")
    if manifest is not None:
        check_no_recording(out, manifest)
    return earlier_record_note(out, held)


def _recorded_device(held: HeldRecord) -> str | None:
    """The device id a held ``calibration.json`` names; None: none."""
    device = held.data.get("device_id")
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
            (:func:`held_record`; None: none).
        device_id: this run's ``--device-id`` (None: not given).
        takes_device_id: whether the command has ``--device-id`` (``demo`` has none: the
            message then names no such option).

    Raises:
        ValueError: the record's id differs from ``device_id`` or ``device_id`` is None.
    """
    if held is None:
        return
    recorded = _recorded_device(held)
    if recorded is None or recorded == device_id:
        return
    if not takes_device_id:
        this, again = "records no device id", ""
    else:
        this = "gives no --device-id" if device_id is None else f"is for --device-id {device_id!r}"
        again = f"to re-calibrate {recorded!r}, give --device-id {recorded!r}; "
    raise ValueError(
        f"{held.path}: holds the calibration of device id {recorded!r}, and this run {this}; "
        f"expected another --out for this display ({again}"
        "to replace that record deliberately, remove it first)"
    )


def check_same_unit(held: HeldRecord | None, no_scale: str | None, scale_from: str) -> None:
    """Refuse to replace a calibration in mm² with one in px: a run without a pixel scale
    (typically a re-calibration that left out the earlier run's ``--rig``) would otherwise
    turn the record a controller loads as mm² into one it refuses, said only in notes.

    A run with a scale may replace a record in px (the areas gain their unit).

    Args:
        held: the ``--out`` folder's ``calibration.json`` as read before the run
            (:func:`held_record`; None: none).
        no_scale: where this run looked for a pixel scale and found none; None: it has one.
        scale_from: what to do to give this run the earlier run's scale (the command's own
            ways: ``demo`` reads only the rig.json beside its manifest).

    Raises:
        ValueError: the record is in mm² and ``no_scale`` is not None; one line naming it, the
            scale options its command line gave (if it recorded them), and what to do.
    """
    if held is None or no_scale is None:
        return
    if held.data.get("area_unit") != MM2:
        return
    given = _scale_options(held.data.get("argv"))
    earlier = "" if given is None else f" (its command line gave {given})"
    raise ValueError(
        f"{held.path}: holds a calibration in {MM2}, and this run has no pixel scale "
        f"({no_scale}): its areas would be in px, in a record a controller expecting {MM2} "
        f"refuses; expected the earlier run's scale: {scale_from}{earlier}, or remove that "
        "record first to replace it with one in px deliberately"
    )


#: The options that give ``calibrate`` its pixel scale.
SCALE_OPTIONS = ("--rig", "--mm-per-px")


def _scale_option(arg: str) -> str | None:
    """The scale option (:data:`SCALE_OPTIONS`) that ``arg`` (``--name`` or ``--name=value``)
    gave, also as an abbreviation (``--mm 0.05``), which argparse accepted before the CLI
    refused prefixes: records written then still hold them; None: none."""
    name = arg.split("=", 1)[0]
    if not name.startswith("--") or len(name) < 3:
        return None
    named = [o for o in SCALE_OPTIONS if o.startswith(name)]
    return named[0] if len(named) == 1 else None


def _scale_options(argv: object) -> str | None:
    """The pixel scale options a held record's ``argv`` gave, spelled out and quoted for a
    shell; None: it recorded no ``calibrate`` command line (``demo``'s has no such options, and
    its abbreviations are of others: ``--m`` is its ``--manifest``), or one without them."""
    if not isinstance(argv, list) or argv[:1] != ["calibrate"]:
        return None
    args = [str(a) for a in argv]
    given: list[str] = []
    for i, arg in enumerate(args):
        option = _scale_option(arg)
        if option is None:
            continue
        if "=" in arg:
            given.append(f"{option}={arg.split('=', 1)[1]}")
        elif i + 1 < len(args):
            given += [option, args[i + 1]]
    return shlex.join(given) if given else None


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

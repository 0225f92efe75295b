"""What a calibration run used: method configuration, input digests, command line, display
identifier and package versions (recorded in ``calibration.json``)."""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from contactcal.infer.calibration.hysteresis import MATCH_TOLERANCE_KPA
from contactcal.infer.errors import few
from contactcal.infer.pipeline.manifest_rows import listed_name

if TYPE_CHECKING:
    from contactcal.infer.pipeline.manifest import Session

#: Longest accepted ``--device-id``, characters.
DEVICE_ID_MAX = 100
# Distribution names probed for versions (first installed one wins); metadata only, no import.
_DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "contactcal": ("contactcal",),
    "numpy": ("numpy",),
    "opencv": (
        "opencv-contrib-python-headless",
        "opencv-python-headless",
        "opencv-contrib-python",
        "opencv-python",
    ),
    "onnxruntime": ("onnxruntime", "onnxruntime-gpu"),
}


def package_versions() -> dict[str, str | None]:
    """Installed versions of contactcal, numpy, opencv, onnxruntime (None if absent)."""
    from importlib import metadata  # ~10-15 ms to import: only when a record is written

    out: dict[str, str | None] = {}
    for key, dists in _DISTRIBUTIONS.items():
        out[key] = None
        for dist in dists:
            with contextlib.suppress(metadata.PackageNotFoundError):
                out[key] = metadata.version(dist)
                break
    return out


def check_device_id(device_id: str | None) -> str | None:
    """Validate a display identifier: None, or 1-100 printable characters.

    Raises:
        ValueError: empty, too long or with control characters (the message says which).
    """
    if device_id is None:
        return None
    if not device_id or not device_id.isprintable() or len(device_id) > DEVICE_ID_MAX:
        shown = device_id if len(device_id) <= 40 else device_id[:40] + "…"
        raise ValueError(
            f"--device-id {shown!r}: expected 1-{DEVICE_ID_MAX} printable characters (e.g. the "
            f"display's serial number), got {len(device_id)} characters"
            + ("" if device_id.isprintable() else " including control characters")
        )
    return device_id


def input_digests(
    manifest: Path,
    session: Session,
    frames: Sequence[tuple[Path, str]],
    recorded: Path | None = None,
    recording: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The record of the manifest and each frame with the sha256 of the content the run read
    (frames named as the manifest lists them:
    :func:`~contactcal.infer.pipeline.manifest_rows.listed_name`): digests of the bytes parsed
    and measured, never of the files read again (which may have been replaced in between).

    Args:
        manifest: the manifest read.
        session: the manifest as read: the sha256 of its content as parsed and the folder its
            frame paths were joined to (:class:`~contactcal.infer.pipeline.manifest.Session`).
        frames: each frame's path and the sha256 of its content as measured
            (:attr:`~contactcal.infer.pipeline.measure.Measured.sha256`).
        recorded: the manifest's path in the record (None: ``manifest`` itself).
        recording: the video or camera and pressure log the frames were extracted from
            (:func:`recording_digests`); None: a manifest's frames (recorded as null).
    """
    return {
        "manifest": {"file": str((recorded or manifest).resolve()), "sha256": session.sha256},
        "frames": [{"file": listed_name(session.folder, f), "sha256": h} for f, h in frames],
        "recording": recording,
    }


def recording_digests(
    video: tuple[Path, str] | None, camera: int | None, log: tuple[Path, str]
) -> dict[str, Any]:
    """The record of what a ``calibrate --video`` / ``--camera`` run extracted its frames from:
    ``{"video": {"file", "sha256"} | None, "camera": index | None, "pressure_log": {"file",
    "sha256"}}``, paths made absolute.

    Args:
        video: the video file and the sha256 of its content, streamed right before it was
            decoded (:attr:`~contactcal.infer.video.extract.VideoFile.sha256`); None: a camera.
        camera: the camera index (``--camera``); None: a video file.
        log: the pressure log and the sha256 of the bytes the run parsed (a camera run's log,
            read as it grew: its last read, the one the capture used).
    """
    return {
        "video": None if video is None else {"file": str(video[0].resolve()), "sha256": video[1]},
        "camera": camera,
        "pressure_log": {"file": str(log[0].resolve()), "sha256": log[1]},
    }


@dataclass(frozen=True)
class Provenance:
    """What a calibration run used, recorded in ``calibration.json``."""

    method_config: dict[str, Any] | None = None  # Method.describe() (None: not recorded)
    inputs: dict[str, Any] | None = None  # input_digests() (None: not recorded)
    argv: list[str] | None = None  # the command line's arguments (None: not run from the CLI)
    device_id: str | None = None  # the calibrated display's identifier (1-100 printable chars)
    #: the note on a rig.json beside the manifest that --rig or --mm-per-px set aside
    #: (:func:`~contactcal.infer.pipeline.rig_note.rig_note`); None: none
    rig_note: str | None = None
    #: a video or camera run's recording (:func:`recording_digests`), recorded in
    #: ``inputs.recording``; None: a manifest's frames
    recording: dict[str, Any] | None = None
    #: ``--overlay``: the methods that only draw the overlays' outlines, by name, each its
    #: ``Method.describe()`` (the U-Net's model file and sha256 of the content loaded),
    #: recorded in ``extra.overlay_methods``; None: no overlays
    overlay_methods: dict[str, dict[str, Any]] | None = None
    #: a video or camera run's preview (``--preview``, ``--show``, ``--camera``): the
    #: ``Method.describe()`` of the U-Net drawing its outline (its model file and sha256 of the
    #: content loaded, whatever ``--method``), recorded in ``extra.preview_method``; None: none
    preview_method: dict[str, Any] | None = None

    def __post_init__(self) -> None:
        check_device_id(self.device_id)


def identical_frames(
    inputs: dict[str, Any], pressures_kpa: Sequence[float]
) -> list[dict[str, Any]]:
    """Groups of byte-identical frames (same sha256) listed at different pressures.

    A camera never gives two byte-identical frames of a live scene (sensor noise): the same
    content at different pressures means a frozen camera or duplicated files, and the areas
    measured there cannot show how the contact changes with pressure. Pressures at most
    :data:`~contactcal.infer.calibration.hysteresis.MATCH_TOLERANCE_KPA` apart count as one set
    point (a video's static frames of one set point, logged a few 0.01 kPa apart on the loading
    and the unloading pass, may decode identically).

    Args:
        inputs: :func:`input_digests`'s result, its frames in the order of ``pressures_kpa``.
        pressures_kpa: each frame's pressure, kPa.

    Returns:
        ``[{"sha256", "files", "pressures_kpa"}, ...]``, one per content seen at set points
        more than that tolerance apart, in order of first appearance (empty when there is none).
    """
    groups: dict[str, list[tuple[str, float]]] = {}
    for entry, p in zip(inputs["frames"], pressures_kpa, strict=True):
        groups.setdefault(entry["sha256"], []).append((entry["file"], float(p)))
    return [
        {"sha256": h, "files": [f for f, _ in g], "pressures_kpa": [p for _, p in g]}
        for h, g in groups.items()
        if max(p for _, p in g) - min(p for _, p in g) > MATCH_TOLERANCE_KPA
    ]


def identical_frames_warning(groups: list[dict[str, Any]]) -> str:
    """The printed warning for :func:`identical_frames`'s groups (at least one)."""
    shown = few(
        [
            f"{len(g['files'])} frames ({g['files'][0]} … {g['files'][-1]}) at "
            f"{', '.join(f'{p:g}' for p in sorted(set(g['pressures_kpa'])))} kPa"
            for g in groups
        ],
        sep="; ",
    )
    return (
        f"warning: byte-identical frames at different pressures: {shown} (the record's "
        "extra.identical_frames): a frozen camera or duplicated files? Their areas cannot show "
        "a change with pressure; check the frames and recalibrate"
    )

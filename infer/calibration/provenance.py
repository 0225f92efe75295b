"""What a calibration run used: method configuration, input digests, command line, display
identifier and package versions (recorded in ``calibration.json``)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.files.digest import sha256_file

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
    manifest: Path, files: Sequence[Path], recorded: Path | None = None
) -> dict[str, Any]:
    """sha256 of the manifest and of each frame (frame names relative to the manifest's folder).

    ``recorded`` is the manifest's path in the record (None: ``manifest`` itself).

    Raises:
        OSError: an unreadable file.
    """
    return {
        "manifest": {
            "file": str((recorded or manifest).resolve()),
            "sha256": sha256_file(manifest),
        },
        "frames": [
            {"file": os.path.relpath(f, manifest.parent), "sha256": sha256_file(f)} for f in files
        ],
    }


@dataclass(frozen=True)
class Provenance:
    """What a calibration run used, recorded in ``calibration.json``."""

    method_config: dict[str, Any] | None = None  # Method.describe() (None: not recorded)
    inputs: dict[str, Any] | None = None  # input_digests() (None: not recorded)
    argv: list[str] | None = None  # the command line's arguments (None: not run from the CLI)
    device_id: str | None = None  # the calibrated display's identifier (1-100 printable chars)

    def __post_init__(self) -> None:
        check_device_id(self.device_id)

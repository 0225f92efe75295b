"""Which frames an evaluation read, by content: so that one session is pooled only once.

``contactcal evaluate`` records the sha256 of its manifest, of the session's reference frame and
of every labelled frame (``inputs`` in ``evaluation.json``). ``contactcal boundary-offset`` pools
sessions as independent values; two evaluations that read the same frame (byte-identical: a
copied evaluation folder, ``evaluate`` run twice on one session, or one session's labels split
over two runs that share its reference) are one session, and are refused with both files named.

The manifest's digest is recorded but does not identify a session: sessions of one protocol
have byte-identical manifests (the same file names and pressures in their own folders; e.g. the
five sessions of ``contactcal procedural`` in ``docs/evaluate.md``). Frames differ between
sessions (a camera's noise alone makes every capture unique), so the frames decide.

A session whose frames were re-encoded (the same captures saved once as JPEG and once as PNG)
shares no byte-identical frame with its first encoding, but it shares its labels: the same masks
(matched by stem) or ellipses give the same pixel count at the same pressure. Two evaluations with
:data:`SHARED_LABELS` or more contact labels of equal area at equal pressures, and at least
:data:`SHARED_FRACTION` of the smaller one's, are one session (or one session's labels given to
another), and are refused with both files named. Two sessions of one display whose contact fills
the ring at the top pressures may share a few such labels (the ring's interior), not most.

An ``evaluation.json`` without ``inputs`` (written by an older ``evaluate``) cannot be checked,
and is refused with a line saying to run ``evaluate`` on that session again (seconds), rather
than pooled unchecked.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from contactcal.infer.calibration.provenance import input_digests as frame_digests

if TYPE_CHECKING:
    from contactcal.infer.pipeline.manifest import Session
    from contactcal.infer.pipeline.measure import Measured

_HEX64 = re.compile(r"[0-9a-f]{64}")
#: Contact labels (pressure, label area in px) two evaluations must share to be one session's:
#: one equal pixel count at one pressure can happen by chance (areas of ~10⁴ px), three cannot.
SHARED_LABELS = 3
#: Fraction of the smaller evaluation's contact labels two must share as well: a re-encoded
#: session shares all of them; distinct sessions only by chance or where both fill the ring.
SHARED_FRACTION = 0.5


def input_digests(manifest: Path, session: Session, measured: Sequence[Measured]) -> dict[str, Any]:
    """The ``inputs`` of ``evaluation.json``: sha256 of the manifest, reference and labelled
    frames, each of the content parsed or measured (not of the files read again).

    The digests are ``calibration.json``'s
    (:func:`~contactcal.infer.calibration.provenance.input_digests`), the reference frame apart.

    Args:
        manifest: the session manifest (its path is recorded resolved).
        session: the manifest as read (its content's sha256, the folder frames are named
            relative to).
        measured: one method's measurements of the labelled frames, in the order scored,
            against the session's reference frame (at least one frame), with their digests;
            every method measures the same contents, each file read once.

    Returns:
        ``{"manifest": {"file", "sha256"}, "reference": {"file", "sha256"}, "frames": [{"file",
        "sha256"}, ...]}``; frame names are relative to the manifest's folder.
    """
    entries = [(measured[0].reference, measured[0].reference_sha256)]
    entries += [(m.file, m.sha256) for m in measured]
    digests = frame_digests(manifest, session, entries)
    reference, *frames = digests["frames"]
    return {"manifest": digests["manifest"], "reference": reference, "frames": frames}


def _entry_ok(value: object) -> bool:
    return (
        isinstance(value, dict)
        and isinstance(value.get("file"), str)
        and isinstance(value.get("sha256"), str)
        and _HEX64.fullmatch(value["sha256"]) is not None
    )


def read_frame_digests(file: str, record: dict[str, Any]) -> dict[str, str]:
    """The frames an evaluation read: sha256 → frame name (reference first).

    Args:
        file: the ``evaluation.json`` (for messages).
        record: its content.

    Raises:
        ValueError: no ``inputs`` (an older ``evaluate``), or malformed ones (naming ``file``).
    """
    inputs = record.get("inputs")
    if inputs is None:
        raise ValueError(
            f"{file}: records no digests of the frames it read (written by an older "
            "`contactcal evaluate`), so whether it repeats another session cannot be checked; "
            "run `contactcal evaluate` (this version) on its session again"
        )
    frames = inputs.get("frames") if isinstance(inputs, dict) else None
    ref = inputs.get("reference") if isinstance(inputs, dict) else None
    if not (_entry_ok(ref) and isinstance(frames, list) and all(map(_entry_ok, frames))):
        raise ValueError(
            f"{file}: its inputs are malformed; expected the reference and frames, each with "
            "its file and sha256 (64 hex digits), as `contactcal evaluate` writes them"
        )
    out: dict[str, str] = {}
    for e in [ref, *frames]:
        out.setdefault(e["sha256"], e["file"])
    return out


def check_distinct_sessions(runs: Sequence[dict[str, Any]]) -> None:
    """Refuse two evaluations that read a byte-identical frame: they are of one session.

    Args:
        runs: each with ``file`` (its ``evaluation.json``) and ``digests``
            (:func:`read_frame_digests`).

    Raises:
        ValueError: naming both files and the shared frame.
    """
    seen: dict[str, tuple[str, str]] = {}  # sha256 → (evaluation file, frame name)
    for run in runs:
        for sha, name in run["digests"].items():
            if sha not in seen:
                seen[sha] = (run["file"], name)
                continue
            first, first_name = seen[sha]
            also = "" if name == first_name else f" (named {name} in the second)"
            raise ValueError(
                f"{first} and {run['file']}: both read the frame {first_name}{also}, sha256 "
                f"{sha[:12]}…: evaluations of one session, which counts once; pool one "
                "evaluation per session"
            )


def read_label_areas(file: str, record: dict[str, Any]) -> set[tuple[float, int]]:
    """The contact labels an evaluation scored: ``(pressure kPa, label area px)`` of each frame
    labelled in contact (``frames`` of ``evaluation.json``).

    Raises:
        ValueError: no or malformed ``frames`` (naming ``file``).
    """
    frames = record.get("frames")
    ok = isinstance(frames, list) and all(
        isinstance(f, dict)
        and isinstance(f.get("pressure_kpa"), int | float)
        and not isinstance(f.get("label_area_px"), bool)
        and isinstance(f.get("label_area_px"), int)
        for f in frames
    )
    if not ok:
        raise ValueError(
            f"{file}: its frames are malformed; expected each frame's pressure_kpa and "
            "label_area_px, as `contactcal evaluate` writes them"
        )
    return {(float(f["pressure_kpa"]), f["label_area_px"]) for f in frames if f["label_area_px"]}


def check_distinct_labels(runs: Sequence[dict[str, Any]]) -> None:
    """Refuse two evaluations sharing :data:`SHARED_LABELS` or more contact labels (equal area at
    equal pressure), and :data:`SHARED_FRACTION` of the smaller one's: one session's frames in
    two encodings, or its labels given to another.

    Args:
        runs: each with ``file`` (its ``evaluation.json``) and ``labels``
            (:func:`read_label_areas`).

    Raises:
        ValueError: naming both files and one shared label.
    """
    for i, first in enumerate(runs):
        for second in runs[i + 1 :]:
            shared = sorted(first["labels"] & second["labels"])
            fewest = min(len(first["labels"]), len(second["labels"]))
            if len(shared) >= max(SHARED_LABELS, SHARED_FRACTION * fewest):
                kpa, area = shared[0]
                raise ValueError(
                    f"{first['file']} and {second['file']}: {len(shared)} frames labelled with "
                    f"the same areas at the same pressures (e.g. {area} px at {kpa:g} kPa): one "
                    "session evaluated twice (its frames in another encoding, e.g. JPEG and PNG, "
                    "or another copy), or one session's labels given to another; it counts "
                    "once: pool one evaluation per session"
                )

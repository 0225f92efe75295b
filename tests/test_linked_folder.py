"""A record names each frame as the manifest lists it, whatever the spelling of the manifest's
folder: reached through a symbolic link, ``calibration.json`` and ``evaluation.json`` say
``p04.0kpa.jpg``, not ``../real/p04.0kpa.jpg`` (frame paths are joined to the manifest's
resolved folder, so their names are made relative to it); a frame that is itself a link is
named as listed too, not as its target, with the digest of the content read through it."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from test_input_digests import NAMES
from test_outputs import EXAMPLE, copy_session
from test_video import make_log, make_video

from contactcal.infer.calibration import calibrate
from contactcal.infer.cli import main
from contactcal.infer.pipeline import manifest


def _linked(tmp_path: Path, real: Path) -> Path:
    """A symbolic link ``tmp_path/link`` to the folder ``real`` (skips where links cannot be
    made, e.g. Windows without the privilege)."""
    link = tmp_path / "link"
    try:
        os.symlink(real, link, target_is_directory=True)
    except (OSError, NotImplementedError) as e:
        pytest.skip(f"no symbolic links here: {e}")
    return link


def _names(entries: list[dict[str, object]]) -> list[object]:
    return [e["file"] for e in entries]


def _calibrated_as_listed(folder: Path, out: Path) -> None:
    """Calibrate ``folder``'s session into ``out``; its record names every frame as listed."""
    argv = ["calibrate", str(folder / "manifest.csv"), "--method", "classical"]
    assert main([*argv, "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    assert _names(record["inputs"]["frames"]) == list(NAMES)
    assert _names(record["points"]) == list(NAMES)
    assert record["extra"]["reference_frame"] == NAMES[0]


def test_calibrate_through_a_linked_folder_names_the_frames_as_listed(tmp_path: Path) -> None:
    link = _linked(tmp_path, copy_session(tmp_path, NAMES))
    _calibrated_as_listed(link, tmp_path / "out")


def test_evaluate_through_a_linked_folder_names_the_frames_as_listed(tmp_path: Path) -> None:
    s = copy_session(tmp_path, NAMES)
    (s / "masks").mkdir()
    for name in NAMES[1:]:
        stem = Path(name).stem
        shutil.copy(EXAMPLE / "masks" / f"{stem}.png", s / "masks" / f"{stem}.png")
    link = _linked(tmp_path, s)
    out = tmp_path / "out"
    argv = ["evaluate", str(link / "manifest.csv"), "--labels", str(link / "masks")]
    assert main([*argv, "--method", "classical", "--out", str(out)]) == 0
    record = json.loads((out / "evaluation.json").read_text(encoding="utf-8"))
    assert record["inputs"]["reference"]["file"] == NAMES[0]
    assert _names(record["inputs"]["frames"]) == list(NAMES[1:])
    assert _names(record["frames"]) == list(NAMES[1:])


def test_calibrate_video_under_a_linked_folder_names_its_frames_as_listed(
    tmp_path: Path,
) -> None:
    """``--out`` in a real folder reached through a link (outputs refuse only a link as the
    folder receiving them): the record names the extracted frames as its manifest does."""
    kpas = [0, 2, 4, 6, 8, 10]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, np.random.default_rng(0))
    (tmp_path / "real" / "runs").mkdir(parents=True)
    out = _linked(tmp_path, tmp_path / "real") / "runs" / "out"
    argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
    argv += [str(tmp_path / "log.csv"), "--settle-s", "0.3", "--method", "classical"]
    assert main([*argv, "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    rows = (out / "frames" / "manifest.csv").read_text(encoding="utf-8").splitlines()[1:]
    listed = [row.split(",")[0] for row in rows]
    assert sorted(_names(record["inputs"]["frames"])) == sorted(listed)
    assert sorted(_names(record["points"])) == sorted(listed)
    assert record["extra"]["reference_frame"] in listed


def _frame_linked_elsewhere(tmp_path: Path, session: Path, name: str) -> Path:
    """Move the frame ``name`` of ``session`` to ``tmp_path/elsewhere/take7.jpg`` and put a
    symbolic link to it in its place; the target's path."""
    target = tmp_path / "elsewhere" / "take7.jpg"
    target.parent.mkdir()
    shutil.move(session / name, target)
    try:
        os.symlink(target, session / name)
    except (OSError, NotImplementedError) as e:
        pytest.skip(f"no symbolic links here: {e}")
    return target


def test_calibrate_names_a_frame_that_is_a_link_as_listed(tmp_path: Path) -> None:
    s = copy_session(tmp_path, NAMES)
    target = _frame_linked_elsewhere(tmp_path, s, NAMES[1])
    out = tmp_path / "out"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical"]
    assert main([*argv, "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    assert _names(record["inputs"]["frames"]) == list(NAMES)  # not ../elsewhere/take7.jpg
    assert _names(record["points"]) == list(NAMES)
    digest = hashlib.sha256(target.read_bytes()).hexdigest()  # the content read through it
    assert record["inputs"]["frames"][1]["sha256"] == digest


def test_evaluate_matches_a_mask_to_a_frame_that_is_a_link_by_its_listed_name(
    tmp_path: Path,
) -> None:
    """The mask ``p04.0kpa.png`` labels the frame listed as ``p04.0kpa.jpg`` (a link to
    ``take7.jpg``): masks go by the listed frame's stem, not its target's."""
    s = copy_session(tmp_path, NAMES)
    (s / "masks").mkdir()
    for name in NAMES[1:]:
        stem = Path(name).stem
        shutil.copy(EXAMPLE / "masks" / f"{stem}.png", s / "masks" / f"{stem}.png")
    _frame_linked_elsewhere(tmp_path, s, NAMES[1])
    out = tmp_path / "out"
    argv = ["evaluate", str(s / "manifest.csv"), "--labels", str(s / "masks")]
    assert main([*argv, "--method", "classical", "--out", str(out)]) == 0
    record = json.loads((out / "evaluation.json").read_text(encoding="utf-8"))
    assert _names(record["inputs"]["frames"]) == list(NAMES[1:])
    assert _names(record["frames"]) == list(NAMES[1:])


def test_frames_are_named_against_the_folder_they_were_read_from(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The manifest's folder is resolved once per read (``Session.folder``) and the records
    name the frames against that very folder: a linked folder pointed elsewhere while the run
    measures (a copy of the session) changes no name (resolved again per frame, each name
    would have become ``../real/p04.0kpa.jpg``)."""
    real = copy_session(tmp_path, NAMES)
    link = _linked(tmp_path, real)
    copy = shutil.copytree(real, tmp_path / "copy")
    read_session = manifest.read_session

    def read_then_repoint(*args: Any) -> manifest.Session:
        session = read_session(*args)
        link.unlink()
        os.symlink(copy, link, target_is_directory=True)
        return session

    monkeypatch.setattr(manifest, "read_session", read_then_repoint)  # the command's read
    monkeypatch.setattr(calibrate, "read_session", read_then_repoint)  # calibrate_session's
    _calibrated_as_listed(link, tmp_path / "out")

"""A record names each frame as the manifest lists it, whatever the spelling of the manifest's
folder: reached through a symbolic link, ``calibration.json`` and ``evaluation.json`` say
``p04.0kpa.jpg``, not ``../real/p04.0kpa.jpg`` (frame paths are resolved, so their names are
made relative to the manifest's resolved folder)."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from test_input_digests import NAMES
from test_outputs import EXAMPLE, copy_session
from test_video import make_log, make_video

from contactcal.infer.cli import main


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


def test_calibrate_through_a_linked_folder_names_the_frames_as_listed(tmp_path: Path) -> None:
    link = _linked(tmp_path, copy_session(tmp_path, NAMES))
    out = tmp_path / "out"
    argv = ["calibrate", str(link / "manifest.csv"), "--method", "classical"]
    assert main([*argv, "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    assert _names(record["inputs"]["frames"]) == list(NAMES)
    assert _names(record["points"]) == list(NAMES)
    assert record["extra"]["reference_frame"] == NAMES[0]


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

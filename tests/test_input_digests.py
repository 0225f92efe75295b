"""The sha256 digests a record keeps (``calibration.json``, ``evaluation.json`` ``inputs``) are of
the content the run parsed and measured: a file replaced after the run read it is recorded as it
was measured, never as it was read again afterwards."""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from test_outputs import EXAMPLE, copy_session

from contactcal.infer.cli import main
from contactcal.infer.image import read
from contactcal.infer.pipeline import manifest

NAMES = ("p00.0kpa.jpg", "p04.0kpa.jpg", "p08.0kpa.jpg", "p12.0kpa.jpg", "p16.0kpa.jpg")


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _replaced_after_reading(
    monkeypatch: pytest.MonkeyPatch, names: set[str]
) -> dict[str, list[bytes]]:
    """Every read of a frame (``read_file_bytes``) or of the manifest (``read_rows``) named in
    ``names`` replaces that file right after it (other bytes, still a valid file): a digest
    taken by reading it again differs from the one of the content read. Returns each file's
    content as each read got it."""
    got: dict[str, list[bytes]] = {}

    def replacing(original: Callable[..., Any]) -> Callable[..., Any]:
        def wrapped(path: Path, *args: Any) -> Any:
            p = Path(path)
            before = p.read_bytes()
            out = original(path, *args)
            if p.name in names:
                got.setdefault(p.name, []).append(before)
                p.write_bytes(before + b"\n")  # after a JPEG's end marker, or a blank CSV line
            return out

        return wrapped

    monkeypatch.setattr(read, "read_file_bytes", replacing(read.read_file_bytes))
    monkeypatch.setattr(manifest, "read_rows", replacing(manifest.read_rows))
    return got


@pytest.mark.parametrize("method", ["unet", "classical"])
def test_calibration_records_the_digests_of_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, method: str
) -> None:
    s = copy_session(tmp_path, NAMES)
    got = _replaced_after_reading(monkeypatch, {*NAMES, "manifest.csv"})
    out = tmp_path / "out"
    assert main(["calibrate", str(s / "manifest.csv"), "--method", method, "--out", str(out)]) == 0
    inputs = json.loads((out / "calibration.json").read_text(encoding="utf-8"))["inputs"]
    # each file read once (the reference too: its decode for the method is the one measured)
    assert {name: len(reads) for name, reads in got.items()} == dict.fromkeys(got, 1)
    assert inputs["manifest"]["sha256"] == _sha(got["manifest.csv"][0])
    assert {e["file"]: e["sha256"] for e in inputs["frames"]} == {
        name: _sha(got[name][0]) for name in NAMES
    }


def _labelled_session(tmp_path: Path) -> tuple[Path, Path]:
    """A copy of some example frames and their label masks: (manifest, masks folder)."""
    s = copy_session(tmp_path, NAMES)
    (s / "masks").mkdir()
    for name in NAMES:
        stem = Path(name).stem
        shutil.copy(EXAMPLE / "masks" / f"{stem}.png", s / "masks" / f"{stem}.png")
    return s / "manifest.csv", s / "masks"


def test_evaluation_records_the_digests_of_the_content_measured(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    manifest_csv, masks = _labelled_session(tmp_path)
    labelled = set(NAMES[1:])  # the reference is read for the labels' check too
    got = _replaced_after_reading(monkeypatch, {*labelled, "manifest.csv"})
    out = tmp_path / "out"
    assert main(["evaluate", str(manifest_csv), "--labels", str(masks), "--out", str(out)]) == 0
    inputs = json.loads((out / "evaluation.json").read_text(encoding="utf-8"))["inputs"]
    assert inputs["manifest"]["sha256"] == _sha(got["manifest.csv"][0])
    recorded = {e["file"]: e["sha256"] for e in inputs["frames"]}
    assert {name: recorded[name] for name in labelled} == {n: _sha(got[n][0]) for n in labelled}


def test_evaluation_refuses_a_frame_that_changed_between_its_methods(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    manifest_csv, masks = _labelled_session(tmp_path)
    _replaced_after_reading(monkeypatch, {NAMES[2]})
    out = tmp_path / "out"
    argv = ["evaluate", str(manifest_csv), "--labels", str(masks), "--method", "both"]
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and NAMES[2] in err and "changed while the run read it" in err
    assert not out.exists()  # nothing written

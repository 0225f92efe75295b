"""An output folder option that cannot receive the run's outputs (``--out`` or ``--overlay`` a
file, an output in it that is a link or a folder) is refused before any frame is read, naming
the option, not after every frame was measured."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from contactcal.infer.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
MANIFEST = str(EXAMPLE / "manifest.csv")
FRAME = str(EXAMPLE / "p10.0kpa.jpg")


@pytest.fixture
def no_frame_read(monkeypatch: pytest.MonkeyPatch) -> None:
    """Reading a frame fails the test: the refusal must come first."""
    from contactcal.infer.image import read as image_read

    def read(*args: object, **kwargs: object) -> None:
        raise AssertionError("a frame was read before the output folder was checked")

    monkeypatch.setattr(image_read.ImageFile, "read", read)


def _cases(tmp: Path) -> list[tuple[list[str], str]]:
    """(argv, the start of its error) for each refused output folder."""
    afile = tmp / "afile"
    linked = tmp / "linked"
    (linked / "unet").mkdir(parents=True)
    os.symlink(afile, linked / "calibration.json")
    (linked / "unet" / "curve.png").mkdir()
    overlays = tmp / "overlays"  # an overlay's name taken by a folder: known before measuring
    (overlays / "p10.0kpa_overlay.png").mkdir(parents=True)
    evaluated = tmp / "evaluated"
    evaluated.mkdir()
    os.symlink(afile, evaluated / "evaluation.json")
    return [
        (["calibrate", MANIFEST, "--out", str(afile)], f"--out {afile}: is not a folder"),
        (["calibrate", MANIFEST, "--out", str(linked)], "is a symbolic link"),
        (
            ["calibrate", MANIFEST, "--out", str(tmp / "c"), "--overlay", str(afile)],
            f"--overlay {afile}: is not a folder",
        ),
        (
            ["measure", "--out", str(tmp / "r.json"), "--overlay", str(afile), FRAME],
            f"--overlay {afile}: is not a folder",
        ),
        (["demo", "--out", str(afile)], f"--out {afile}: is not a folder"),
        (["demo", "--out", str(linked)], "is not a regular file"),
        (
            ["calibrate", MANIFEST, "--out", str(tmp / "c"), "--overlay", str(overlays)],
            f"--overlay {overlays}: {overlays / 'p10.0kpa_overlay.png'}: exists and is not",
        ),
        (
            ["measure", "--out", str(tmp / "r.json"), "--overlay", str(overlays), FRAME],
            f"--overlay {overlays}: {overlays / 'p10.0kpa_overlay.png'}: exists and is not",
        ),
        (
            ["evaluate", MANIFEST, "--labels", str(EXAMPLE / "masks"), "--out", str(evaluated)],
            f"--out {evaluated}: {evaluated / 'evaluation.json'}: is a symbolic link",
        ),
    ]


@pytest.mark.parametrize("case", range(9))
def test_output_folder_refused_before_the_work(
    case: int, tmp_path: Path, capsys: pytest.CaptureFixture[str], no_frame_read: None
) -> None:
    (tmp_path / "afile").write_text("kept")
    argv, expected = _cases(tmp_path)[case]
    assert main(argv) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    option = "--overlay" if "--overlay" in argv else "--out"
    assert err.startswith(f"contactcal: error: {option} ") and expected in err, err
    assert (tmp_path / "afile").read_text() == "kept"
    assert not (tmp_path / "c").exists() and not (tmp_path / "r.json").exists()

"""What ``calibrate``, ``demo`` and ``measure`` do with an ``--out`` that already holds a run's
files: another display's calibration and an earlier recording's frames are refused before any
work; a re-calibration of the same display replaces its record, and ``measure`` its results
file, with a note."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from test_outputs import EXAMPLE, copy_session, one_line_naming

from contactcal.infer.cli import main


def _calibrate(manifest: Path, out: Path, *more: str) -> list[str]:
    return ["calibrate", str(manifest), "--method", "classical", "--out", str(out), *more]


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def _not_measured(*args: object, **kwargs: object) -> None:
    raise AssertionError("measured before the --out was checked")


@pytest.mark.parametrize("device", [["--device-id", "display-08"], []])
def test_another_displays_calibration_is_refused_not_replaced(
    device: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """A typo in --out replaced display-07's calibration, said only afterwards in a note."""
    from contactcal.infer.calibration import calibrate

    s = copy_session(tmp_path)
    out = tmp_path / "cal" / "display-07-stills"
    assert main(_calibrate(s / "manifest.csv", out, "--device-id", "display-07")) == 0
    capsys.readouterr()
    before = _snapshot(out)

    monkeypatch.setattr(calibrate, "calibrate_session", _not_measured)
    assert main(_calibrate(s / "manifest.csv", out, *device)) == 2
    printed = capsys.readouterr()
    one_line_naming(printed.err, out / "calibration.json")
    assert "device id 'display-07'" in printed.err and "another --out" in printed.err
    assert "remove it first" in printed.err and printed.out == ""
    assert _snapshot(out) == before


def test_demo_refuses_a_displays_calibration_in_its_folders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """demo (no --device-id) replaced display-07's record in DIR/classical with a note."""
    from contactcal.infer.pipeline import demo

    s = copy_session(tmp_path)
    out = tmp_path / "cal"
    assert main(_calibrate(s / "manifest.csv", out / "classical", "--device-id", "display-07")) == 0
    capsys.readouterr()
    before = _snapshot(out)

    monkeypatch.setattr(demo, "run_demo", _not_measured)
    assert main(["demo", "--out", str(out)]) == 2
    printed = capsys.readouterr()
    one_line_naming(printed.err, out / "classical" / "calibration.json")
    assert "device id 'display-07'" in printed.err and "another --out" in printed.err
    assert "--device-id" not in printed.err  # demo has no such option
    assert "this run records no device id" in printed.err
    assert printed.out == "" and _snapshot(out) == before


def test_the_same_display_or_none_is_replaced_with_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    s = copy_session(tmp_path)
    for device in (["--device-id", "display-07"], []):
        out = tmp_path / f"c{len(device)}"
        assert main(_calibrate(s / "manifest.csv", out, *device)) == 0
        first = json.loads((out / "calibration.json").read_text())
        capsys.readouterr()
        assert main(_calibrate(s / "manifest.csv", out, *device)) == 0
        assert f"note: replaced the calibration that {out} held" in capsys.readouterr().out
        assert json.loads((out / "calibration.json").read_text())["created"] >= first["created"]
    # a record without a device id is replaced by an identified run, with the note
    assert main(_calibrate(s / "manifest.csv", tmp_path / "c0", "--device-id", "display-07")) == 0
    assert "no device id" in capsys.readouterr().out


#: calibration.json contents that are no record, and what the refusal says was found there.
NO_RECORD = {
    "damaged": (
        b'{"device_id": "display-07", "crea',
        "not valid JSON (Unterminated string starting at: line 1 column 29)",
    ),
    "not UTF-8": (b"\xff\xfe", "not valid JSON (not UTF-8 text)"),
    "not an object": (b'["display-07"]', "not a contactcal calibration record"),
    "no format": (
        b'{"created": "2024-05-01T10:00:00+00:00", "device_id": "display-07"}',
        "not a contactcal calibration record",
    ),
}


@pytest.mark.parametrize("command", ["calibrate", "demo"])
@pytest.mark.parametrize("held", NO_RECORD)
def test_a_calibration_json_that_is_no_record_is_refused_not_replaced(
    held: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """Such a file was replaced with a note ("unreadable as a record"): the device check could
    not run on it, so a typo in --out lost another display's record, damaged or hand-edited.
    (A folder, device or pipe there is refused before, as an output that cannot be written.)"""
    from contactcal.infer.calibration import calibrate
    from contactcal.infer.pipeline import demo

    s = copy_session(tmp_path)
    out = tmp_path / "cal"
    folder = out / "classical" if command == "demo" else out
    folder.mkdir(parents=True)
    content, found = NO_RECORD[held]
    path = folder / "calibration.json"
    path.write_bytes(content)
    before = _snapshot(out)
    monkeypatch.setattr(calibrate, "calibrate_session", _not_measured)
    monkeypatch.setattr(demo, "run_demo", _not_measured)
    another = _calibrate(s / "manifest.csv", out, "--device-id", "display-08")
    assert main(["demo", "--out", str(out)] if command == "demo" else another) == 2
    printed = capsys.readouterr()
    one_line_naming(printed.err, path)
    assert f"{path}: {found}" in printed.err and printed.out == ""
    assert printed.err.rstrip().endswith("move it away or give another --out")
    assert _snapshot(out) == before


def test_a_record_of_an_earlier_format_version_is_replaced_with_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Only what is no record is refused: a version 1 record (no "created", no device id), which
    load_curve reads, is a re-calibration's to replace."""
    from contactcal.infer.calibration.load import load_curve

    s = copy_session(tmp_path)
    out = tmp_path / "cal"
    out.mkdir()
    fit = {"pressure_kpa": [0.0, 5.0, 10.0], "area": [0.0, 40.0, 80.0]}
    v1 = {"format": "contactcal.calibration", "format_version": 1, "fit": fit, "onset_kpa": 1.0}
    (out / "calibration.json").write_text(json.dumps({**v1, "area_unit": "px", "inverse": None}))
    assert load_curve(out / "calibration.json").onset_kpa == 1.0
    assert main(_calibrate(s / "manifest.csv", out, "--device-id", "display-07")) == 0
    note = f"note: replaced the calibration that {out} held (no creation time, no device id)"
    assert note in capsys.readouterr().out
    assert json.loads((out / "calibration.json").read_text())["device_id"] == "display-07"


@pytest.mark.parametrize("held", ["unreadable", "a folder"])
def test_a_calibration_json_that_cannot_be_read_is_refused_naming_it(
    held: str, tmp_path: Path, monkeypatch
) -> None:
    """A permission error (root reads any file: raised here), or a folder put there after the
    output check, is refused like any non-record (it was held as "unreadable as a record")."""
    from contactcal.infer.calibration import out_folder
    from contactcal.infer.files import regular

    def denied(path: Path, *args: object) -> bytes:
        raise PermissionError(13, "Permission denied", str(path))

    path = tmp_path / "calibration.json"
    if held == "a folder":
        path.mkdir()
        found = "is a folder"
    else:
        path.write_text("{}")
        monkeypatch.setattr(regular, "read_input_json", denied)
        found = "cannot be read (Permission denied)"
    want = re.escape(f"{path}: {found}; expected a calibration record")
    with pytest.raises(ValueError, match=f"^{want}.*move it away or give another --out$"):
        out_folder.held_record(tmp_path)


HELD = [("frames/p.jpg",), ("preview.mp4",), ("frames/p.jpg", "preview.avi")]


@pytest.mark.parametrize("held", HELD)
def test_a_manifest_run_into_a_recordings_folder_is_refused(
    held: tuple[str, ...], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its frames/ and preview stayed beside a calibration of other frames."""
    s = copy_session(tmp_path)
    out = tmp_path / "cal" / "display-07"
    for name in held:
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_bytes(b"x")
    before = _snapshot(out)
    assert main(_calibrate(s / "manifest.csv", out)) == 2
    err = capsys.readouterr().err
    one_line_naming(err, out)
    assert "earlier calibrate --video/--camera run" in err and "another --out" in err
    assert ("frames/" in err) is held[0].startswith("frames/")
    assert ("preview." in err) is (held != ("frames/p.jpg",))
    assert _snapshot(out) == before and not (out / "calibration.json").exists()


def test_a_recording_calibrated_again_in_its_own_folder_is_not_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its frames/manifest.csv again (as the docs suggest): the calibration is of those frames."""
    s = copy_session(tmp_path)
    out = tmp_path / "cal"
    shutil.copytree(s, out / "frames")
    (out / "preview.mp4").write_bytes(b"x")
    assert main(_calibrate(out / "frames" / "manifest.csv", out)) == 0, capsys.readouterr().err
    assert (out / "calibration.json").is_file() and (out / "preview.mp4").is_file()


def test_measure_says_which_results_file_it_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An existing results file was overwritten without a word (calibrate, evaluate say so)."""
    frame = str(EXAMPLE / "p12.0kpa.jpg")
    out = tmp_path / "results.json"
    argv = ["measure", "--method", "classical", frame]
    assert main([*argv, "--out", str(out)]) == 0
    assert "replaced" not in capsys.readouterr().out
    assert main([*argv, frame, "--out", str(out)]) == 0
    printed = capsys.readouterr()
    note = f"note: replaced {out} (1 result(s)); give each run its own --out to keep both"
    assert printed.out.splitlines()[-1] == note and "replaced" not in printed.err
    assert len(json.loads(out.read_text())) == 2
    assert main([*argv, "--out", "-"]) == 0  # standard output replaces no file
    printed = capsys.readouterr()
    assert "replaced" not in printed.out + printed.err

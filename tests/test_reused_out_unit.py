"""A run without a pixel scale into an ``--out`` holding a calibration in mm² is refused before
any work: it replaced the record a controller loads as mm² with one in px, said only in notes
(a re-calibration of a recording's ``frames/``, which hold no rig.json, without the ``--rig``
the recording's run had). A run with a scale, or into a record in px, replaces it with a note."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from test_outputs import copy_session, one_line_naming
from test_reused_out import _calibrate, _snapshot

from contactcal.infer.cli import main

MM2 = "mm²"


def _session(tmp_path: Path) -> tuple[Path, Path]:
    """Example frames with their manifest and no rig.json beside them, and a rig.json apart
    (as a recording's ``frames/`` and the rig's config)."""
    s = copy_session(tmp_path)
    rig = tmp_path / "rig dir" / "rig.json"  # a space: quoted as a shell would need it
    rig.parent.mkdir()
    shutil.move(s / "rig.json", rig)
    return s / "manifest.csv", rig


def _held(manifest: Path, out: Path, *scale: str) -> None:
    """Calibrate ``manifest`` into ``out`` for display-07 with ``scale``."""
    assert main(_calibrate(manifest, out, "--device-id", "display-07", *scale)) == 0


def _unit(out: Path) -> str:
    return json.loads((out / "calibration.json").read_text(encoding="utf-8"))["area_unit"]


@pytest.mark.parametrize("earlier", ["--rig", "--mm-per-px=0.05", "beside"])
def test_a_record_in_mm2_is_not_replaced_by_a_run_without_a_scale(
    earlier: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The run's one line names the record and the scale options its command line gave."""
    manifest, rig = _session(tmp_path)
    out = tmp_path / "cal"
    if earlier == "beside":  # the scale came from a rig.json beside the manifest: no option
        shutil.copy(rig, manifest.parent / "rig.json")
        _held(manifest, out)
        (manifest.parent / "rig.json").unlink()
    else:
        _held(manifest, out, *(["--rig", str(rig)] if earlier == "--rig" else [earlier]))
    assert _unit(out) == MM2
    capsys.readouterr()
    before = _snapshot(tmp_path)
    monkeypatch.setattr(  # after its checks, a frame read fails the test
        "contactcal.infer.image.read.ImageFile.read",
        lambda *a, **k: pytest.fail("a frame was read before the --out was checked"),
    )
    assert main(_calibrate(manifest, out, "--device-id", "display-07")) == 2
    printed = capsys.readouterr()
    one_line_naming(printed.err, out / "calibration.json")
    assert f"holds a calibration in {MM2}, and this run has no pixel scale" in printed.err
    assert "give the --rig or --mm-per-px it used" in printed.err
    gave = {"--rig": f"--rig '{rig}'", "--mm-per-px=0.05": "--mm-per-px=0.05", "beside": None}
    said = f"(its command line gave {gave[earlier]})"
    assert (said in printed.err) is (gave[earlier] is not None), printed.err
    assert "remove that record first" in printed.err and printed.out == ""
    assert _snapshot(tmp_path) == before


def test_a_video_run_without_a_scale_is_refused_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Before the video is opened: a video run reads no rig.json, so it needs --rig too."""
    from contactcal.infer.video import command

    manifest, rig = _session(tmp_path)
    out = tmp_path / "cal"
    _held(manifest, out, "--rig", str(rig))
    capsys.readouterr()
    before = _snapshot(tmp_path)
    monkeypatch.setattr(
        command, "calibrate_video", lambda *a, **k: pytest.fail("the video run started")
    )
    video = ["--video", str(tmp_path / "v.mp4"), "--pressure-log", str(tmp_path / "log.csv")]
    argv = ["calibrate", *video, "--device-id", "display-07", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    one_line_naming(err, out / "calibration.json")
    assert "a video or camera run reads no rig.json" in err and f"--rig '{rig}'" in err
    assert _snapshot(tmp_path) == before


@pytest.mark.parametrize(
    ("held", "again", "unit"),
    [
        ("--rig", ["--rig", "RIG"], MM2),  # the same scale
        ("--rig", ["--mm-per-px", "0.05"], MM2),  # another way to give one
        ("px", [], "px"),  # px again
        ("px", ["--rig", "RIG"], MM2),  # a record in px gains its unit
    ],
)
def test_a_run_keeping_or_gaining_mm2_replaces_the_record_with_a_note(
    held: str, again: list[str], unit: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    manifest, rig = _session(tmp_path)
    out = tmp_path / "cal"
    _held(manifest, out, *(["--rig", str(rig)] if held == "--rig" else []))
    capsys.readouterr()
    scale = [str(rig) if a == "RIG" else a for a in again]
    assert main(_calibrate(manifest, out, "--device-id", "display-07", *scale)) == 0
    printed = capsys.readouterr()
    assert f"note: replaced the calibration that {out} held" in printed.out, printed.err
    assert _unit(out) == unit


def test_demo_without_a_rig_json_refuses_a_record_in_mm2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """demo has no --rig: the fix it names is a rig.json beside its manifest."""
    from contactcal.infer.pipeline import demo

    manifest, rig = _session(tmp_path)
    out = tmp_path / "demo"
    assert main(_calibrate(manifest, out / "classical", "--rig", str(rig))) == 0
    capsys.readouterr()
    before = _snapshot(tmp_path)
    monkeypatch.setattr(demo, "run_demo", lambda *a, **k: pytest.fail("the demo ran"))
    assert main(["demo", "--manifest", str(manifest), "--out", str(out)]) == 2
    printed = capsys.readouterr()
    one_line_naming(printed.err, out / "classical" / "calibration.json")
    assert "(no rig.json beside the manifest)" in printed.err
    assert "put the rig.json it used beside the manifest" in printed.err
    assert "--mm-per-px it used" not in printed.err  # demo has no such option
    assert printed.out == "" and _snapshot(tmp_path) == before


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["calibrate", "--rig", "rig dir/rig.json"], "--rig 'rig dir/rig.json'"),
        (["calibrate", "--mm-per-px=0.05"], "--mm-per-px=0.05"),
        (["calibrate", "--mm", "0.05"], "--mm-per-px 0.05"),  # abbreviations in earlier records
        (["calibrate", "--ri=r.json"], "--rig=r.json"),
        (["calibrate", "--method", "classical"], None),  # no scale option
        (["demo", "--m", "m.csv"], None),  # demo's --manifest: demo has no scale options
    ],
)
def test_the_refusal_quotes_the_scale_options_as_the_record_gave_them(
    argv: list[str], said: str | None, tmp_path: Path
) -> None:
    """Spelled out, whichever way the record's command line gave them."""
    from contactcal.infer.calibration.out_folder import HeldRecord, check_same_unit

    path = tmp_path / "calibration.json"
    data = {"area_unit": MM2, "argv": [*argv, "--out", "cal"]}
    with pytest.raises(ValueError, match="holds a calibration in mm²") as err:
        check_same_unit(HeldRecord(path, data), "no --rig", "give the --rig it used")
    gave = f"(its command line gave {said})"
    assert (gave in str(err.value)) is (said is not None), str(err.value)
    assert (said is None) is ("(its command line gave" not in str(err.value))


def test_a_video_run_into_an_earlier_recording_is_told_that_first(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Its record in mm² would be refused too, but giving the --rig the refusal asks for would
    only meet the frames' refusal: no --out holding a recording takes another."""
    from contactcal.infer.video import command

    manifest, rig = _session(tmp_path)
    out = tmp_path / "cal"
    _held(manifest, out, "--rig", str(rig))
    (out / "frames").mkdir()
    shutil.copy(manifest.parent / "p00.0kpa.jpg", out / "frames")
    capsys.readouterr()
    monkeypatch.setattr(
        command, "calibrate_video", lambda *a, **k: pytest.fail("the video run started")
    )
    video = ["--video", str(tmp_path / "v.mp4"), "--pressure-log", str(tmp_path / "log.csv")]
    assert main(["calibrate", *video, "--device-id", "display-07", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    one_line_naming(err, out / "frames")
    assert "holds the frames of an earlier recording" in err and MM2 not in err

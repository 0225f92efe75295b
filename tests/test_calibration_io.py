"""Tests of contactcal.infer.calibration.record (calibration outputs) and .table."""

from __future__ import annotations

import csv
import hashlib
import json
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
from read_counts import count_reads
from test_outputs import copy_session

from contactcal.infer.calibration import out_folder
from contactcal.infer.calibration import record as calibration_io
from contactcal.infer.calibration.fit import CurveConfig
from contactcal.infer.calibration.load import (
    FORMAT,
    NoContactCurveError,
    NoSuchPhaseError,
    load_curve,
)
from contactcal.infer.calibration.out_folder import earlier_record_note, held_record
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.record import write_calibration
from contactcal.infer.calibration.session import SessionFit, fit_session
from contactcal.infer.calibration.table import format_table
from contactcal.infer.cli import main
from contactcal.infer.methods.classical import ClassicalConfig
from contactcal.infer.pipeline import scale

P = np.arange(0.0, 11.0, 2.0)


def _results(mm2: bool = True) -> list[CalibrationPoint]:
    out = []
    for p in P[::-1]:  # any order
        area_px = 0.0 if p < 3 else 500.0 * (p - 3)
        out.append(
            CalibrationPoint(
                file=f"p{p:04.1f}.png",
                pressure_kpa=float(p),
                contact=area_px > 0,
                area_px=area_px,
                area_mm2=(area_px * 0.002 if mm2 else None),
                note="dim" if p == 4 else "",
            )
        )
    return out


def _curve(results: list[CalibrationPoint], unit: str = "mm²") -> SessionFit:
    return fit_session(results, unit, CurveConfig(n_bootstrap=40))


def _no_nan(obj) -> None:
    if isinstance(obj, float):
        assert math.isfinite(obj)
    elif isinstance(obj, dict):
        for v in obj.values():
            _no_nan(v)
    elif isinstance(obj, list):
        for v in obj:
            _no_nan(v)


def test_write_calibration_outputs(tmp_path: Path) -> None:
    results = _results()
    fit = _curve(results)
    curve = fit.curve
    extra = {"mm_per_px": 0.045, "bad": float("nan"), "arr": np.array([1.0, np.inf]), "p": tmp_path}
    paths = write_calibration(tmp_path / "out", results, fit, "classical", extra)
    assert set(paths) == {"json", "csv", "png"}
    assert all(p.is_file() and p.stat().st_size > 0 for p in paths.values())
    assert sorted(x.name for x in (tmp_path / "out").iterdir()) == [
        "calibration.csv",
        "calibration.json",
        "curve.png",
    ]
    text = paths["json"].read_text(encoding="utf-8")
    assert "NaN" not in text and "Infinity" not in text
    data = json.loads(text)
    _no_nan(data)
    assert data["method"] == "classical" and data["area_unit"] == "mm²"
    assert data["onset_kpa"] == pytest.approx(curve.onset_kpa)
    assert [pt["pressure_kpa"] for pt in data["points"]] == sorted(P.tolist())
    assert data["fit"]["area"] == pytest.approx(curve.fit_area.tolist())
    assert data["inverse"]["area"][0] == 0.0 and data["inverse"]["pressure_kpa"][-1] == 10.0
    assert data["extra"]["bad"] is None and data["extra"]["arr"] == [1.0, None]
    assert data["versions"]["numpy"] == np.__version__
    assert "created" in data
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    with open(paths["csv"], newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == list(calibration_io.CSV_COLUMNS)
    assert [float(r["pressure_kpa"]) for r in rows] == sorted(P.tolist())
    assert rows[0]["contact"] == "false" and rows[-1]["contact"] == "true"
    assert {r["n_frames"] for r in rows} == {"1"} and rows[0]["phase"] == "loading"

    loaded = load_curve(paths["json"])
    np.testing.assert_allclose(loaded.fit_area, curve.fit_area)
    assert loaded.pressure_for_area(5.0) == pytest.approx(curve.pressure_for_area(5.0))
    assert loaded.pressure_interval_for_area(5.0) == pytest.approx(
        (*curve.pressure_interval_for_area(5.0)[:3], None)
    )


def test_px_curve_without_mm2_and_without_contact(tmp_path: Path) -> None:
    results = _results(mm2=False)
    paths = write_calibration(tmp_path, results, _curve(results, "px"), "learned", {})
    data = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert data["area_unit"] == "px" and all(pt["area_mm2"] is None for pt in data["points"])
    assert all(pt["area_interval_px"] is None for pt in data["points"])

    flat = [CalibrationPoint(r.file, r.pressure_kpa, False, 0.0, None) for r in results]
    paths = write_calibration(tmp_path / "none", flat, _curve(flat, "px"), "classical", {})
    data = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert data["onset_kpa"] is None and data["inverse"] is None
    # load_curve refuses it up front, naming the file and the pass (not pressure_for_area later)
    with pytest.raises(NoContactCurveError, match="the loading curve has no contact") as exc:
        load_curve(paths["json"])
    assert str(paths["json"]) in str(exc.value) and "not a readable" not in str(exc.value)
    v2 = {k: v for k, v in data.items() if k != "phases"} | {"format_version": 2}
    (tmp_path / "v2.json").write_text(json.dumps(v2), encoding="utf-8")
    with pytest.raises(NoContactCurveError, match="v2.json: the loading curve has no contact"):
        load_curve(tmp_path / "v2.json")


def test_failed_write_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def boom(*args, **kwargs):
        raise RuntimeError("plot failed")

    monkeypatch.setattr(calibration_io, "plot_curve", boom)
    results = _results()
    out = tmp_path / "out"
    with pytest.raises(RuntimeError, match="plot failed"):
        write_calibration(out, results, _curve(results), "classical", {})
    assert not out.exists()  # the folder this run created is removed too


def test_failed_write_keeps_previous_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    results = _results()
    paths = write_calibration(tmp_path, results, _curve(results), "classical", {})
    before = {k: p.read_bytes() for k, p in paths.items()}

    def boom(path, text):
        raise OSError("disk full")

    monkeypatch.setattr(calibration_io, "write_synced", boom)
    with pytest.raises(OSError, match="disk full"):
        write_calibration(tmp_path, results, _curve(results), "other", {})
    assert {k: p.read_bytes() for k, p in paths.items()} == before
    assert sorted(x.name for x in tmp_path.iterdir()) == sorted(p.name for p in paths.values())


def test_load_curve_reads_versions_1_and_2(tmp_path: Path) -> None:
    results = _results()
    fit = _curve(results)
    paths = write_calibration(tmp_path, results, fit, "classical", {})
    data = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert data["format_version"] == calibration_io.FORMAT_VERSION == 3
    # A version 2 record: the top-level fit, no phases (the fields of format 2 only).
    v3_only = ("phases", "steps", "hysteresis", "inverse_phase", "phase_source")
    v2 = {k: v for k, v in data.items() if k not in v3_only} | {"format_version": 2}
    v2["points"] = [
        {k: pt[k] for k in ("file", "pressure_kpa", "contact")} for pt in data["points"]
    ]
    (tmp_path / "v2.json").write_text(json.dumps(v2), encoding="utf-8")
    old = load_curve(tmp_path / "v2.json")
    np.testing.assert_allclose(old.fit_area, fit.curve.fit_area)
    assert old.band is None and old.model is None
    with pytest.raises(ValueError, match="no uncertainty band"):
        old.pressure_interval_for_area(5.0)
    with pytest.raises(NoSuchPhaseError, match="loading pass only"):
        load_curve(tmp_path / "v2.json", phase="unloading")
    v1 = {k: v for k, v in v2.items() if k not in ("method_config", "device_id", "argv")}
    v1 = {**v1, "format_version": 1}
    del v1["inputs"]
    (tmp_path / "v1.json").write_text(json.dumps(v1), encoding="utf-8")
    np.testing.assert_allclose(load_curve(tmp_path / "v1.json").fit_area, fit.curve.fit_area)
    for caught in (FileNotFoundError, ValueError):  # a controller may catch either
        with pytest.raises(caught, match="missing.json: no such file; expected the calibration"):
            load_curve(tmp_path / "missing.json")
    with pytest.raises(NoSuchPhaseError, match="no unloading pass: the record has loading") as exc:
        load_curve(paths["json"], phase="unloading")
    assert "not a readable" not in str(exc.value)  # it is readable; the pass is not in it
    assert load_curve(paths["json"], area_unit="mm²").area_unit == "mm²"
    assert load_curve(paths["json"], area_unit="mm2").area_unit == "mm²"
    with pytest.raises(ValueError, match="expected px \\(give area_unit='mm²'"):
        load_curve(paths["json"], area_unit="px")
    with pytest.raises(ValueError, match="area_unit 'mm\\^2': expected 'mm²'"):
        load_curve(paths["json"], area_unit="mm^2")
    (tmp_path / "v4.json").write_text(json.dumps({**data, "format_version": 4}), encoding="utf-8")
    with pytest.raises(ValueError, match="format_version 4"):
        load_curve(tmp_path / "v4.json")


@pytest.mark.parametrize("bad", ["", "x" * 101, "rig\n2", "tab\there"])
def test_provenance_rejects_bad_device_id(bad: str) -> None:
    with pytest.raises(ValueError, match="device-id"):
        calibration_io.Provenance(device_id=bad)
    assert calibration_io.check_device_id("x" * 100) == "x" * 100
    assert calibration_io.check_device_id("display #7 (left)") == "display #7 (left)"


def test_format_table() -> None:
    results = _results()
    table = format_table(results, _curve(results))
    lines = table.splitlines()
    assert "pressure (kPa)" in lines[0] and "median (mm²)" in lines[0] and "contact" in lines[0]
    assert "90 % band" in lines[0] and "min-max" in lines[0]
    assert lines[2].split()[:5] == ["loading", "0.00", "1", "0.0", "0.0"]
    assert lines[2 + len(results) - 1].split()[1] == "10.00"
    assert "dim" in table and "CV RMSE" in table and "as given" in table
    px = format_table(_results(mm2=False), _curve(_results(mm2=False), "px"))
    assert "median (px)" in px.splitlines()[0]
    named = format_table(results, _curve(results), "TD-0042 left").splitlines()
    assert named[0] == "device: TD-0042 left" and named[1:] == lines


def test_a_steps_notes_are_said_once() -> None:
    """Two frames of one step whose notes share a part (the reference's note extends its
    sibling's): the row says each part once."""
    from dataclasses import replace

    results = _results()
    four = next(r for r in results if r.pressure_kpa == 4)
    results.append(replace(four, file="p04.0b.png", note="dim; this is the reference"))
    table = format_table(results, _curve(results))
    row = next(line for line in table.splitlines() if line.split()[1:2] == ["4.00"])
    assert row.endswith("dim; this is the reference") and row.count("dim") == 1


def test_curve_title_names_the_device(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    titles: list[str | None] = []

    def spy(path: Path, results: object, fit: object, method: str, device_id: str | None) -> None:
        titles.append(device_id)
        Path(path).write_bytes(b"png")

    monkeypatch.setattr(calibration_io, "plot_curve", spy)
    results = _results()
    prov = calibration_io.Provenance(device_id="TD-7")
    calibration_io.write_calibration(tmp_path / "a", results, _curve(results), "unet", None, prov)
    calibration_io.write_calibration(tmp_path / "b", results, _curve(results), "unet")
    assert titles == ["TD-7", None]


def test_curve_title_takes_any_device_id(tmp_path: Path) -> None:
    from contactcal.infer.calibration.plot import plot_curve

    results = _results()
    odd = "x$_$y $\\frac$ " + "W" * 90  # mathtext that would not parse, and a long id
    plot_curve(tmp_path / "c.png", results, _curve(results), "unet", odd)
    assert (tmp_path / "c.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_calibration_records_provenance(tmp_path: Path) -> None:
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter

    s = copy_session(tmp_path, ("p00.0kpa.jpg", "p08.0kpa.jpg", "p16.0kpa.jpg"))
    argv = ["calibrate", str(s / "manifest.csv"), "--device-id", "TD-0042 left", "--out"]
    assert main([*argv, str(tmp_path / "u")]) == 0
    rec = json.loads((tmp_path / "u" / "calibration.json").read_text())
    assert rec["format_version"] == 3 and rec["device_id"] == "TD-0042 left"
    assert rec["argv"] == [*argv, str(tmp_path / "u")]
    cfg = rec["method_config"]
    assert cfg["name"] == "unet" and Path(cfg["model"]) == DEFAULT_MODEL.resolve()
    assert cfg["model_sha256"] == hashlib.sha256(DEFAULT_MODEL.read_bytes()).hexdigest()
    meta = OnnxSegmenter().metadata
    assert cfg["data_digest"] == meta["data_digest"] and len(cfg["data_digest"]) > 0
    assert cfg["spec"]["channels"] == int(meta["channels"]) and cfg["spec"]["threshold"] == float(
        meta["threshold"]
    )
    # the record states the resolved config: the metadata, plus the fields the model predates
    # with the values it runs with
    from contactcal.infer.methods.unet.spec import LEGACY_PREPROCESS

    assert cfg["spec"]["preprocess"] == {**LEGACY_PREPROCESS, **json.loads(meta["preprocess"])}
    assert cfg["spec"]["min_contact_area_px"] == float(meta["min_contact_area_px"])
    assert cfg["spec"]["region"] == meta.get("region", "largest")
    digests = {f["file"]: f["sha256"] for f in rec["inputs"]["frames"]}
    assert digests == {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in s.glob("*.jpg")}
    assert [f["file"] for f in rec["inputs"]["frames"]] == [p["file"] for p in rec["points"]]
    manifest_sha = hashlib.sha256((s / "manifest.csv").read_bytes()).hexdigest()
    assert rec["inputs"]["manifest"]["sha256"] == manifest_sha
    assert {"contactcal", "onnxruntime", "opencv"} <= set(rec["versions"])
    assert rec["versions"]["onnxruntime"] is not None and rec["versions"]["opencv"] is not None

    assert (
        main(
            [
                "calibrate",
                str(s / "manifest.csv"),
                "--method",
                "classical",
                "--out",
                str(tmp_path / "c"),
            ]
        )
        == 0
    )
    rec = json.loads((tmp_path / "c" / "calibration.json").read_text())
    assert rec["method_config"] == {"name": "classical", "config": asdict(ClassicalConfig())}
    assert rec["device_id"] is None


def test_a_second_run_into_one_out_says_which_calibration_it_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    s = copy_session(tmp_path)
    out = tmp_path / "c"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical", "--out", str(out)]
    assert main([*argv, "--device-id", "display-07"]) == 0
    first = json.loads((out / "calibration.json").read_text())
    assert "replaced" not in capsys.readouterr().out
    assert main([*argv, "--device-id", "display-07"]) == 0
    printed = capsys.readouterr().out
    held = f"note: replaced the calibration that {out} held (created {first['created']}, device id "
    assert held + "'display-07'); give each run its own --out to keep both" in printed
    assert json.loads((out / "calibration.json").read_text())["device_id"] == "display-07"


def test_calibrate_reads_the_earlier_record_and_the_rig_json_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The earlier calibration.json was read twice (device check, then the note) and the
    rig.json beside the manifest twice with --mm-per-px (scale and offset, then the note): two
    reads of one file can see two versions of it."""
    s = copy_session(tmp_path)
    out = tmp_path / "c"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical", "--out", str(out)]
    argv += ["--device-id", "display-07", "--mm-per-px", "0.2"]
    assert main(argv) == 0
    capsys.readouterr()
    # how the record and the rig.json are read
    reads = count_reads(monkeypatch, (out_folder, "read_record_json"), (scale, "read_input_bytes"))
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "note: replaced the calibration that" in printed  # from the one read
    assert f"note: --mm-per-px 0.2 used in place of the scale of {s / 'rig.json'}" in printed
    assert reads == {out / "calibration.json": 1, s / "rig.json": 1}


def test_a_sweep_far_above_20_kpa_is_read_with_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 0-10 kPa sweep logged in mbar reads 0-100 "kPa": calibrated (no bound tells it from a
    high-pressure display), but said."""
    s = copy_session(tmp_path)
    for top, warned in ((95.0, True), (20.0, False)):
        (s / "manifest.csv").write_text(f"file,pressure_kpa\np00.0kpa.jpg,0\np12.0kpa.jpg,{top}\n")
        out = tmp_path / f"c{top:g}"
        argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical", "--out", str(out)]
        assert main(argv) == 0
        printed = capsys.readouterr().out
        assert ("warning: the highest pressure is 95 kPa, far above" in printed) is warned
        assert ("in mbar" in printed) is warned
        assert ("convert them to kPa and run calibrate again" in printed) is warned
    # evaluate's run of the same warning names evaluate, not calibrate
    from contactcal.infer.pipeline.manifest_rows import sweep_top_warning

    assert str(sweep_top_warning(95.0, "evaluate")).endswith("run evaluate again")


@pytest.mark.parametrize("bad", ["", "x" * 101, "line\nbreak"])
def test_bad_device_id_exits_2(
    bad: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    s = copy_session(tmp_path)
    out = tmp_path / "c"
    assert main(["calibrate", str(s / "manifest.csv"), "--device-id", bad, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--device-id" in err and "printable" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
    frame = str(s / "p12.0kpa.jpg")
    assert main(["measure", "--device-id", bad, "--out", str(tmp_path / "r.json"), frame]) == 2
    assert not (tmp_path / "r.json").exists()


def test_a_curve_that_does_not_resolve_is_not_read_silently(tmp_path: Path) -> None:
    """The classical routine's curve of the example is flat (``calibrate`` warns): reading it
    for a controller is an error unless asked for; the phase name is read in any case."""
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.calibration.load import UnresolvedCurveError

    example = Path(__file__).resolve().parents[1] / "examples" / "session" / "manifest.csv"
    rep = calibrate_session(example, tmp_path / "c", "classical")
    record = json.loads(rep.files["json"].read_text())
    assert record["phases"]["loading"]["resolution"]["resolves"] is False
    with pytest.raises(UnresolvedCurveError, match=r"calibration\.json: the loading curve rises"):
        load_curve(rep.files["json"])
    curve = load_curve(rep.files["json"], phase="Loading", allow_unresolved=True)
    assert curve.onset_kpa == rep.curve.onset_kpa
    unet = calibrate_session(example, tmp_path / "u", "unet")
    assert load_curve(unet.files["json"], phase="LOADING").onset_kpa == unet.curve.onset_kpa


def test_a_replaced_record_without_a_device_id_is_said_so(tmp_path: Path) -> None:
    """The note read "device id None" for a record made without --device-id."""
    record = {"format": FORMAT, "created": "2024-05-01T10:00:00+00:00", "device_id": None}
    (tmp_path / "calibration.json").write_text(json.dumps(record))
    note = earlier_record_note(tmp_path, held_record(tmp_path))
    assert note is not None and "None" not in note
    assert f"(created {record['created']}, no device id)" in note


def test_a_foreign_calibration_csv_replaced_is_said_so(tmp_path: Path) -> None:
    """A calibration.csv without a calibration.json beside it was overwritten without a word."""
    assert earlier_record_note(tmp_path, None) is None
    (tmp_path / "calibration.csv").write_text("pressure,area\n1,2\n")
    note = earlier_record_note(tmp_path, None)
    assert note is not None
    want = f"note: replaced the calibration.csv that {tmp_path} held (no calibration"
    assert note.startswith(want)


def test_a_pooled_reading_is_a_number_in_the_record(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """pressure_kpa_read was written as a string ("5.98") in the points' extras; a manifest's
    own column of that name that is no number exits 2 naming the row."""
    s = copy_session(tmp_path, ("p00.0kpa.jpg", "p05.0kpa.jpg", "p06.0kpa.jpg", "p12.0kpa.jpg"))
    rows = "p00.0kpa.jpg,0\np05.0kpa.jpg,5.98\np06.0kpa.jpg,6.02\np12.0kpa.jpg,12\n"
    (s / "manifest.csv").write_text("file,pressure_kpa\n" + rows)
    out = tmp_path / "c"
    argv = ["calibrate", str(s / "manifest.csv"), "--method", "classical", "--out", str(out)]
    assert main(argv) == 0
    points = json.loads((out / "calibration.json").read_text())["points"]
    reads = sorted(p["extras"]["pressure_kpa_read"] for p in points if p["extras"])
    assert reads == [5.98, 6.02]
    (s / "manifest.csv").write_text(
        "file,pressure_kpa,pressure_kpa_read\np00.0kpa.jpg,0,0\np12.0kpa.jpg,12,12 kPa\n"
    )
    capsys.readouterr()
    assert main([*argv[:-1], str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err
    assert "row 2" in err and "pressure_kpa_read '12 kPa' is not a number" in err
    # a blank cell is a frame without a reading (null), not an error
    (s / "manifest.csv").write_text(
        "file,pressure_kpa,pressure_kpa_read\np00.0kpa.jpg,0,\np05.0kpa.jpg,5,5.0\n"
        "p06.0kpa.jpg,6, \np12.0kpa.jpg,12,12.01\n"
    )
    assert main([*argv[:-1], str(tmp_path / "e")]) == 0
    points = json.loads((tmp_path / "e" / "calibration.json").read_text())["points"]
    assert [p["extras"]["pressure_kpa_read"] for p in points] == [None, 5.0, None, 12.01]

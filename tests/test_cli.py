"""The CLI contract: measure / calibrate / demo outputs, exit codes and atomicity."""

from __future__ import annotations

import csv
import hashlib
import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer import cli
from contactcal.infer.cli import main
from contactcal.infer.methods.registry import METHODS
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def test_measure_contract(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.json"
    frames = [str(EXAMPLE / "p00.0kpa.jpg"), str(EXAMPLE / "p12.0kpa.jpg")]
    code = main(
        [
            "measure",
            "--method",
            "classical",
            "--reference",
            frames[0],
            "--rig",
            str(EXAMPLE / "rig.json"),
            "--out",
            str(out),
            *frames,
        ]
    )
    assert code == 0
    rows = json.loads(out.read_text())
    assert [Path(r["file"]).name for r in rows] == ["p00.0kpa.jpg", "p12.0kpa.jpg"]
    for r in rows:
        assert {"file", "contact", "area_px", "area_mm2"} <= set(r)
        assert isinstance(r["contact"], bool) and isinstance(r["area_px"], float)
        assert (r["area_px"] > 0) == r["contact"] and r["area_mm2"] is not None
    assert "p12.0kpa.jpg" in capsys.readouterr().out


def test_default_method_is_unet(tmp_path: Path) -> None:
    out = tmp_path / "r.json"
    assert main(["measure", "--out", str(out), str(EXAMPLE / "p12.0kpa.jpg")]) == 0
    assert json.loads(out.read_text())[0]["method"] == "unet"


def test_calibrate_and_overlays(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        [
            "calibrate",
            str(EXAMPLE / "manifest.csv"),
            "--out",
            str(tmp_path / "cal"),
            "--overlay",
            str(tmp_path / "ov"),
        ]
    )
    assert code == 0
    cal = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert cal["method"] == "unet" and cal["onset_kpa"] is not None
    assert (tmp_path / "cal" / "curve.png").is_file()
    assert (tmp_path / "cal" / "calibration.csv").is_file()
    assert len(list((tmp_path / "ov").glob("*_overlay.png"))) == 21
    assert "pressure" in capsys.readouterr().out


def test_bad_inputs_exit_2_and_write_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.json"
    assert main(["measure", "--out", str(out), str(tmp_path / "missing.png")]) == 2
    err = capsys.readouterr().err
    assert "missing.png" in err and "no such file" in err and not out.exists()
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    assert main(["measure", "--method", "classical", "--out", str(out), str(bad)]) == 2
    assert "bad.png" in capsys.readouterr().err and not out.exists()
    manifest = tmp_path / "m.csv"
    manifest.write_text("file,pressure\nx.png,1\n")
    assert main(["calibrate", str(manifest), "--out", str(tmp_path / "cal")]) == 2
    assert "m.csv" in capsys.readouterr().err
    assert not (tmp_path / "cal").exists()
    assert (
        main(
            [
                "measure",
                "--model",
                str(tmp_path / "none.onnx"),
                "--out",
                str(out),
                str(EXAMPLE / "p12.0kpa.jpg"),
            ]
        )
        == 2
    )
    assert "none.onnx" in capsys.readouterr().err


def test_no_contact_session_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for name in ("p00.0kpa.jpg", "p01.0kpa.jpg"):  # the example's onset is 2.35 kPa
        shutil.copy(EXAMPLE / name, tmp_path / name)
    (tmp_path / "manifest.csv").write_text("file,pressure_kpa\np00.0kpa.jpg,0\np01.0kpa.jpg,1\n")
    assert main(["calibrate", str(tmp_path / "manifest.csv"), "--out", str(tmp_path / "c")]) == 1
    assert "no contact detected" in capsys.readouterr().err
    assert not (tmp_path / "c" / "calibration.json").exists()


def test_demo(tmp_path: Path) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    with open(EXAMPLE / "truth.csv", newline="") as fh:
        truth = {float(r["pressure_kpa"]): float(r["area_mm2"]) for r in csv.DictReader(fh)}
    records = {m: json.loads((tmp_path / m / "calibration.json").read_text()) for m in METHODS}
    for method, rec in records.items():
        assert rec["method"] == method and rec["area_unit"] == "mm²"
        assert rec["argv"] == ["demo", "--out", str(tmp_path)]  # was null: not recorded
        assert rec["extra"]["reference_frame"] == "p00.0kpa.jpg"  # as the manifest lists it
        assert [p["pressure_kpa"] for p in rec["points"]] == sorted(truth)
        assert (tmp_path / method / "curve.png").stat().st_size > 0
    unet = {p["pressure_kpa"]: p for p in records["unet"]["points"]}
    errors = [abs(unet[p]["area_mm2"] / a - 1) for p, a in truth.items() if p >= 5]
    assert max(errors) < 0.1, f"U-Net relative area errors on the example: {errors}"
    assert not any(unet[p]["contact"] for p, a in truth.items() if a == 0)
    montage = cv2.imread(str(tmp_path / "overlay_montage.png"))
    assert montage is not None and montage.shape[1] == 3 * 400  # 3 columns of 400 px tiles
    summary = (tmp_path / "summary.txt").read_text()
    assert all(f"== {m}" in summary for m in METHODS)


def test_measure_says_which_reference_mode_ran(tmp_path: Path) -> None:
    """Without --reference every result says so (and how the method coped); with it, names it."""
    frame, ref = str(EXAMPLE / "p12.0kpa.jpg"), str(EXAMPLE / "p00.0kpa.jpg")
    for method in METHODS:
        out = tmp_path / f"{method}.json"
        assert main(["measure", "--method", method, "--out", str(out), frame]) == 0
        row = json.loads(out.read_text())[0]
        assert row["reference"] is None and "no reference frame" in row["note"]
        assert (
            main(["measure", "--method", method, "--reference", ref, "--out", str(out), frame]) == 0
        )
        row = json.loads(out.read_text())[0]
        assert row["reference"] == ref and "no reference frame" not in row["note"]


def test_measure_records_the_models_that_measured(tmp_path: Path) -> None:
    """Each result names the model that measured it (its file and the sha256 of its content, as
    ``calibration.json``'s ``method_config``), with ``--overlay`` the one that only drew the
    outlines (``overlay_methods``); the classical routine has none (null)."""
    other = tmp_path / "other.onnx"  # another loadable model: a doc_string (field 6) appended
    other.write_bytes(DEFAULT_MODEL.read_bytes() + b"\x32\x01x")
    model = {
        m: {"model": str(m.resolve()), "model_sha256": hashlib.sha256(m.read_bytes()).hexdigest()}
        for m in (DEFAULT_MODEL, other)
    }
    assert model[other]["model_sha256"] != model[DEFAULT_MODEL]["model_sha256"]
    frame, out = str(EXAMPLE / "p12.0kpa.jpg"), tmp_path / "r.json"
    none = {"model": None, "model_sha256": None}
    runs = [
        ([], {**model[DEFAULT_MODEL], "overlay_methods": None}),
        (["--model", str(other)], {**model[other], "overlay_methods": None}),
        (["--method", "classical"], {**none, "overlay_methods": None}),
        (
            ["--method", "classical", "--model", str(other), "--overlay", str(tmp_path / "ov")],
            {**none, "overlay_methods": {"unet": model[other]}},
        ),
        (
            ["--overlay", str(tmp_path / "ov")],
            {**model[DEFAULT_MODEL], "overlay_methods": {"classical": none}},
        ),
    ]
    for options, recorded in runs:
        assert main(["measure", *options, "--out", str(out), frame]) == 0
        row = json.loads(out.read_text())[0]
        assert {k: row[k] for k in recorded} == recorded, options


def test_core_commands_skip_the_plugin_commands(monkeypatch: pytest.MonkeyPatch) -> None:
    """A core command does not look up the synth/train commands; --help and theirs do."""
    calls: list[int] = []
    monkeypatch.setattr(cli, "add_plugin_commands", lambda sub: calls.append(1))
    for command in ("measure", "calibrate", "bench", "demo"):
        cli.build_parser(command)
    assert calls == []
    for command in (None, "--help", "train", "synth"):
        cli.build_parser(command)
    assert len(calls) == 4


def test_demo_takes_bit_depth_and_says_which_calibration_it_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --manifest`` of a 12-bit camera's 16-bit PNGs needs ``--bit-depth 12`` as
    ``calibrate`` does; a second run into one ``--out`` names each record it replaced."""
    session = tmp_path / "s"
    session.mkdir()
    rows = ["file,pressure_kpa"]
    for kpa in (0, 6, 12, 18):
        gray = cv2.imread(str(EXAMPLE / f"p{kpa:04.1f}kpa.jpg"), cv2.IMREAD_GRAYSCALE)
        data = np.rint(gray * (4095 / 255)).astype(np.uint16)  # 12-bit data in 16 bits
        assert cv2.imwrite(str(session / f"p{kpa}.png"), data)
        rows.append(f"p{kpa}.png,{kpa}")
    (session / "manifest.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "demo"
    argv = ["demo", "--manifest", str(session / "manifest.csv"), "--out", str(out)]
    assert main(argv) == 2
    assert "--bit-depth" in capsys.readouterr().err
    assert main([*argv, "--bit-depth", "12"]) == 0
    assert "replaced" not in capsys.readouterr().out
    assert main([*argv, "--bit-depth", "12"]) == 0
    printed = capsys.readouterr().out
    for method in METHODS:
        assert f"note: replaced the calibration that {out / method} held (created " in printed
    # no rig.json beside that manifest: areas in px, said as calibrate says it
    assert "note: no pixel scale (no rig.json beside the manifest): areas are in px" in printed


@pytest.mark.parametrize(
    "argv",
    [
        ["measure", "x.png", "--out", "o", "--ref", "r.png"],  # --reference
        ["calibrate", "m.csv", "--out", "o", "--mm", "0.05"],  # --mm-per-px
        # a plugin command's --seed (--fingers 0: a prefix taken is a quick refusal, no render)
        ["synth", "--fingers", "0", "--out", "o", "--see", "3"],
    ],
)
def test_option_prefixes_are_refused(
    argv: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """An abbreviation is not taken for the option it starts: a recorded command line keeps its
    meaning when an option sharing the prefix is added. (Run where the relative ``--out`` of a
    prefix taken would write: the synth case once rendered a dataset into the repository.)"""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert f"unrecognized arguments: {argv[-2]} {argv[-1]}" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_module_tools_refuse_option_prefixes(capsys: pytest.CaptureFixture[str]) -> None:
    """The ``python -m`` tools' parsers take whole option names too."""
    from contactcal.train import floor, restate

    with pytest.raises(SystemExit) as exit_:
        floor.main(["m.onnx", "--percentile", "1", "--out", "new.onnx", "--perc", "2"])
    assert exit_.value.code == 2
    assert "unrecognized arguments: --perc 2" in capsys.readouterr().err
    parser = restate.restating_parser("restate", "a restating tool")
    with pytest.raises(SystemExit):
        parser.parse_args(["m.onnx", "--data", "d", "--out", "new.onnx", "--dat", "e"])
    assert "unrecognized arguments: --dat e" in capsys.readouterr().err

"""``contactcal quantize``: the INT8 variant loads with the same spec and decides like the float."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from procedural import write_dataset
from test_one_path import _example_dataset

pytest.importorskip("onnx")

from contactcal.infer.bench.dataset import spread
from contactcal.infer.cli import main
from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter
from contactcal.train import quantize
from contactcal.train.quantize import quantize_model


def test_int8_variant_keeps_the_spec_and_the_decisions(tmp_path: Path) -> None:
    data = _example_dataset(tmp_path / "data")  # rendered frames, as calibration should use
    out = tmp_path / "int8.onnx"
    check = quantize_model(DEFAULT_MODEL, out, [data], frames=3)
    assert OnnxSegmenter(out).spec == OnnxSegmenter(DEFAULT_MODEL).spec  # same metadata
    assert out.stat().st_size < 0.6 * Path(DEFAULT_MODEL).stat().st_size  # weights in int8
    assert check["frames"] == 3 and check["check_frames"] == 3 and check["contact_agreement"] == 1.0
    ratio = check["median_area_ratio"]
    assert ratio is not None and 0.95 <= ratio <= 1.05
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


def test_refuses_to_overwrite_the_float_model(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data")
    with pytest.raises(ValueError, match="overwrite"):
        quantize_model(DEFAULT_MODEL, DEFAULT_MODEL, [data], frames=2)


def test_cli_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["quantize", str(DEFAULT_MODEL), "--out", str(tmp_path / "q.onnx")]
    assert main([*argv, "--data", str(tmp_path / "missing")]) == 2
    assert f"--data {tmp_path / 'missing'}: does not exist;" in capsys.readouterr().err
    data = write_dataset(tmp_path / "data")
    assert main([*argv, "--data", str(data), "--frames", "0"]) == 2
    assert not (tmp_path / "q.onnx").exists()


def test_refuses_an_int8_model_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    data = _example_dataset(tmp_path / "data")
    q = tmp_path / "int8.onnx"
    argv = ["quantize", str(DEFAULT_MODEL), "--out", str(q), "--data", str(data), "--frames", "2"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert err == "" and out.startswith(f"wrote {q}: calibrated on 2 frames; on 2 others")
    assert "replaced" not in out  # nothing was there to replace
    assert not [r.getMessage() for r in caplog.records]  # onnxruntime's advice held back
    with pytest.raises(ValueError, match="already quantized"):
        quantize_model(q, tmp_path / "qq.onnx", [data], frames=2)
    assert not (tmp_path / "qq.onnx").exists()


def test_cli_says_which_model_it_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An --out that held a file is replaced with a note naming it and its content's sha256."""
    data = _example_dataset(tmp_path / "data")
    q = tmp_path / "int8.onnx"
    q.write_bytes(b"an earlier INT8 model")
    argv = ["quantize", str(DEFAULT_MODEL), "--out", str(q), "--data", str(data), "--frames", "2"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    first, note = out.strip().splitlines()
    assert err == "" and first.startswith(f"wrote {q}: calibrated on 2 frames")
    held = sha256_bytes(b"an earlier INT8 model")[:12]
    assert note == f"note: replaced {q} (sha256 {held}); give each run its own --out to keep both"
    assert q.read_bytes() != b"an earlier INT8 model"


def test_cli_refuses_an_output_that_is_not_a_model_before_the_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = write_dataset(tmp_path / "data")
    frame = next(data.rglob("*.png"))
    before = frame.read_bytes()
    for out in (frame, data / "index.csv"):
        argv = ["quantize", str(DEFAULT_MODEL), "--out", str(out), "--data", str(data)]
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--out {out}: expected an output file name ending" in err[0]
    assert frame.read_bytes() == before


def test_calibration_frames_are_spread_over_all_frames() -> None:
    # 65 frames, 40 wanted: a stride of 65 // 40 = 1 once took the first 40 (the first sessions)
    idx = spread(65, 40)
    assert len(idx) == 40 and idx[0] == 0 and idx[-1] == 64
    assert spread(5, 64) == [0, 1, 2, 3, 4] and spread(10, 1) == [0] and spread(0, 3) == []


def test_an_int8_model_that_departs_from_the_float_is_not_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A failed check is a run error (exit 1, one line) and leaves the earlier file untouched."""
    data = _example_dataset(tmp_path / "data")
    out = tmp_path / "int8.onnx"
    out.write_bytes(b"an earlier INT8 model")
    argv = ["quantize", str(DEFAULT_MODEL), "--out", str(out), "--data", str(data)]
    checks = {
        "% of 2 frames not used to calibrate it": {"check_frames": 2.0, "contact_agreement": 0.5},
        "0.900× the float model's": {"check_frames": 2.0, "median_area_ratio": 0.9},
    }
    for expected, bad in checks.items():
        fake = {"check_frames": 2.0, "contact_agreement": 1.0, "median_area_ratio": 1.0, **bad}
        monkeypatch.setattr(quantize, "_agreement", lambda *a, fake=fake: fake)
        assert main([*argv, "--frames", "2"]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "not written" in err[0] and expected in err[0], err

    def unreadable(*args: object) -> None:
        raise ValueError("model metadata: no 'preprocess'\n key")

    monkeypatch.setattr(quantize, "_agreement", unreadable)
    assert main([*argv, "--frames", "2"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fails its check (model metadata: no 'preprocess' key)" in err[0]
    assert out.read_bytes() == b"an earlier INT8 model"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "int8.onnx"]


def test_the_agreement_is_checked_on_frames_not_used_to_calibrate(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Agreement measured on the calibration frames themselves would be in-sample: the check
    segments the frames the calibration reader was not given (every other one drawn)."""
    data = _example_dataset(tmp_path / "data")
    drawn, calibrated, checked = [], [], []
    frames, reader, agreement = quantize.calibration_frames, quantize._Reader, quantize._agreement

    def draw(*args: object) -> list:
        drawn[:] = frames(*args)
        return drawn

    def read(name: str, inputs: list) -> quantize._Reader:
        calibrated.extend(inputs)
        return reader(name, inputs)

    def check(a: OnnxSegmenter, b: OnnxSegmenter, pairs: list) -> dict:
        checked.extend(g for g, _ in pairs)
        return agreement(a, b, pairs)

    monkeypatch.setattr(quantize, "calibration_frames", draw)
    monkeypatch.setattr(quantize, "_Reader", read)
    monkeypatch.setattr(quantize, "_agreement", check)
    result = quantize_model(DEFAULT_MODEL, tmp_path / "q.onnx", [data], frames=3)
    assert result["frames"] == 3 and result["check_frames"] == 3 and len(drawn) == 6
    assert [id(g) for g in checked] == [id(g) for g, _ in drawn[1::2]]
    assert len(calibrated) == 3
    with pytest.raises(ValueError, match=r"frames must be >= 1"):
        quantize_model(DEFAULT_MODEL, tmp_path / "q2.onnx", [data], frames=0)
    one = tmp_path / "one"
    shutil.copytree(data, one)
    rows = (one / "index.csv").read_text().splitlines()
    (one / "index.csv").write_text("\n".join(rows[:2]) + "\n")  # the header and one frame
    with pytest.raises(ValueError, match=r"1 frame\(s\) in .*expected at least 2 \(one to"):
        quantize_model(DEFAULT_MODEL, tmp_path / "q2.onnx", [one], frames=3)


def test_the_float_model_is_read_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The float model is read once, through the checked reader: the model checked, calibrated
    and whose metadata the INT8 model carries is that content. It was read three times (the
    float session, ``onnx.load``, ``quantize_static``), the last two unchecked: a model
    re-exported meanwhile (here: replaced by junk after the first read) was quantized as another."""
    from read_counts import count_reads

    from contactcal.infer.methods.unet import runner

    data = _example_dataset(tmp_path / "data")
    model = tmp_path / "float.onnx"
    shutil.copyfile(DEFAULT_MODEL, model)
    reads = count_reads(
        monkeypatch,
        (runner, "read_input_bytes"),
        only={model},
        after=lambda path, _: path.write_bytes(b"not a model"),
    )
    quantize_model(model, tmp_path / "q.onnx", [data], frames=2)
    assert reads[model] == 1
    assert OnnxSegmenter(tmp_path / "q.onnx").spec == OnnxSegmenter(DEFAULT_MODEL).spec

"""The change gate (metadata ``min_change``): a kept region that looks as it did in the session's
zero-pressure frame is "no contact"; its threshold is calibrated on validation renders."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox
from contactcal.infer.methods.unet.postprocess import postprocess, region_change
from contactcal.infer.methods.unet.prepare import reference_difference, session_reference
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter
from contactcal.infer.methods.unet.spec import IntervalSpec, ModelError, ModelSpec, read_spec
from contactcal.train.change_gate import MARGIN, margin_threshold

SIZE = 64
BOX = CropBox(x0=0, y0=0, side=128)  # 2 × 2 input pixels per network pixel
SHAPE = (128, 128)
SPEC = ModelSpec(2, PreprocessConfig(input_size=SIZE), 0.5, 20.0, IntervalSpec(0.9, 0.1, 0.9, 1, 9))
GATED = dataclasses.replace(SPEC, min_change=0.2)


def square(p: float = 0.8) -> np.ndarray:
    """``(SIZE, SIZE) float32``: a 20×20 px square of probability ``p``, 0 elsewhere."""
    prob = np.zeros((SIZE, SIZE), np.float32)
    prob[20:40, 20:40] = p
    return prob


def difference_in_square(inside: float) -> np.ndarray:
    """``(SIZE, SIZE) float32`` |frame − reference|: ``inside`` in the square, 1 elsewhere (the
    gate must read the region only)."""
    diff = np.ones((SIZE, SIZE), np.float32)
    diff[20:40, 20:40] = inside
    return diff


def test_region_change_is_the_mean_over_the_region() -> None:
    keep = square() >= 0.5
    diff = difference_in_square(0.1)
    diff[20, 20] = 4.1  # one pixel of 400 adds 4 / 400
    assert region_change(diff, keep) == pytest.approx(0.11)


def test_gate_turns_an_unchanged_region_into_no_contact() -> None:
    seg = postprocess(square(), BOX, SHAPE, GATED, difference_in_square(0.1))
    assert not seg.contact and seg.unchanged and seg.area_px == 0.0
    assert seg.change == pytest.approx(0.1) and seg.region_net_px == 400.0
    assert seg.interval_px is not None and seg.interval_px[0] == 0.0 < seg.interval_px[1]


def test_gate_keeps_a_changed_region_as_it_was() -> None:
    seg = postprocess(square(), BOX, SHAPE, GATED, difference_in_square(0.3))
    ungated = postprocess(square(), BOX, SHAPE, SPEC)
    assert seg.contact and not seg.unchanged and seg.change == pytest.approx(0.3)
    assert seg.area_px == ungated.area_px == 400 * 4 and seg.interval_px == ungated.interval_px


def test_no_gate_without_a_difference_or_a_threshold() -> None:
    assert postprocess(square(), BOX, SHAPE, GATED).contact  # no reference frame: no gate
    seg = postprocess(square(), BOX, SHAPE, SPEC, difference_in_square(0.0))
    assert seg.contact and seg.change == 0.0 and not seg.unchanged  # min_change 0: no gate
    small = postprocess(square(0.3), BOX, SHAPE, GATED, difference_in_square(0.0))
    assert not small.contact and small.change is None and not small.unchanged  # no region


def test_reference_difference_needs_a_reference_frame_and_channel() -> None:
    cfg = PreprocessConfig(input_size=SIZE, ridge_work_px=0)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2, SIZE, SIZE)).astype(np.float32)
    gray = np.full((96, 128), 40, np.uint8)
    ref = session_reference(gray, cfg)
    diff = reference_difference(x, ref, True)
    assert diff is not None and diff.shape == (SIZE, SIZE)
    np.testing.assert_array_equal(diff, np.abs(x[0] - x[1]))
    assert reference_difference(x, session_reference(None, cfg), True) is None
    assert reference_difference(x[:1], ref, False) is None


def _gated(path: Path, min_change: float) -> Path:
    """The shipped model written to ``path`` with ``min_change`` set (metadata only)."""
    onnx = pytest.importorskip("onnx")
    from contactcal.infer.methods.unet.method import UnetMethod
    from contactcal.train.restate import save_restated

    spec = dataclasses.replace(UnetMethod().segmenter.spec, min_change=min_change)
    save_restated(onnx.load(str(DEFAULT_MODEL)), {"min_change": repr(min_change)}, spec, path)
    return path


def _metadata() -> dict[str, str]:
    return dict(OnnxSegmenter().metadata)


def test_min_change_metadata_round_trip_default_and_errors() -> None:
    base = read_spec(_metadata(), "m.onnx")
    meta = {**_metadata(), **dataclasses.replace(base, min_change=0.07).to_metadata()}
    assert read_spec(meta, "m.onnx").min_change == 0.07
    del meta["min_change"]  # a model exported before the key existed: no gate
    assert read_spec(meta, "m.onnx").min_change == 0.0
    for bad in ("-0.1", "nan", "inf", "much"):
        with pytest.raises(ModelError, match=r"m.onnx.*min_change.*train.change_gate"):
            read_spec({**meta, "min_change": bad}, "m.onnx")
    with pytest.raises(ValueError, match="min_change"):
        dataclasses.replace(SPEC, min_change=-1.0)
    with pytest.raises(ValueError, match="reference channel"):
        dataclasses.replace(SPEC, channels=1, min_change=0.1)
    single = {**meta, "channels": "2", "min_change": "0.1"}  # frame + ridge: no reference
    with pytest.raises(ModelError, match=r"m.onnx.*reference channel.*remove the min_change key"):
        read_spec(single, "m.onnx")
    assert read_spec({**single, "min_change": "0"}, "m.onnx").min_change == 0.0


def test_margin_threshold_reference_values_and_bad_input() -> None:
    change = np.array([0.02, 0.05, 0.09, 0.3, 0.12, 0.4, 0.2])
    contact = np.array([False, False, False, False, True, True, True])
    t, summary = margin_threshold(change, contact)
    assert MARGIN == 2.0 and t == pytest.approx(0.06)
    assert summary["false_removed"] == 2 and summary["regions_false"] == 4
    assert summary["smallest_true_change"] == pytest.approx(0.12)
    with pytest.raises(ValueError, match="no region in a frame in contact"):
        margin_threshold(change, np.zeros(7, bool))
    with pytest.raises(ValueError, match="finite"):
        margin_threshold(np.array([np.nan, 0.1]), np.array([False, True]))
    with pytest.raises(ValueError, match="one per region"):
        margin_threshold(change, contact[:3])


def test_gate_model_writes_the_threshold_and_refuses_bad_paths(tmp_path: Path) -> None:
    onnx = pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.infer.methods.unet.method import UnetMethod
    from contactcal.train.change_gate import collect_changes, gate_model, main

    data = write_dataset(tmp_path / "data", fingers=3)
    out = tmp_path / "gated.onnx"
    summary = gate_model(DEFAULT_MODEL, [data], out, specks=(0.2,), draws=1)
    change, contact, frames = collect_changes(DEFAULT_MODEL, [data], (0.2,), 1)
    assert summary["min_change"] == pytest.approx(change[contact].min() / MARGIN)
    assert frames == summary["frames"] and set(frames) == {"0.0", "0.2"}
    new, src = onnx.load(str(out)), onnx.load(str(DEFAULT_MODEL))
    assert new.graph.SerializeToString() == src.graph.SerializeToString()
    after = {p.key: p.value for p in new.metadata_props}
    assert json.loads(after["min_change"])["value"] == summary["min_change"]
    assert UnetMethod(out).describe()["spec"]["min_change"] == summary["min_change"]
    assert json.loads(after["interval"]) == json.loads(
        {p.key: p.value for p in src.metadata_props}["interval"]
    )
    for bad in (tmp_path / "x.txt", DEFAULT_MODEL):
        assert main([str(DEFAULT_MODEL), "--data", str(data), "--out", str(bad)]) == 2
    assert not (tmp_path / "x.txt").exists()


def test_data_without_a_region_in_contact_names_data_and_model(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """No kept region in a contact frame (an untrained model): one line naming both."""
    pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train import change_gate

    data, out = write_dataset(tmp_path / "data", fingers=2), tmp_path / "gated.onnx"
    none = (np.array([0.1]), np.array([False]), {"0.0": 1})  # a region, in no contact frame
    monkeypatch.setattr(change_gate, "_changes", lambda *args: none)
    assert change_gate.main([str(DEFAULT_MODEL), "--data", str(data), "--out", str(out)]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert f"--data {data}: {DEFAULT_MODEL}: no region in a frame in contact" in err, err
    assert "expected frames in contact that the model segments" in err and not out.exists()


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("--seed", "-1", "an integer >= 0"),
        ("--draws", "0", "at least 1 speck"),
        ("--speck", "1.5", "speck levels in (0, 1]"),
    ],
)
def test_gate_options_are_named_in_errors(
    option: str, value: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train.change_gate import main

    data, out = write_dataset(tmp_path / "d", fingers=1), tmp_path / "g.onnx"
    argv = [str(DEFAULT_MODEL), "--data", str(data), "--out", str(out), option, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {option} {value}: expected {expected}")
    assert err.count("\n") == 1 and not out.exists()


def _session(root: Path) -> list:
    """One procedural session's index rows, lowest pressure first."""
    from procedural import write_dataset

    from contactcal.infer.bench.dataset import read_index, sessions_of

    rows = next(iter(sessions_of(read_index(write_dataset(root, fingers=1))).values()))
    return sorted(rows, key=lambda r: r.pressure_kpa)


def test_a_gated_frame_says_why_and_no_reference_means_no_gate(tmp_path: Path) -> None:
    from contactcal.infer.image.read import load_image
    from contactcal.infer.methods.unet.method import UnetMethod

    rows = _session(tmp_path / "d")
    out = _gated(tmp_path / "strict.onnx", 100.0)  # a gate no contact passes
    frame = load_image(rows[-1].frame)  # the highest pressure: in contact
    shipped, strict = UnetMethod(), UnetMethod(out)
    for m in (shipped, strict):
        m.set_reference(load_image(rows[0].frame))
    assert rows[-1].contact and shipped.measure(frame).contact
    gated = strict.measure(frame)
    assert not gated.contact and gated.area_px == 0.0
    assert "unchanged from the reference frame" in gated.note and "< 100.000" in gated.note
    strict.set_reference(None)
    assert strict.measure(frame).contact  # nothing to compare with: no gate


def test_no_change_gate_measures_the_region_and_says_so(tmp_path: Path) -> None:
    from contactcal.infer.cli import main
    from contactcal.infer.image.read import load_image
    from contactcal.infer.methods.unet.method import UnetMethod

    rows = _session(tmp_path / "d")
    strict = _gated(tmp_path / "strict.onnx", 100.0)
    off = UnetMethod(strict, change_gate=False)
    off.set_reference(load_image(rows[0].frame))
    res = off.measure(load_image(rows[-1].frame))
    assert res.contact and res.note.startswith("kept by --no-change-gate: change ")
    assert res.note.endswith(" < 100.000")
    assert off.describe()["change_gate"] == "off (--no-change-gate)"
    assert off.describe()["spec"]["min_change"] == 100.0  # the model's, as stated
    assert UnetMethod(strict).describe()["change_gate"] == "on"
    legacy = _gated(tmp_path / "legacy.onnx", 0.0)  # a model without a gate
    assert UnetMethod(legacy, change_gate=False).describe()["change_gate"] == "none in the model"
    out = tmp_path / "r.json"
    ref, frame = str(rows[0].frame), str(rows[-1].frame)
    args = ["measure", "--model", str(strict), "--reference", ref, "--out", str(out), frame]
    assert main([*args, "--no-change-gate"]) == 0
    (row,) = json.loads(out.read_text())
    assert row["contact"] and "kept by --no-change-gate" in row["note"]
    out.unlink()
    assert main(args) == 0
    (row,) = json.loads(out.read_text())
    assert not row["contact"] and "unchanged from the reference frame" in row["note"]


def test_a_frame_against_itself_is_unchanged(tmp_path: Path) -> None:
    from contactcal.infer.image.read import load_image
    from contactcal.infer.methods.base import UNCHANGED_NOTE
    from contactcal.infer.methods.unet.method import UnetMethod

    frame = load_image(_session(tmp_path / "d")[-1].frame)  # the highest pressure: in contact
    m = UnetMethod()  # the shipped gate
    assert m.segmenter.spec.min_change > 0.0
    m.set_reference(None)
    assert m.measure(frame).contact  # no reference frame: no gate
    m.set_reference(frame)  # the frame is its own reference: nothing changed
    res = m.measure(frame)
    limit = f"{m.segmenter.spec.min_change:.3f}"
    assert not res.contact and res.note == f"{UNCHANGED_NOTE} (change 0.000 < {limit})"


def test_measure_says_when_a_frame_is_its_own_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``measure --reference X X`` (or a byte-identical copy of X): the gate's "no contact"
    is noted and warned as a frame compared with itself; the result is unchanged."""
    import shutil

    from contactcal.infer.cli import main
    from contactcal.infer.pipeline.measure import SELF_REFERENCE_NOTE

    example = Path(__file__).resolve().parents[1] / "examples" / "session"
    ref = example / "p12.0kpa.jpg"  # in contact: only the gate says no contact
    copy = tmp_path / "copy.jpg"
    shutil.copy(ref, copy)
    other = example / "p14.0kpa.jpg"
    out = tmp_path / "r.json"
    argv = ["measure", "--reference", str(ref), "--out", str(out), str(ref), str(copy), str(other)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    same, copied, different = json.loads(out.read_text())
    for row, how in ((same, "path"), (copied, "bytes")):
        assert not row["contact"] and row["area_px"] == 0.0  # as measured
        assert row["note"].startswith("no contact: the region is unchanged from the reference")
        assert row["note"].endswith(SELF_REFERENCE_NOTE.format(how=how))
        assert f"warning: {row['file']}: {SELF_REFERENCE_NOTE.format(how=how)}" in err
    assert "reference frame itself" not in different["note"]
    assert err.count("warning:") == 2

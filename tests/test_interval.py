"""The stated interval of a frame's area: carried through results, contains the estimate, wider
for a soft edge, read strictly from the model's metadata, shipped, calibrated to its level."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.methods.base import AreaResult
from contactcal.infer.methods.classical import ClassicalMethod
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox
from contactcal.infer.methods.unet.postprocess import Band, boundary_band, postprocess
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter
from contactcal.infer.methods.unet.spec import IntervalSpec, ModelError, ModelSpec, read_spec
from contactcal.infer.pipeline.measure import Measured
from contactcal.train.interval import calibrate, required_widen

SIZE = 64
BOX = CropBox(x0=0, y0=0, side=128)  # 4 input pixels per network pixel
SHAPE = (128, 128)
INTERVAL = IntervalSpec(0.9, 0.12, 0.88, 1.0, 100)
SPEC = ModelSpec(1, PreprocessConfig(input_size=SIZE), 0.5, 20.0, INTERVAL)


def disk(radius: float, edge: float) -> np.ndarray:
    """``(SIZE, SIZE) float32`` probabilities of a disk with a logistic edge ``edge`` px wide."""
    yy, xx = np.mgrid[0:SIZE, 0:SIZE] - (SIZE - 1) / 2.0
    return (1.0 / (1.0 + np.exp((np.hypot(xx, yy) - radius) / edge))).astype(np.float32)


def test_upscaled_scales_the_interval_and_keeps_none() -> None:
    res = AreaResult(True, 10.0, "", None, 11.0, (8.0, 13.0))
    up = res.upscaled(4)
    assert up.area_px == 160.0 and up.area_interval_px == (128.0, 208.0)
    assert AreaResult(False, 0.0, "no contact", None).upscaled(4).area_interval_px is None


def test_measured_json_carries_the_interval() -> None:
    res = AreaResult(True, 10.0, "", None, None, (8.0, 13.0))
    obj = Measured(Path("f.png"), 4, 3, res, None).to_json("unet")
    assert obj["area_interval_px"] == [8.0, 13.0]
    none = Measured(Path("f.png"), 4, 3, dataclasses.replace(res, area_interval_px=None), None)
    assert none.to_json("classical")["area_interval_px"] is None


@pytest.mark.parametrize("edge", [0.3, 1.0, 3.0])
def test_interval_contains_the_estimate(edge: float) -> None:
    seg = postprocess(disk(15.0, edge), BOX, SHAPE, SPEC)
    assert seg.contact and seg.interval_px is not None
    lower, upper = seg.interval_px
    assert 0.0 <= lower <= seg.area_px <= upper
    assert np.isclose(seg.area_px, seg.region_net_px * 4.0)


def test_soft_edge_gives_a_wider_interval() -> None:
    sharp = postprocess(disk(15.0, 0.2), BOX, SHAPE, SPEC).interval_px
    soft = postprocess(disk(15.0, 3.0), BOX, SHAPE, SPEC).interval_px
    assert sharp is not None and soft is not None
    assert soft[1] - soft[0] > 2.0 * (sharp[1] - sharp[0]) > 0.0


def test_no_contact_interval() -> None:
    seg = postprocess(np.zeros((SIZE, SIZE), np.float32), BOX, SHAPE, SPEC)
    assert not seg.contact and seg.interval_px == (0.0, 0.0)
    # A patch below the minimum area at the threshold but above it at the looser threshold.
    prob = np.zeros((SIZE, SIZE), np.float32)
    prob[20:24, 20:24] = 0.9  # 16 network px < 20
    prob[18:26, 18:26] = np.maximum(prob[18:26, 18:26], 0.3)  # 64 px at p >= 0.12
    seg = postprocess(prob, BOX, SHAPE, SPEC)
    assert not seg.contact and seg.area_px == 0.0
    assert seg.interval_px == (0.0, 64.0 * 4.0)


def test_band_interval_contains_area_for_any_factor() -> None:
    band = Band(area=100.0, strict=80.0, loose=130.0, edge=10.0)
    for widen in (0.0, 0.5, 1.0, 7.0):
        lower, upper = band.interval(widen)
        assert 0.0 <= lower <= 100.0 <= upper
    assert band.interval(1.0) == (70.0, 140.0)
    assert required_widen(band, 140.0) == 1.0 and required_widen(band, 85.0) == 0.5
    assert required_widen(Band(0.0, 0.0, 0.0, 0.0), 5.0) == float("inf")


def _metadata() -> dict[str, str]:
    meta = dict(OnnxSegmenter().metadata)
    assert read_spec(meta, "m.onnx").interval is not None
    return meta


def test_read_spec_requires_the_interval_key() -> None:
    meta = _metadata()
    del meta["interval"]
    with pytest.raises(ModelError, match="lacks key.*interval"):
        read_spec(meta, "m.onnx")


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"level": 1.5}, "level"),
        ({"threshold_low": 0.6}, "enclose the threshold"),
        ({"threshold_low": 0.9, "threshold_high": 0.2}, "threshold_low < threshold_high"),
        ({"widen": -1.0}, "widen"),
        ({"widen": True}, "numbers"),
        ({"frames": 0}, "frames"),
        ({"extra": 1}, "unknown key"),
    ],
)
def test_read_spec_rejects_an_invalid_interval(change: dict[str, object], match: str) -> None:
    meta = _metadata()
    meta["interval"] = json.dumps({**json.loads(meta["interval"]), **change})
    with pytest.raises(ModelError, match=match):
        read_spec(meta, "m.onnx")
    meta["interval"] = "[0.9]"
    with pytest.raises(ModelError, match="JSON object"):
        read_spec(meta, "m.onnx")


def test_to_metadata_needs_a_calibrated_interval() -> None:
    with pytest.raises(ValueError, match="calibrate"):
        dataclasses.replace(SPEC, interval=None).to_metadata()
    assert json.loads(SPEC.to_metadata()["interval"]) == dataclasses.asdict(INTERVAL)


def test_shipped_model_states_a_90_percent_interval() -> None:
    import onnx

    meta = {p.key: p.value for p in onnx.load(str(DEFAULT_MODEL)).metadata_props}
    iv = read_spec(meta, DEFAULT_MODEL).interval
    assert iv is not None and iv.level == 0.9 and iv.frames >= 50
    assert iv.threshold_low < 0.5 < iv.threshold_high and iv.widen > 0.0


def test_classical_states_no_interval() -> None:
    from procedural import draw_frame

    frame = draw_frame(np.random.default_rng(0), 160, 120, semi_axes_px=(20.0, 15.0))
    method = ClassicalMethod()
    method.set_reference(None)
    assert method.measure(frame.image).area_interval_px is None


def test_calibration_reaches_its_level_on_its_frames() -> None:
    rng = np.random.default_rng(3)
    base = dataclasses.replace(SPEC, interval=None)
    segs, truths = [], []
    for _ in range(60):
        r, edge = rng.uniform(8.0, 20.0), rng.uniform(0.3, 2.5)
        seg = postprocess(disk(r, edge), BOX, SHAPE, base)
        segs.append(seg)
        truths.append(seg.area_px * rng.normal(1.0, 0.05))  # the estimate is off by ~5 %
    iv, summary = calibrate(segs, truths, base)
    spec = dataclasses.replace(base, interval=iv)
    covered = []
    for seg, truth in zip(segs, truths, strict=True):
        band = boundary_band(seg.prob, seg.mask_net, iv, spec.min_contact_area_px)
        lower, upper = band.interval(iv.widen)
        covered.append(lower * 4.0 <= truth <= upper * 4.0)
    assert np.mean(covered) >= 0.9 and iv.frames == 60 and summary["frames"] == 60
    assert iv.threshold_low < 0.5 < iv.threshold_high


def test_a_candidate_that_cannot_reach_the_level_is_null_in_standard_json() -> None:
    """A threshold pair whose looser threshold misses a faint true contact has no factor: its
    summary says so (null, ``reaches_level`` false), never ``Infinity``."""
    base = dataclasses.replace(SPEC, interval=None)
    segs = [postprocess(disk(r, 1.0), BOX, SHAPE, base) for r in (10.0, 14.0, 18.0)]
    faint = np.zeros((SIZE, SIZE), np.float32)
    faint[20:40, 20:40] = 0.2  # kept below p 0.27 (margins 0.5, 1), found from p 0.12 (2, 3)
    segs.append(postprocess(faint, BOX, SHAPE, base))
    _, summary = calibrate(segs, [s.area_px for s in segs[:3]] + [1600.0], base)
    text = json.dumps(summary, allow_nan=False)  # raises on a non-finite number
    cand = json.loads(text)["candidates"]
    for m in ("0.5", "1.0"):
        assert cand[m] == {"reaches_level": False, "widen": None, "median_rel_width": None}
    assert cand["3.0"]["reaches_level"] and cand["3.0"]["widen"] >= 0.0


def test_recalibrate_changes_only_the_interval(tmp_path: Path) -> None:
    onnx = pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train.interval import recalibrate_model

    data = write_dataset(tmp_path / "data", fingers=4)
    old = onnx.load(str(DEFAULT_MODEL))
    legacy = onnx.load(str(DEFAULT_MODEL))  # as exported before the region key existed
    meta = {p.key: p.value for p in legacy.metadata_props if p.key != "region"}
    del legacy.metadata_props[:]
    onnx.helper.set_model_props(legacy, meta)
    onnx.save(legacy, str(tmp_path / "legacy.onnx"))
    for src, model in ((DEFAULT_MODEL, old), (tmp_path / "legacy.onnx", legacy)):
        out = tmp_path / f"re-{Path(src).name}"
        summary = recalibrate_model(src, [data], out)
        new = onnx.load(str(out))
        assert new.graph.SerializeToString() == model.graph.SerializeToString()
        before = {p.key: p.value for p in model.metadata_props}
        after = {p.key: p.value for p in new.metadata_props}
        # a model without the region key gains it, with the region it was deployed with
        assert {k for k in after if after[k] != before.get(k)} <= {"interval", "region"}
        assert after.keys() == before.keys() | {"region"}
        assert after["region"] == before.get("region", "largest")
        assert json.loads(after["interval"]) == {**summary["interval"], "data": summary["data"]}
        assert OnnxSegmenter(out).spec.interval is not None
    assert "region" not in meta and after["region"] == "largest"  # the legacy path ran last
    with pytest.raises(ValueError, match="is an input of this run"):
        recalibrate_model(out, [data], out)

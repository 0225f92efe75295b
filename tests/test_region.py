"""The contact region a model states (metadata ``region``): the largest region as segmented, or
its convex hull; the contact decision is the same, the area is the hull's."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox
from contactcal.infer.methods.unet.postprocess import boundary_band, convex_region, postprocess
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter
from contactcal.infer.methods.unet.spec import (
    IntervalSpec,
    ModelError,
    ModelSpec,
    read_spec,
)

SIZE = 64
BOX = CropBox(x0=0, y0=0, side=128)  # 4 input pixels per network pixel
SHAPE = (128, 128)
SPEC = ModelSpec(1, PreprocessConfig(input_size=SIZE), 0.5, 20.0, IntervalSpec(0.9, 0.1, 0.9, 1, 9))
CONVEX = dataclasses.replace(SPEC, region="convex")


def notched_square() -> np.ndarray:
    """``(SIZE, SIZE) float32``: a 20×20 px square of p = 0.8 with a 6×10 px notch cut into
    the middle of its top edge (340 px above the threshold; its convex hull is the square)."""
    prob = np.zeros((SIZE, SIZE), np.float32)
    prob[20:40, 20:40] = 0.8
    prob[20:26, 25:35] = 0.02
    return prob


def test_convex_region_reference_values() -> None:
    keep = notched_square() >= 0.5
    assert keep.sum() == 340
    hull = convex_region(keep)
    assert hull.sum() == 400 and hull[20:40, 20:40].all() and (hull | keep).sum() == hull.sum()
    assert not convex_region(np.zeros((8, 8), bool)).any()


def test_convex_region_is_exactly_the_pixels_in_the_hull() -> None:
    import cv2

    rng = np.random.default_rng(5)
    yy, xx = np.mgrid[0:SIZE, 0:SIZE]
    for _ in range(4):  # notched ellipses: each pixel tested against the hull itself
        cx, cy, ax, ay, nx, ny = rng.uniform([20, 20, 4, 4, -6, -6], [44, 44, 18, 18, 6, 6])
        keep = ((xx - cx) / ax) ** 2 + ((yy - cy) / ay) ** 2 <= 1.0
        keep &= ~((xx > cx + nx) & (yy < cy + ny))
        hull = cv2.convexHull(cv2.findNonZero(keep.astype(np.uint8))).astype(np.float32)
        inside = [
            [cv2.pointPolygonTest(hull, (float(x), float(y)), False) >= 0 for x in range(SIZE)]
            for y in range(SIZE)
        ]
        np.testing.assert_array_equal(convex_region(keep), np.array(inside) | keep)


def test_convex_region_keeps_a_convex_region() -> None:
    yy, xx = np.mgrid[0:SIZE, 0:SIZE] - 31.5
    disk = np.hypot(xx, yy) <= 12.0
    # every pixel centre in the hull of a digitised disk's centres is in the disk (OpenCV's
    # polygon fill adds ~2 % here)
    np.testing.assert_array_equal(convex_region(disk), disk)


def test_convex_region_edge_cases() -> None:
    one = np.zeros((8, 8), bool)
    one[3, 5] = True
    np.testing.assert_array_equal(convex_region(one), one)
    line = np.zeros((8, 8), bool)
    line[np.arange(8), np.arange(8)] = True  # a diagonal from corner to corner
    np.testing.assert_array_equal(convex_region(line), line)
    corner = np.zeros((8, 8), bool)  # an L along two borders: its hull is the triangle
    corner[0, :] = True
    corner[:, 0] = True
    np.testing.assert_array_equal(
        convex_region(corner), np.add.outer(np.arange(8), np.arange(8)) <= 7
    )


def test_convex_postprocess_measures_the_hull() -> None:
    prob = notched_square()
    largest, convex = postprocess(prob, BOX, SHAPE, SPEC), postprocess(prob, BOX, SHAPE, CONVEX)
    assert largest.contact and convex.contact
    assert largest.area_px == 340 * 4.0 and convex.area_px == 400 * 4.0
    assert convex.region_net_px == largest.region_net_px == 340.0  # decided on the segmented one
    assert convex.mask_net.sum() == 400
    # hull pixels count whole in the soft area: 340 px at p = 0.8 + 60 hull px as 1 (p = 0 around)
    assert convex.soft_area_px == pytest.approx((340 * 0.8 + 60) * 4.0, rel=1e-6)
    lower, upper = convex.interval_px
    assert 0.0 <= lower <= convex.area_px <= upper


def test_band_loose_joins_the_components_the_hull_touches() -> None:
    prob = notched_square()
    prob[17:24, 29:31] = 0.3  # a faint streak (14 px) from above into the notch, detached at 0.1
    iv = CONVEX.interval
    largest = postprocess(prob, BOX, SHAPE, SPEC)
    assert boundary_band(prob, largest.mask_net, iv, 20.0).loose == 340.0  # the square only
    hull = postprocess(prob, BOX, SHAPE, CONVEX).mask_net
    assert hull.sum() == 400
    # the hull, the streak's 6 px outside it: the square's component, the whole streak, and the
    # 52 notch pixels that lie in no component
    assert boundary_band(prob, hull, iv, 20.0).loose == 406.0


def test_convex_region_does_not_change_the_contact_decision() -> None:
    prob = np.zeros((SIZE, SIZE), np.float32)
    prob[10:14, 10:14] = 0.9  # 16 px < the minimum area 20
    prob[14:18, 14:18] = 0.9  # a second touching block: a thin diagonal region of 32 px
    small = dataclasses.replace(CONVEX, min_contact_area_px=40.0)
    assert not postprocess(prob, BOX, SHAPE, small).contact
    seg = postprocess(prob, BOX, SHAPE, CONVEX)
    assert seg.contact and seg.region_net_px == 32.0 and seg.mask_net.sum() > 32


def _metadata() -> dict[str, str]:
    return dict(OnnxSegmenter().metadata)


def test_region_metadata_round_trip_and_default() -> None:
    meta = {**_metadata(), **CONVEX.to_metadata()}
    assert meta["region"] == "convex" and read_spec(meta, "m.onnx").region == "convex"
    del meta["region"]  # a model exported before the key existed
    assert read_spec(meta, "m.onnx").region == "largest"


def test_region_must_be_known() -> None:
    meta = {**_metadata(), "region": "ellipse"}
    with pytest.raises(ModelError, match="m.onnx.*region must be one of largest, convex"):
        read_spec(meta, "m.onnx")
    with pytest.raises(ValueError, match="region"):
        dataclasses.replace(SPEC, region="hull")


def test_recalibrate_states_the_region(tmp_path: Path) -> None:
    onnx = pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train.interval import main, recalibrate_model

    data = write_dataset(tmp_path / "data", fingers=4)
    proto = onnx.load(str(DEFAULT_MODEL))
    meta = {p.key: p.value for p in proto.metadata_props if p.key != "region"}
    del proto.metadata_props[:]
    onnx.helper.set_model_props(proto, meta)
    legacy = tmp_path / "legacy.onnx"  # exported before the region key existed
    onnx.save(proto, str(legacy))
    for region, expected in ((None, "largest"), ("convex", "convex"), ("largest", "largest")):
        out = tmp_path / f"{expected}-{region}.onnx"
        summary = recalibrate_model(legacy, [data], out, region=region)
        new = onnx.load(str(out))
        after = {p.key: p.value for p in new.metadata_props}
        assert new.graph.SerializeToString() == proto.graph.SerializeToString()
        assert after["region"] == summary["region"] == expected
        assert json.loads(after["interval"]) == {**summary["interval"], "data": summary["data"]}
        assert OnnxSegmenter(out).spec.region == expected
    with pytest.raises(ValueError, match="legacy.onnx: region must be one of"):
        recalibrate_model(legacy, [data], tmp_path / "x.onnx", region="hull")
    bad = tmp_path / "y.onnx"
    with pytest.raises(SystemExit) as exc:
        main([str(legacy), "--data", str(data), "--out", str(bad), "--region", "hull"])
    assert exc.value.code == 2 and not bad.exists()

"""Network preprocessing: ring search, crop/resize, normalisation and the inverse mapping."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from procedural import draw_frame

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import (
    CropBox,
    crop_box,
    crop_resize,
    from_network,
    valid_window,
)
from contactcal.infer.methods.unet.prepare import (
    network_to_unit,
    prepare,
    session_reference,
    to_network,
    unit_to_network,
)
from contactcal.infer.methods.unet.ring import RingFit, locate_ring
from contactcal.infer.methods.unet.runner import sigmoid

W, H = 324, 243  # half the procedural default: fast, ring radius 0.42·H ≈ 102 px


def _frame(rng: np.random.Generator, **kw: object) -> np.ndarray:
    return draw_frame(rng, width=W, height=H, semi_axes_px=(30.0, 22.0), **kw).image


def test_prepare_shapes(rng: np.random.Generator) -> None:
    cfg = PreprocessConfig(input_size=64)
    img = _frame(rng)
    one = prepare(img, session_reference(None, cfg), cfg, channels=1)
    two = prepare(img, session_reference(_frame(rng), cfg), cfg, channels=2)
    assert one.x.shape == (1, 64, 64) and one.x.dtype == np.float32
    assert two.x.shape == (2, 64, 64) and two.x.dtype == np.float32
    assert np.all(np.isfinite(two.x))
    assert two.box == crop_box(two.ring, img.shape, cfg)


@pytest.mark.parametrize("gain", [0.5, 1.0, 1.5])
def test_ring_located_under_exposure(rng: np.random.Generator, gain: float) -> None:
    img = np.clip(np.rint(_frame(rng) * gain), 0, 255).astype(np.uint8)
    ring = locate_ring(img)
    assert ring.found
    assert abs(ring.cx - (W - 1) / 2) < 2.0 and abs(ring.cy - (H - 1) / 2) < 2.0
    # outer edge of the procedural ring: centre line 0.42·H plus its half width
    assert 0.42 * H < ring.radius < 0.42 * H + 0.04 * H


def test_ring_cut_by_border(rng: np.random.Generator) -> None:
    img = _frame(rng)
    shifted = np.zeros_like(img)
    shifted[:, 40:] = img[:, :-40]  # ring centre moves 40 px right, its right side leaves view
    ring = locate_ring(shifted[:, : W - 20])
    assert ring.found and abs(ring.cx - ((W - 1) / 2 + 40)) < 3.0


def test_no_ring_falls_back(rng: np.random.Generator) -> None:
    noise = np.clip(rng.normal(20.0, 3.0, (H, W)), 0, 255).astype(np.uint8)
    for img in (noise, np.zeros((H, W), np.uint8), np.full((H, W), 200, np.uint8)):
        ring = locate_ring(img)
        assert not ring.found
        assert ring.cx == pytest.approx((W - 1) / 2) and ring.radius == pytest.approx(0.45 * H)
        assert prepare(img, session_reference(None), PreprocessConfig(), 1).x.shape == (1, 256, 256)


def test_blob_only_is_not_a_ring(rng: np.random.Generator) -> None:
    img = np.full((H, W), 20, np.uint8)
    cv2.ellipse(img, (W // 2, H // 2), (30, 20), 15, 0, 360, 200, -1)
    assert not locate_ring(img).found


def test_round_trip_iou() -> None:
    cfg = PreprocessConfig()
    mask = np.zeros((486, 648), np.uint8)
    cv2.ellipse(mask, (300, 250), (70, 45), 25, 0, 360, 1, -1)
    box = crop_box(RingFit(323.5, 242.5, 209.0), mask.shape, cfg)
    net = crop_resize(mask.astype(np.float32), box, cfg.input_size)
    back = from_network(net, box, mask.shape) > 0.5
    truth = mask > 0
    iou = (back & truth).sum() / (back | truth).sum()
    assert iou > 0.97


def test_round_trip_box_outside_image() -> None:
    mask = np.zeros((100, 120), np.float32)
    mask[10:40, 5:50] = 1.0
    box = CropBox(-30, -20, 160)  # extends past every border
    back = from_network(crop_resize(mask, box, 256), box, mask.shape) > 0.5
    assert ((back & (mask > 0)).sum() / (back | (mask > 0)).sum()) > 0.97


def test_affine_maps_pixel_centres() -> None:
    box = CropBox(10, 20, 200)
    m = box.to_network_affine(100)
    # input pixel centre x = x0 + (u + 0.5)·side/S - 0.5 ↔ network u
    u = 7.0
    x = box.x0 + (u + 0.5) * 2.0 - 0.5
    assert m[0, 0] * x + m[0, 2] == pytest.approx(u)


def test_normalisation_is_exposure_invariant(rng: np.random.Generator) -> None:
    img = _frame(rng, noise_sd=0.0)
    box = crop_box(locate_ring(img), img.shape)
    a = to_network(img, box)
    b = to_network(np.clip(np.rint(img * 0.6), 0, 255).astype(np.uint8), box)
    assert np.median(np.abs(a - b)) < 0.05


def test_in_place_normalisation_equals_the_plain_expression(rng: np.random.Generator) -> None:
    """``to_network`` works in place; bit for bit it is unit_to_network(clip(crop / P, 0, 1))."""
    gray = _frame(rng)
    cfg = PreprocessConfig(input_size=96)
    box = crop_box(locate_ring(gray, cfg), gray.shape, cfg)
    crop = crop_resize(gray, box, cfg.input_size)
    inside = crop[valid_window(box, gray.shape, cfg.input_size)]
    level = max(float(np.percentile(inside, cfg.norm_percentile)), 1.0)
    expected = unit_to_network(np.clip(crop / level, 0.0, 1.0), cfg).astype(np.float32)
    got = to_network(gray, box, cfg)
    assert got.dtype == np.float32 and np.array_equal(got, expected)


def _contrast(img: np.ndarray, c: float) -> np.ndarray:
    """The robustness suite's contrast about mid grey, ``128 + c·(g − 128)``, clipped."""
    return np.clip(np.rint(128.0 + c * (img.astype(np.float64) - 128.0)), 0, 255).astype(np.uint8)


def test_dark_floor_makes_the_input_contrast_invariant(rng: np.random.Generator) -> None:
    """With ``norm_floor_percentile`` the frame channel and the ridge channel of a frame at
    contrast 0.75 are those of the frame (up to the grey levels' rounding); without, they are
    not. Bit for bit it is ``unit_to_network(clip((crop - F) / (P - F), 0, 1))``."""
    img = _frame(rng, noise_sd=0.0)
    floored = PreprocessConfig(input_size=96, norm_floor_percentile=1.0, ridge_work_px=144)
    plain = PreprocessConfig(input_size=96, ridge_work_px=144)
    diffs = {}
    for name, cfg in (("floor", floored), ("plain", plain)):
        a = prepare(img, session_reference(img, cfg), cfg, 3).x
        low = _contrast(img, 0.75)
        b = prepare(low, session_reference(low, cfg), cfg, 3).x
        # frame channel: median |difference|; ridge channel: its total energy's ratio
        diffs[name] = (float(np.median(np.abs(a[0] - b[0]))), float(b[2].sum() / a[2].sum()))
    assert diffs["floor"][0] < 1e-3 and diffs["plain"][0] > 0.3, diffs
    assert abs(diffs["floor"][1] - 1.0) < 0.02 and diffs["plain"][1] < 0.9, diffs
    box = crop_box(locate_ring(img, floored), img.shape, floored)
    crop = crop_resize(img, box, floored.input_size)
    inside = crop[valid_window(box, img.shape, floored.input_size)]
    f, p = (float(v) for v in np.percentile(inside, [1.0, floored.norm_percentile]))
    expected = unit_to_network(np.clip((crop - f) / (p - f), 0.0, 1.0), floored)
    np.testing.assert_allclose(to_network(img, box, floored), expected, atol=1e-6)
    with pytest.raises(ValueError, match="norm_floor_percentile"):
        PreprocessConfig(norm_floor_percentile=99.5)


def test_sigmoid_equals_the_plain_expression(rng: np.random.Generator) -> None:
    logits = rng.normal(0.0, 20.0, (64, 64)).astype(np.float32)
    before = logits.copy()
    expected = (1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))).astype(np.float32)
    got = sigmoid(logits)
    assert got.dtype == np.float32 and np.array_equal(got, expected)
    assert np.array_equal(logits, before)  # a new array: the caller's logits are kept


def test_unit_mapping_inverts() -> None:
    cfg = PreprocessConfig()
    u = np.linspace(0, 1, 11)
    np.testing.assert_allclose(network_to_unit(unit_to_network(u, cfg), cfg), u)


def test_bad_input_raises(rng: np.random.Generator) -> None:
    nan = np.full((H, W), np.nan, np.float32)
    with pytest.raises(ValueError, match="NaN"):
        prepare(nan, session_reference(None), PreprocessConfig(), 1)
    with pytest.raises(ValueError, match="expected"):
        prepare(np.zeros((2, 3, 4, 5), np.uint8), session_reference(None), PreprocessConfig(), 1)
    with pytest.raises(ValueError, match="expected"):
        locate_ring(np.zeros(10, np.uint8))
    with pytest.raises(ValueError, match="reference"):
        bad_ref = session_reference(np.zeros((10, 10), np.uint8))
        prepare(_frame(rng), bad_ref, PreprocessConfig(), 2)
    with pytest.raises(ValueError, match="square"):
        from_network(np.zeros((4, 5), np.float32), CropBox(0, 0, 4), (4, 4))
    with pytest.raises(ValueError, match="input_size"):
        PreprocessConfig(input_size=0)


def test_ring_radius_is_bounded() -> None:
    # A bright arc of a circle far larger than the image (nearly straight): its fitted radius is
    # ~5000 px, which would make a crop of ~11000 px side; it is not accepted as the ring.
    h, w = 120, 1000
    yy, xx = np.mgrid[0:h, 0:w]
    r = np.hypot(xx - w / 2, yy - 5060.0)
    img = np.where(np.abs(r - 5000.0) < 6, 220, 20).astype(np.uint8)
    ring = locate_ring(img)
    assert not ring.found and ring.radius <= max(h, w)


def test_metadata_without_the_floor_reads_as_none_and_with_it_round_trips() -> None:
    """The shipped model predates ``norm_floor_percentile``: read as 0 (what it was deployed
    with); a restated value reads back; an unknown preprocess key is still an error."""
    import dataclasses
    import json

    from contactcal.infer.methods.unet.runner import OnnxSegmenter
    from contactcal.infer.methods.unet.spec import ModelError, read_spec

    meta = dict(OnnxSegmenter().metadata)
    assert "norm_floor_percentile" not in json.loads(meta["preprocess"])
    spec = read_spec(meta, "m.onnx")
    assert spec.preprocess.norm_floor_percentile == 0.0
    floored = dataclasses.replace(
        spec, preprocess=dataclasses.replace(spec.preprocess, norm_floor_percentile=1.0)
    )
    assert read_spec({**meta, **floored.to_metadata()}, "m.onnx") == floored
    extra = {**json.loads(meta["preprocess"]), "norm_floor": 1.0}
    with pytest.raises(ModelError, match="unknown key"):
        read_spec({**meta, "preprocess": json.dumps(extra)}, "m.onnx")

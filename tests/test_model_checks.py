"""A model file is checked before it is trusted: metadata values, graph input and output; and a
crop with no network pixel inside the image measures nothing (never more than the image)."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from unreadable_json import UNREADABLE_JSON

from contactcal.infer.cli import main
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import CropBox, valid_window
from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.infer.methods.unet.prepare import to_network
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter, static_dims
from contactcal.infer.methods.unet.spec import ModelError, ModelSpec

FRAME = Path(__file__).resolve().parents[1] / "examples" / "session" / "p05.0kpa.jpg"


def _measure(model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    out = tmp_path / "results.json"
    code = main(["measure", str(FRAME), "--model", str(model), "--out", str(out)])
    assert not out.exists(), "a rejected model must not produce results"
    return code, capsys.readouterr().err


def test_nan_min_area_in_a_real_model_is_rejected(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    onnx = pytest.importorskip("onnx")
    proto = onnx.load(str(DEFAULT_MODEL))
    for prop in proto.metadata_props:
        if prop.key == "min_contact_area_px":
            prop.value = "nan"
    path = tmp_path / "nan_area.onnx"
    onnx.save(proto, str(path))
    with pytest.raises(ModelError, match="min_contact_area_px"):
        OnnxSegmenter(path)
    code, err = _measure(path, tmp_path, capsys)
    assert code == 2 and str(path) in err and "min_contact_area_px" in err
    assert len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("key", ["interval", "min_change"])
@pytest.mark.parametrize("text", UNREADABLE_JSON.values(), ids=UNREADABLE_JSON.keys())
def test_metadata_json_no_reader_takes_is_one_line_naming_the_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str, text: str
) -> None:
    """A metadata entry in JSON no reader takes (an integer over the digit limit, deep nesting)
    is invalid metadata (was a line without the file, or a RecursionError traceback)."""
    onnx = pytest.importorskip("onnx")
    proto = onnx.load(str(DEFAULT_MODEL))
    onnx.helper.set_model_props(
        proto, {**{p.key: p.value for p in proto.metadata_props}, key: text}
    )
    path = tmp_path / "unreadable.onnx"
    onnx.save(proto, str(path))
    code, err = _measure(path, tmp_path, capsys)
    assert code == 2 and err.startswith(
        f"contactcal: error: --model {path}: invalid model metadata: "
    )
    assert err.count("\n") == 1, err[:300]


def test_model_without_interval_is_one_clear_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    onnx = pytest.importorskip("onnx")
    proto = onnx.load(str(DEFAULT_MODEL))
    keep = [p for p in proto.metadata_props if p.key != "interval"]
    assert len(keep) == len(proto.metadata_props) - 1  # the shipped model states one
    del proto.metadata_props[:]
    proto.metadata_props.extend(keep)
    path = tmp_path / "no_interval.onnx"
    onnx.save(proto, str(path))
    with pytest.raises(ModelError, match="lacks key.*interval"):
        OnnxSegmenter(path)
    code, err = _measure(path, tmp_path, capsys)
    assert code == 2 and str(path) in err and "interval" in err and "re-export" in err
    assert len(err.strip().splitlines()) == 1, err


def _identity_model(path: Path, channels_in: int, channels_meta: int) -> Path:
    """A valid ONNX graph (Identity) with otherwise valid contactcal metadata."""
    onnx = pytest.importorskip("onnx")
    helper = onnx.helper
    shape = ["batch", channels_in, "height", "width"]
    graph = helper.make_graph(
        [helper.make_node("Identity", ["input"], ["logits"])],
        "identity",
        [helper.make_tensor_value_info("input", onnx.TensorProto.FLOAT, shape)],
        [helper.make_tensor_value_info("logits", onnx.TensorProto.FLOAT, shape)],
    )
    proto = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    proto.ir_version = 8  # readable by every supported onnxruntime
    shipped = onnx.load(str(DEFAULT_MODEL))
    meta = {p.key: p.value for p in shipped.metadata_props}
    meta["channels"] = str(channels_meta)
    meta.pop("min_change", None)  # the shipped change gate needs a reference channel
    helper.set_model_props(proto, meta)
    onnx.save(proto, str(path))
    return path


def test_wrong_input_channels_is_one_clear_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _identity_model(tmp_path / "rgb.onnx", channels_in=3, channels_meta=2)
    with pytest.raises(ModelError, match=r"expected one float input of shape \(N, 2, "):
        OnnxSegmenter(path)
    code, err = _measure(path, tmp_path, capsys)
    assert code == 2 and str(path) in err and "input" in err
    assert len(err.strip().splitlines()) == 1, err


def test_wrong_output_channels_is_rejected(tmp_path: Path) -> None:
    path = _identity_model(tmp_path / "two_out.onnx", channels_in=2, channels_meta=2)
    with pytest.raises(ModelError, match=r"expected one float output of shape \(N, 1, "):
        OnnxSegmenter(path)


def _dynamic_output_model(path: Path, pool: bool) -> Path:
    """A two-channel model whose output shape onnxruntime cannot infer before a run: the input
    itself (two channels) or its channel mean max-pooled to half the size."""
    onnx = pytest.importorskip("onnx")
    helper = onnx.helper
    nodes = [
        helper.make_node("Shape", ["input"], ["shape"]),  # Reshape to a runtime shape hides it
        helper.make_node("Reshape", ["input", "shape"], ["same" if pool else "logits"]),
    ]
    if pool:
        nodes += [
            helper.make_node("ReduceMean", ["same"], ["mean"], axes=[1], keepdims=1),
            helper.make_node("MaxPool", ["mean"], ["logits"], kernel_shape=[2, 2], strides=[2, 2]),
        ]
    graph = helper.make_graph(
        nodes,
        "dynamic",
        [helper.make_tensor_value_info("input", onnx.TensorProto.FLOAT, ["n", 2, "h", "w"])],
        [helper.make_tensor_value_info("logits", onnx.TensorProto.FLOAT, None)],
    )
    proto = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    proto.ir_version = 8
    meta = {p.key: p.value for p in onnx.load(str(DEFAULT_MODEL)).metadata_props}
    meta["channels"] = "2"
    meta.pop("min_change", None)
    helper.set_model_props(proto, meta)
    onnx.save(proto, str(path))
    return path


@pytest.mark.parametrize(("pool", "got"), [(False, "(1, 2, S, S)"), (True, "(1, 1, H, H)")])
def test_wrong_output_shape_at_run_time_is_one_clear_line(
    pool: bool, got: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _dynamic_output_model(tmp_path / "dynamic.onnx", pool)
    s = OnnxSegmenter().spec.preprocess.input_size  # the metadata is the shipped model's
    got = got.replace("S", str(s)).replace("H", str(s // 2))
    net = OnnxSegmenter(path)
    x = np.zeros((net.spec.channels, s, s), np.float32)
    with pytest.raises(ModelError, match=re.escape(f"(1, 1, {s}, {s})") + ".*" + re.escape(got)):
        net.probabilities(x)
    code, err = _measure(path, tmp_path, capsys)
    assert code == 2 and str(path) in err and got in err
    assert len(err.strip().splitlines()) == 1, err


def test_shipped_model_passes_the_graph_check() -> None:
    spec = OnnxSegmenter().spec
    ridge = spec.preprocess.ridge_work_px > 0
    assert spec.channels == 1 + int(spec.uses_reference) + int(ridge)


def test_crop_without_network_pixel_in_the_image_measures_nothing() -> None:
    shape = (10, 10)
    size = 64
    box = CropBox(x0=-999, y0=-999, side=1000)  # overlaps the image by one pixel
    rows, cols = valid_window(box, shape, size)
    assert rows.stop - rows.start == 0 and cols.stop - cols.start == 0
    spec = ModelSpec(1, PreprocessConfig(input_size=size), 0.5, 0.0)
    seg = postprocess(np.ones((size, size), np.float32), box, shape, spec)
    assert not seg.contact and seg.area_px == 0.0 and seg.soft_area_px == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "mean of empty slice" or NaN on the way
        x = to_network(np.full(shape, 200, np.uint8), box, spec.preprocess)
    assert x.shape == (size, size) and np.all(np.isfinite(x))


def test_crop_partly_outside_counts_only_pixels_inside() -> None:
    shape = (40, 40)
    box = CropBox(x0=20, y0=20, side=64)  # a quarter of the crop lies inside the image
    spec = ModelSpec(1, PreprocessConfig(input_size=32), 0.5, 0.0)
    seg = postprocess(np.ones((32, 32), np.float32), box, shape, spec)
    assert seg.contact and 0.0 < seg.area_px <= shape[0] * shape[1]


#: Logits of one graph run with free and with fixed input dimensions differ by float rounding
#: only (onnxruntime picks other kernels once the shapes are known).
STATIC_DIMS_ATOL = 1e-4


def test_static_dims_fixes_named_dimensions_only() -> None:
    spec = OnnxSegmenter().spec
    s, c = spec.preprocess.input_size, spec.channels
    assert static_dims(["batch", c, "height", "width"], spec) == {
        "batch": 1,
        "height": s,
        "width": s,
    }
    assert static_dims([1, c, s, s], spec) == {}
    assert static_dims([None, c, "", "w"], spec) == {"w": s}


def test_deployed_session_runs_the_input_shape_it_is_fed() -> None:
    ort = pytest.importorskip("onnxruntime")
    seg = OnnxSegmenter()
    s, c = seg.spec.preprocess.input_size, seg.spec.channels
    assert seg.ort_session.get_inputs()[0].shape == [1, c, s, s]
    free = ort.InferenceSession(str(DEFAULT_MODEL), providers=["CPUExecutionProvider"])
    assert free.get_inputs()[0].shape == ["batch", c, "height", "width"]  # the file is dynamic
    x = np.random.default_rng(3).normal(size=(1, c, s, s)).astype(np.float32)
    got = seg.ort_session.run(None, {seg.input_name: x})[0]
    want = free.run(None, {free.get_inputs()[0].name: x})[0]
    assert got.shape == want.shape == (1, 1, s, s)
    np.testing.assert_allclose(got, want, atol=STATIC_DIMS_ATOL, rtol=0)


EXAMPLE = FRAME.parent


@pytest.mark.parametrize(
    "argv",
    [
        ["measure", str(FRAME), "--reference", str(EXAMPLE / "p00.0kpa.jpg"), "--out", "out.json"],
        ["calibrate", str(EXAMPLE / "manifest.csv"), "--out", "out"],
        [
            "evaluate",
            str(EXAMPLE / "manifest.csv"),
            "--labels",
            str(EXAMPLE / "masks"),
            "--out",
            "out",
        ],
    ],
    ids=["measure", "calibrate", "evaluate"],
)
def test_an_unusable_model_is_named_by_its_option(
    argv: list[str],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A missing --model, a folder, or a file that is not a model, names the option as typed (as
    bench and every --out refusal do), not only the file."""
    monkeypatch.chdir(tmp_path)
    Path("notes.onnx").write_text("not a model\n")
    Path("models").mkdir()
    cases = (
        ("missing.onnx", "no such model file"),
        ("models", "is a folder; expected the ONNX model file"),
        ("notes.onnx", "not a loadable ONNX model ("),
    )
    for model, says in cases:
        assert main([*argv, "--model", model]) == 2
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert err.startswith(f"contactcal: error: --model {model}: {says}"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["models", "notes.onnx"]  # nothing written

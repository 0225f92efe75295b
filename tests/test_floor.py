"""``python -m contactcal.train.floor``: a model's dark floor restated, weights untouched."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter


def test_floor_is_restated_and_read_back(tmp_path: Path) -> None:
    onnx = pytest.importorskip("onnx")
    from contactcal.train.floor import floor_model, main

    out = tmp_path / "f1.onnx"
    summary = floor_model(DEFAULT_MODEL, 1.0, out)
    assert summary["norm_floor_percentile"] == 1.0 and summary["before"] == 0.0
    seg = OnnxSegmenter(out)
    assert seg.spec.preprocess.norm_floor_percentile == 1.0
    base = OnnxSegmenter().spec
    assert seg.spec.preprocess.input_size == base.preprocess.input_size
    assert seg.spec.min_change == base.min_change and seg.spec.interval == base.interval
    weights = [
        {i.name: i.raw_data for i in onnx.load(str(p)).graph.initializer}
        for p in (DEFAULT_MODEL, out)
    ]
    assert weights[0] == weights[1]
    with pytest.raises(ValueError, match="is an input of this run"):
        floor_model(out, 5.0, out)
    assert (
        main([str(DEFAULT_MODEL), "--percentile", "99.5", "--out", str(tmp_path / "x.onnx")]) == 2
    )
    assert not (tmp_path / "x.onnx").exists()


def test_a_new_floor_says_the_calibrated_entries_are_stale(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The interval and the change gate were calibrated on the old inputs: the summary and a
    warning line say so and what to rerun, gate first; nothing stale when nothing changed."""
    onnx = pytest.importorskip("onnx")
    from contactcal.train.floor import floor_model, main

    out = tmp_path / "f1.onnx"
    assert main([str(DEFAULT_MODEL), "--percentile", "1", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    stale = json.loads(captured.out[: captured.out.rindex("wrote ")])["stale"]
    assert stale.startswith(
        "the change gate (min_change) and the area interval (interval) were calibrated before "
        f"this change and are kept as before; rerun `python -m contactcal.train.change_gate {out} "
    )
    assert stale.index("train.change_gate") < stale.index("train.interval")
    assert captured.err == f"warning: {out}: {stale}\n"
    assert floor_model(DEFAULT_MODEL, 0.0, tmp_path / "f0.onnx")["stale"] is None
    proto = onnx.load(str(DEFAULT_MODEL))  # a model without a change gate
    meta = {p.key: p.value for p in proto.metadata_props if p.key != "min_change"}
    del proto.metadata_props[:]
    onnx.helper.set_model_props(proto, meta)
    onnx.save(proto, str(tmp_path / "ungated.onnx"))
    stale = floor_model(tmp_path / "ungated.onnx", 1.0, tmp_path / "g1.onnx")["stale"]
    assert stale.startswith("the area interval (interval) was calibrated before this change")


def test_floor_names_the_option_it_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from contactcal.train.floor import main

    out = tmp_path / "x.onnx"
    assert main([str(DEFAULT_MODEL), "--percentile", "99.5", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --percentile 99.5: norm_floor_percentile must be in [0, ")
    assert err.count("\n") == 1 and not out.exists()
    folder = tmp_path / "folder.onnx"
    folder.mkdir()
    (tmp_path / "x.txt").write_text("a file")
    model = tmp_path / "m.onnx"
    model.write_bytes(DEFAULT_MODEL.read_bytes())
    for bad, says in (
        (tmp_path / "x.txt", "expected an output file name ending in .onnx"),
        (folder, "exists and is not a regular file"),
        (tmp_path / "x.txt" / "x.onnx", f"{tmp_path / 'x.txt'}: is not a folder"),
        (model, "is an input of this run"),
    ):
        assert main([str(model), "--percentile", "1", "--out", str(bad)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: --out {bad}: {says}") and err.count("\n") == 1, err


def test_floor_refuses_a_file_that_is_not_a_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not an ONNX file: one line on stderr naming it, exit 2, nothing written (it was a
    protobuf DecodeError traceback)."""
    pytest.importorskip("onnx")
    from contactcal.train.floor import main

    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"garbage")
    out = tmp_path / "f1.onnx"
    assert main([str(bad), "--percentile", "1", "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"error: {bad}: not a readable ONNX model")
    assert captured.err.count("\n") == 1
    assert not out.exists()


def test_train_option_sets_the_floor_the_cache_and_the_export_use() -> None:
    """``contactcal train --norm-floor F`` trains on floored inputs: the spec that the cache,
    validation and export read carries F; an out-of-range F is refused before training."""
    import argparse

    pytest.importorskip("torch")
    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser(prog="contactcal")
    add_parsers(parser.add_subparsers(dest="command", required=True))
    base = ["train", "--data", "a", "--out", "r", "--input-size", "64"]
    assert build_config(parser.parse_args(base)).spec().preprocess.norm_floor_percentile == 0.0
    spec = build_config(parser.parse_args([*base, "--norm-floor", "1"])).spec()
    assert spec.preprocess.norm_floor_percentile == 1.0
    assert spec.preprocess.input_size == 64
    with pytest.raises(ValueError, match="--norm-floor 99.5: norm_floor_percentile must be in"):
        build_config(parser.parse_args([*base, "--norm-floor", "99.5"]))

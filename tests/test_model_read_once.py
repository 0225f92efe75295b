"""The U-Net's model file is read once: both onnxruntime sessions and the ``model_sha256`` a
record states come from that content, so a model replaced during a run (a re-export into the
same path) is neither half loaded nor recorded as the model that ran."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any, BinaryIO

import pytest

from contactcal.infer.files import regular
from contactcal.infer.files.digest import sha256_file
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

ort = pytest.importorskip("onnxruntime")


def test_a_model_replaced_while_loading_is_loaded_and_recorded_as_first_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    model = tmp_path / "model.onnx"
    shutil.copyfile(DEFAULT_MODEL, model)
    loaded = sha256_file(model)
    real = ort.InferenceSession

    def session_then_replace(*args: object, **kwargs: object) -> object:
        out = real(*args, **kwargs)
        model.write_bytes(b"not a model any more")  # replaced right after each session
        return out

    monkeypatch.setattr(ort, "InferenceSession", session_then_replace)
    method = UnetMethod(model)  # once read by path, the second session was this garbage
    assert method.describe()["model_sha256"] == loaded != sha256_file(model)


def test_a_model_that_cannot_be_read_is_one_model_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from contactcal.infer.methods.unet.spec import ModelError

    model = tmp_path / "model.onnx"
    shutil.copyfile(DEFAULT_MODEL, model)

    real_open = os.open

    def refused(path: str | os.PathLike[str], *args: object, **kwargs: object) -> int:
        if Path(path) == model:  # as for a file this user may not read (root reads any)
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(os, "open", refused)
    with pytest.raises(
        ModelError, match=r"model\.onnx: cannot read the model \(Permission denied\)"
    ):
        UnetMethod(model)


def _replaced_after_each_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of the shipped model that turns to junk right after each read of it (a re-export
    into the same path, half done): after each ``Path.read_bytes``, and after each opening by
    the shared reader every input goes through (:func:`~contactcal.infer.files.regular.open_input`,
    behind ``read_input_bytes``: the file opened is replaced, so that reading goes on)."""
    model = tmp_path / "model.onnx"
    shutil.copyfile(DEFAULT_MODEL, model)
    junk = tmp_path / "junk.onnx"

    def replace_model() -> None:
        junk.write_bytes(b"not a model any more")
        os.replace(junk, model)

    real_read, real_open = Path.read_bytes, regular.open_input

    def read_then_replace(self: Path) -> bytes:
        content = real_read(self)
        if self == model:
            replace_model()
        return content

    def open_then_replace(path: str | os.PathLike[str], *args: Any) -> BinaryIO:
        opened = real_open(path, *args)
        if Path(path) == model:
            replace_model()
        return opened

    monkeypatch.setattr(Path, "read_bytes", read_then_replace)
    monkeypatch.setattr(regular, "open_input", open_then_replace)
    return model


def _restated_only(out: Path, key: str) -> dict[str, str]:
    """The metadata of the model written to ``out``, asserted to be the shipped model's graph
    and metadata with only ``key`` restated (the content first read, not the junk after it)."""
    import onnx

    new, src = onnx.load(str(out)), onnx.load(str(DEFAULT_MODEL))
    assert new.graph.SerializeToString() == src.graph.SerializeToString()
    meta = {p.key: p.value for p in new.metadata_props}
    assert meta == {**{p.key: p.value for p in src.metadata_props}, key: meta[key]}
    return meta


def test_the_change_gate_measures_and_rewrites_the_model_as_first_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train.change_gate import gate_model

    data = write_dataset(tmp_path / "data", fingers=2)
    model, out = _replaced_after_each_read(tmp_path, monkeypatch), tmp_path / "gated.onnx"
    summary = gate_model(model, [data], out, draws=1)  # once read again: a ModelError
    _restated_only(out, "min_change")
    assert summary["min_change"] > 0.0


def test_the_interval_measures_and_rewrites_the_model_as_first_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("onnx")
    from procedural import write_dataset

    from contactcal.train.interval import recalibrate_model

    data = write_dataset(tmp_path / "data", fingers=2)
    model, out = _replaced_after_each_read(tmp_path, monkeypatch), tmp_path / "recalibrated.onnx"
    summary = recalibrate_model(model, [data], out)  # once read again: a ValueError
    meta = _restated_only(out, "interval")
    assert json.loads(meta["interval"]) == {**summary["interval"], "data": summary["data"]}

"""The U-Net's model file is read once: both onnxruntime sessions and the ``model_sha256`` a
record states come from that content, so a model replaced during a run (a re-export into the
same path) is neither half loaded nor recorded as the model that ran."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

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

    def refused(self: Path) -> bytes:
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "read_bytes", refused)
    with pytest.raises(
        ModelError, match=r"model\.onnx: cannot read the model \(Permission denied\)"
    ):
        UnetMethod(model)

"""``calibrate --video | --camera`` loads the U-Net before the recording is opened, from one read
of its model file: a bad ``--model`` is refused in one line before any frame is read and nothing
is written (it was refused only after the whole recording had been read and its frames
extracted), and the calibration and the preview are built from that one read."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from read_counts import count_reads
from test_video import make_log, make_video

from contactcal.infer.cli import main
from contactcal.infer.files.digest import sha256_file
from contactcal.infer.methods.unet import runner
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

KPAS = [0, 5, 10]


@pytest.fixture
def recording(tmp_path: Path, rng: np.random.Generator) -> list[str]:
    """``--video V --pressure-log LOG`` of a short synthetic recording."""
    make_video(tmp_path / "v.avi", KPAS)
    make_log(tmp_path / "log.csv", KPAS, rng)
    return ["--video", str(tmp_path / "v.avi"), "--pressure-log", str(tmp_path / "log.csv")]


def _unreachable(*args: object) -> None:
    raise AssertionError(f"the recording was opened: {args}")


@pytest.mark.parametrize("source", ["video", "video+preview", "camera"])  # camera: a preview
@pytest.mark.parametrize("model", ["typo.onnx", "junk.onnx"])
def test_a_bad_model_is_refused_before_the_recording_is_opened(
    tmp_path: Path,
    recording: list[str],
    source: str,
    model: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    (tmp_path / "junk.onnx").write_bytes(b"not a model")
    expected = {"typo.onnx": "no such model file", "junk.onnx": "not a loadable ONNX model"}
    given = {
        "video": recording,
        "video+preview": [*recording, "--preview"],
        "camera": ["--camera", "0", *recording[2:]],
    }[source]
    out = tmp_path / "out"
    argv = ["calibrate", *given, "--model", str(tmp_path / model), "--out", str(out)]
    monkeypatch.setattr(cv2, "VideoCapture", _unreachable)  # the video or the camera
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"--model {tmp_path / model}: {expected[model]}" in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("options", "read"),
    [
        (["--model", "MODEL", "--preview"], "MODEL"),  # the calibration's and the preview's U-Net
        (["--model", "MODEL"], "MODEL"),
        (["--method", "classical"], None),  # no U-Net runs
        (["--method", "classical", "--preview"], "SHIPPED"),  # the preview's outline only
        (["--method", "classical", "--preview", "--model", "MODEL"], "MODEL"),  # was refused
    ],
)
def test_the_model_is_read_once_and_only_where_a_unet_runs(
    tmp_path: Path,
    recording: list[str],
    options: list[str],
    read: str | None,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    model = tmp_path / "model.onnx"
    model.write_bytes(DEFAULT_MODEL.read_bytes())
    files = {"MODEL": model, "SHIPPED": DEFAULT_MODEL}
    # runner.read_input_bytes: how read_model reads a model file
    readers = ((Path, "read_bytes"), (runner, "read_input_bytes"))
    reads = count_reads(monkeypatch, *readers, only=list(files.values()))
    options = [str(files.get(o, o)) for o in options]
    out = tmp_path / "out"
    assert main(["calibrate", *recording, "--settle-s", "0.3", *options, "--out", str(out)]) == 0
    assert reads == ({} if read is None else {files[read]: 1})
    record = json.loads((out / "calibration.json").read_text())
    if "classical" not in options:  # the U-Net calibrated, from the content read
        assert record["method_config"]["model_sha256"] == sha256_file(model)
    # the preview's U-Net is recorded as loaded (behind --method classical it was in argv only)
    drawn = record["extra"]["preview_method"]
    if "--preview" not in options:
        assert drawn is None
    else:
        assert read is not None
        shown = (drawn["model"], drawn["model_sha256"])
        assert shown == (str(files[read].resolve()), sha256_file(files[read]))

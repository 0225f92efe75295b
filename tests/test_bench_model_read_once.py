"""``contactcal bench`` reads each model file once, before any work: every onnxruntime session it
scores, times or perturbs with, and the sha256 ``results.json`` records (``models``), are of that
content. It read each file 6-7 times (accuracy, timing, the network alone, the robustness suite,
each cross-check set) and hashed it once more for ``models``: a model re-exported during a run
was scored as half one model and half the other, and recorded as the one read last."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from procedural import write_dataset
from read_counts import count_reads

from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.run import run_bench
from contactcal.infer.cli import main
from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.methods.unet import runner
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

ort = pytest.importorskip("onnxruntime")

#: Appended to a model: a loadable model of other content (a doc_string, field 6; the last wins).
DOC_STRING = b"\x32\x01"


class Watched:
    """Reads of the model files (each replaced by another loadable model right after each read:
    a re-export into the same path) and the content of every onnxruntime session built."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, files: list[Path]) -> None:
        self.sessions: list[str] = []  # sha256 of each session's model content
        self.first = {f: sha256_bytes(f.read_bytes()) for f in files}
        real_read, real_session = Path.read_bytes, ort.InferenceSession

        def replace(path: Path, content: bytes) -> None:
            if path != DEFAULT_MODEL:  # the installed file is only counted
                path.write_bytes(content + DOC_STRING + b"x")

        def session(model: bytes | str, *args: object, **kwargs: object) -> object:
            content = model if isinstance(model, bytes) else real_read(Path(model))
            self.sessions.append(sha256_bytes(content))
            return real_session(model, *args, **kwargs)

        monkeypatch.setattr(ort, "InferenceSession", session)
        # runner.read_input_bytes: how read_model reads a model file
        readers = ((Path, "read_bytes"), (runner, "read_input_bytes"))
        self.reads = count_reads(monkeypatch, *readers, only=self.first, after=replace)

    def check(self, results: dict[str, object], names: dict[str, Path]) -> None:
        """Each file read once; ``models`` records, and every session ran, the content read."""
        assert self.reads == dict.fromkeys(names.values(), 1)
        assert results["models"] == {
            name: {"path": str(path), "sha256": self.first[path]} for name, path in names.items()
        }
        assert set(self.sessions) == set(self.first.values())


@pytest.mark.usefixtures("small_bench_cli")
def test_the_cli_reads_each_model_once_for_every_part_of_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    data = write_dataset(tmp_path / "data", fingers=1)
    other = write_dataset(tmp_path / "other", fingers=1, seed=2)
    model, variant = tmp_path / "model.onnx", tmp_path / "int8.onnx"
    shutil.copyfile(DEFAULT_MODEL, model)
    variant.write_bytes(DEFAULT_MODEL.read_bytes() + DOC_STRING + b"v")  # another model
    watched = Watched(monkeypatch, [model, variant])
    out = tmp_path / "out"
    argv = ["bench", "--data", str(data), "--out", str(out), "--model", str(model)]
    argv += ["--variant", f"int8={variant}", "--crosscheck", str(other)]
    argv += ["--repeats", "1", "--timing-frames", "1", "--robustness", "--robustness-frames", "2"]
    assert main(argv) == 0
    results = json.loads((out / "results.json").read_text())
    watched.check(results, {"unet": model, "unet[int8]": variant})
    assert len(watched.sessions) > 2 * 6  # the check, scoring, timing, robustness, cross-check


def test_run_bench_reads_the_shipped_model_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without --model, and without reference frames (what each U-Net does then is asked)."""
    data = write_dataset(tmp_path / "data", fingers=1)
    watched = Watched(monkeypatch, [DEFAULT_MODEL])
    config = BenchConfig(
        repeats=1, timing_frames=1, full_size=(128, 96), threads=(1,), use_reference=False
    )
    watched.check(run_bench(data, tmp_path / "out", config=config), {"unet": DEFAULT_MODEL})

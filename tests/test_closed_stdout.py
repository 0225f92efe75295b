"""A standard output closed early (``contactcal train ... | head -1``) after a train-side or
synth-side command wrote its outputs: one line saying so and naming them, exit 2, as the infer
commands' (``printing_after``), not a bare "what it printed is incomplete" that reads as if
nothing was written; the restating tools (``python -m contactcal.train.floor`` and the others)
printed a BrokenPipeError traceback."""

from __future__ import annotations

import errno
import io
import os
import sys
from pathlib import Path

import pytest
from procedural import write_dataset

from contactcal.infer.cli import main
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

WRITTEN = "writing to standard output failed (Broken pipe): what it printed is incomplete; "
TINY = ["--epochs", "1", "--input-size", "32", "--batch-size", "4", "--base", "4", "--levels"]
TINY += ["2", "--threads", "1", "--device", "cpu", "--quiet"]


class _ClosedPipe(io.StringIO):
    """A standard output whose reader has gone (``| head -1`` after its line)."""

    def write(self, text: str) -> int:
        raise BrokenPipeError(errno.EPIPE, os.strerror(errno.EPIPE))


def _closed_run(argv: list[str], monkeypatch: pytest.MonkeyPatch, capsys) -> str:
    """``main(argv)`` with a closed standard output: exit 2, its one error line."""
    capsys.readouterr()
    with monkeypatch.context() as m:
        m.setattr(sys, "stdout", _ClosedPipe())
        assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def test_the_restating_tools_name_a_closed_stdout_and_their_written_model(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("onnx")
    from contactcal.train.floor import main as floor_main

    out = tmp_path / "f.onnx"
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    assert floor_main([str(DEFAULT_MODEL), "--percentile", "1", "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and out.is_file(), lines
    assert lines[0].startswith(f"error: {WRITTEN}the run's outputs were written, whole: {out}")
    assert f"warning: {out}: " in lines[0] and "calibrated before this change" in lines[0]


def test_procedural_and_quantize_name_their_written_outputs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p"
    argv = ["procedural", "--fingers", "2", "--size", "64x48", "--out", str(out)]
    assert _closed_run(argv, monkeypatch, capsys).endswith(f"{WRITTEN}{_whole(out)}")
    pytest.importorskip("onnx")
    q = tmp_path / "q.onnx"
    d = write_dataset(tmp_path / "d", fingers=4)  # a procedural set is refused as --data
    argv = ["quantize", str(DEFAULT_MODEL), "--out", str(q), "--data", str(d), "--frames", "4"]
    assert _closed_run(argv, monkeypatch, capsys).endswith(f"{WRITTEN}{_whole(q)}")


def test_train_and_export_name_their_written_outputs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    pytest.importorskip("kornia")
    d = write_dataset(tmp_path / "d", fingers=3)
    run = tmp_path / "r"
    argv = ["train", "--data", str(d), "--out", str(run), *TINY]
    assert _closed_run(argv, monkeypatch, capsys).endswith(f"{WRITTEN}{_whole(run)}")
    # --resume on the finished run writes nothing: the line says only that stdout failed
    resumed = _closed_run([*argv, "--resume"], monkeypatch, capsys)
    assert resumed.endswith(WRITTEN.removesuffix("; ")), resumed
    m = tmp_path / "m.onnx"
    line = _closed_run(["export", str(run), "--out", str(m)], monkeypatch, capsys)
    assert line.endswith(f"{WRITTEN}{_whole(m)}") and m.is_file()


@pytest.mark.slow
def test_fidelity_names_its_report_and_the_one_it_replaced(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("mitsuba")
    out = tmp_path / "f"
    argv = ["fidelity", "--sessions", "1", "--size", "32x24", "--spp", "1", "--pressures"]
    argv += ["0,10", "--out", str(out)]
    assert main(argv) == 0
    line = _closed_run(argv, monkeypatch, capsys)
    assert f"{WRITTEN}{_whole(out)}; replaced the fidelity report that {out} held" in line


def _whole(path: Path) -> str:
    return f"the run's outputs were written, whole: {path}"

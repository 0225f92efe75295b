"""The restating tools (``interval``, ``change_gate``, ``floor``) say which model an ``--out``
that held one they replaced, as ``export`` and ``quantize`` do."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

pytest.importorskip("onnx")

from contactcal.train import change_gate, floor, interval


def _argv(tool: Callable[[list[str]], int], data: Path) -> list[str]:
    """The tool's options besides ``MODEL`` and ``--out``."""
    return ["--percentile", "1"] if tool is floor.main else ["--data", str(data)]


@pytest.mark.parametrize(
    "tool", [interval.main, change_gate.main, floor.main], ids=["interval", "change_gate", "floor"]
)
def test_a_replaced_model_is_named_with_its_sha256(
    tool: Callable[[list[str]], int], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from procedural import write_dataset

    data = write_dataset(tmp_path / "data", fingers=1)
    out = tmp_path / "new.onnx"
    out.write_bytes(b"an earlier model")
    assert tool([str(DEFAULT_MODEL), *_argv(tool, data), "--out", str(out)]) == 0
    wrote, note = capsys.readouterr().out.strip().splitlines()[-2:]
    held = sha256_bytes(b"an earlier model")[:12]
    assert wrote == f"wrote {out}"
    assert note == f"note: replaced {out} (sha256 {held}); give each run its own --out to keep both"
    assert out.read_bytes() != b"an earlier model"
    fresh = tmp_path / "fresh.onnx"  # nothing held: no note
    assert floor.main([str(out), "--percentile", "2", "--out", str(fresh)]) == 0
    assert capsys.readouterr().out.strip().splitlines()[-1] == f"wrote {fresh}"

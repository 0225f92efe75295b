"""Without an optional extra, its commands name the `pip install` they need and write nothing."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from contactcal.infer.cli import main

REAL_FIND_SPEC = importlib.util.find_spec

CASES = {
    "synth": (
        ["synth", "--fingers", "1", "--pressures", "0", "--size", "32x24", "--spp", "1"],
        "mitsuba",
        "synth",
    ),
    "train": (["train", "--data", "{tmp}", "--epochs", "1"], "torch", "train"),
    "export": (["export", "{tmp}"], "onnx", "train"),
}


@pytest.mark.parametrize("command", CASES)
def test_missing_extra_names_the_pip_command(
    command: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv, module, extra = CASES[command]

    def find_spec(name: str, package: str | None = None) -> object:
        if name.split(".")[0] == module:
            return None  # as if the extra were not installed
        return REAL_FIND_SPEC(name, package)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    out = tmp_path / "out"
    code = main([a.replace("{tmp}", str(tmp_path)) for a in argv] + ["--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"pip install 'contactcal[{extra}]'" in err and module in err
    assert len(err.strip().splitlines()) == 1, err
    assert not out.exists(), "nothing may be written without the extra"

"""Input files that are not regular files (a device, a FIFO, or a link to one) are refused
unread, in one line naming the file, exit 2: never read until memory runs out nor waited on."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

SESSION = Path(__file__).resolve().parents[1] / "examples" / "session"
FRAME = str(SESSION / "p05.0kpa.jpg")

#: Input → (argv with ``{bad}`` for the odd file, and the suffix the odd file takes).
CASES: dict[str, tuple[list[str], str]] = {
    "rig": (["measure", "--rig", "{bad}", FRAME, "--out", "-"], ".json"),
    "manifest": (["calibrate", "{bad}", "--out", "{out}"], ".csv"),
    "frame": (["measure", "{bad}", "--out", "-"], ".jpg"),
    "listed frame": (
        ["calibrate", "{manifest}", "--method", "classical", "--out", "{out}"],
        ".jpg",
    ),
    "reference": (["measure", "--reference", "{bad}", FRAME, "--out", "-"], ".png"),
    "model": (["measure", "--model", "{bad}", FRAME, "--out", "-"], ".onnx"),
    "labels": (
        ["evaluate", "--labels", "{bad}", "--out", "{out}", str(SESSION / "manifest.csv")],
        ".csv",
    ),
    "evaluation": (["boundary-offset", "{bad}"], ".json"),
    "dataset index": (["bench", "--data", "{data}", "--out", "{out}"], ".csv"),
}


def _odd_file(tmp_path: Path, kind: str, suffix: str) -> Path:
    """A link to /dev/zero, or a FIFO, named with ``suffix``."""
    bad = tmp_path / f"odd{suffix}"
    if kind == "device":
        bad.symlink_to("/dev/zero")
    else:
        os.mkfifo(bad)
    return bad


@pytest.mark.parametrize("kind", ["device", "fifo"])
@pytest.mark.parametrize("case", list(CASES))
def test_not_regular_input_exit_2(tmp_path: Path, case: str, kind: str) -> None:
    argv, suffix = CASES[case]
    bad = _odd_file(tmp_path, kind, suffix)
    manifest = tmp_path / "manifest.csv"
    for name in ("p00.0kpa.jpg", "p05.0kpa.jpg"):
        shutil.copy(SESSION / name, tmp_path / name)
    manifest.write_text(f"file,pressure_kpa\np00.0kpa.jpg,0\np05.0kpa.jpg,5\n{bad.name},10\n")
    data = tmp_path / "data"
    data.mkdir()
    if case == "dataset index":
        bad = data / "index.csv"
        bad.symlink_to("/dev/zero") if kind == "device" else os.mkfifo(bad)
    fill = {"bad": str(bad), "out": str(tmp_path / "out"), "manifest": str(manifest)}
    fill["data"] = str(data)
    code = "import sys; from contactcal.infer.cli import main; sys.exit(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", code, *(a.format(**fill) for a in argv)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=30, check=False)
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1, res.stderr
    assert f"{bad}: not a regular file (a device, pipe or socket); expected" in res.stderr


def test_inputs_are_opened_binary_and_non_blocking_where_the_platform_has_them() -> None:
    """Windows has no O_NONBLOCK (reading any input raised AttributeError there) and opens in
    text mode without O_BINARY (CR LF read as LF in a frame's bytes)."""
    from types import SimpleNamespace

    from contactcal.infer.files.regular import READ_FLAGS, input_flags

    windows = SimpleNamespace(O_RDONLY=0, O_BINARY=0x8000)
    assert input_flags(windows) == 0x8000
    posix = SimpleNamespace(O_RDONLY=0, O_NONBLOCK=0x800)
    assert input_flags(posix) == 0x800
    assert READ_FLAGS & getattr(os, "O_NONBLOCK", 0) == getattr(os, "O_NONBLOCK", 0)

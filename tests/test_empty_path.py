"""A path option given an empty string is refused: ``Path("")`` is ``.``, so ``--model ""`` was
refused as "--model .: is a folder", and ``calibrate --out ""`` wrote into the current folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from contactcal.infer.cli import main

SESSION = Path(__file__).resolve().parents[1] / "examples" / "session"
FRAME = str(SESSION / "p05.0kpa.jpg")
REFUSAL = (
    "'': expected a file or folder path, got an empty string (for the current folder give '.')"
)


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["measure", FRAME, "--model", "", "--out", "-"], "--model"),
        (["measure", "", "--out", "-"], "IMAGE"),
        (["measure", FRAME, "--reference", "", "--out", "-"], "--reference"),
        (["measure", FRAME, "--rig", "", "--out", "-"], "--rig"),
        (
            ["calibrate", str(SESSION / "manifest.csv"), "--method", "classical", "--out", ""],
            "--out",
        ),
    ],
)
def test_an_empty_path_is_refused_naming_the_option(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    option: str,
) -> None:
    monkeypatch.chdir(tmp_path)  # where "" would have been read or written
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert f"error: argument {option}: {REFUSAL}" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_restating_tools_refuse_an_empty_path() -> None:
    """``python -m contactcal.train.restate``'s and its kin's parser, outside ``contactcal``."""
    from contactcal.train.restate import restating_parser

    parser = restating_parser("restate", "test")
    assert parser.parse_args(["m.onnx", "--data", "d", "--out", "o.onnx"]).out == Path("o.onnx")
    with pytest.raises(SystemExit):
        parser.parse_args(["m.onnx", "--data", "d", "--out", ""])


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["", "--percentile", "1", "--out", "x.onnx"], "model"),
        (["m.onnx", "--percentile", "1", "--out", ""], "--out"),
    ],
)
def test_the_floor_tool_refuses_an_empty_path_naming_it(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    option: str,
) -> None:
    """``python -m contactcal.train.floor`` took its paths as plain strings: ``""`` was read as
    the current folder (".: not a readable ONNX model ([Errno 21] Is a directory: '.')") or
    refused as ``--out .``."""
    from contactcal.train.floor import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert errors == [f"python -m contactcal.train.floor: error: argument {option}: {REFUSAL}"]
    assert list(tmp_path.iterdir()) == []

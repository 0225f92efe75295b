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


def _floor_main(argv: list[str]) -> int:
    """``python -m contactcal.train.floor``'s entry point (imported when a case runs it)."""
    from contactcal.train.floor import main as floor_main

    return floor_main(argv)


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
        # python -m contactcal.train.floor took its paths as plain strings: "" was read as the
        # current folder (".: not a readable ONNX model ([Errno 21] Is a directory: '.')")
        (["floor", "", "--percentile", "1", "--out", "x.onnx"], "model"),
        (["floor", "m.onnx", "--percentile", "1", "--out", ""], "--out"),
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
    floor = argv[0] == "floor"
    run = _floor_main if floor else main
    prog = "python -m contactcal.train.floor" if floor else f"contactcal {argv[0]}"
    with pytest.raises(SystemExit) as exc:
        run(argv[1:] if floor else argv)
    assert exc.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert errors == [f"{prog}: error: argument {option}: {REFUSAL}"]
    assert list(tmp_path.iterdir()) == []


def test_the_restating_tools_refuse_an_empty_path(capsys: pytest.CaptureFixture[str]) -> None:
    """``python -m contactcal.train.restate``'s and its kin's parser, outside ``contactcal``."""
    from contactcal.train.restate import restating_parser

    parser = restating_parser("restate", "test")
    assert parser.parse_args(["m.onnx", "--data", "d", "--out", "o.onnx"]).out == Path("o.onnx")
    with pytest.raises(SystemExit) as exc:
        parser.parse_args(["m.onnx", "--data", "d", "--out", ""])
    assert exc.value.code == 2
    assert f"restate: error: argument --out: {REFUSAL}" in capsys.readouterr().err

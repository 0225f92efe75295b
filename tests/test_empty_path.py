"""A path option given an empty string is refused: ``Path("")`` is ``.``, so ``--model ""`` was
refused as "--model .: is a folder", and ``calibrate --out ""`` wrote into the current folder.
Only an option that may name a folder is told to give ``.`` for the current folder."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from contactcal.infer.cli import build_parser, main
from contactcal.infer.parser import folder_arg

SESSION = Path(__file__).resolve().parents[1] / "examples" / "session"
FRAME = str(SESSION / "p05.0kpa.jpg")
#: The refusal for an option that takes a file (``--model ""``: "give '.'" would name a folder).
FILE_REFUSAL = "'': expected a file path, got an empty string"
#: The refusal for an option that may name a folder.
REFUSAL = (
    "'': expected a file or folder path, got an empty string (for the current folder give '.')"
)


def _floor_main(argv: list[str]) -> int:
    """``python -m contactcal.train.floor``'s entry point (imported when a case runs it)."""
    from contactcal.train.floor import main as floor_main

    return floor_main(argv)


@pytest.mark.parametrize(
    ("argv", "option", "refusal"),
    [
        (["measure", FRAME, "--model", "", "--out", "-"], "--model", FILE_REFUSAL),
        (["measure", "", "--out", "-"], "IMAGE", FILE_REFUSAL),
        (["measure", FRAME, "--reference", "", "--out", "-"], "--reference", FILE_REFUSAL),
        (["measure", FRAME, "--rig", "", "--out", "-"], "--rig", FILE_REFUSAL),
        (["measure", FRAME, "--out", ""], "--out", FILE_REFUSAL),
        (
            ["calibrate", str(SESSION / "manifest.csv"), "--method", "classical", "--out", ""],
            "--out",
            REFUSAL,
        ),
        (["evaluate", "m.csv", "--labels", "", "--out", "e"], "--labels", REFUSAL),
        (["boundary-offset", "e1", ""], "EVAL_DIR", REFUSAL),
        (["bench", "--data", "", "--out", "b"], "--data", REFUSAL),
        # python -m contactcal.train.floor took its paths as plain strings: "" was read as the
        # current folder (".: not a readable ONNX model ([Errno 21] Is a directory: '.')")
        (["floor", "", "--percentile", "1", "--out", "x.onnx"], "model", FILE_REFUSAL),
        (["floor", "m.onnx", "--percentile", "1", "--out", ""], "--out", FILE_REFUSAL),
    ],
)
def test_an_empty_path_is_refused_naming_the_option(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    option: str,
    refusal: str,
) -> None:
    monkeypatch.chdir(tmp_path)  # where "" would have been read or written
    floor = argv[0] == "floor"
    run = _floor_main if floor else main
    prog = "python -m contactcal.train.floor" if floor else f"contactcal {argv[0]}"
    with pytest.raises(SystemExit) as exc:
        run(argv[1:] if floor else argv)
    assert exc.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert errors == [f"{prog}: error: argument {option}: {refusal}"]
    assert list(tmp_path.iterdir()) == []


def test_the_restating_tools_refuse_an_empty_path(capsys: pytest.CaptureFixture[str]) -> None:
    """``python -m contactcal.train.restate``'s and its kin's parser, outside ``contactcal``."""
    from contactcal.train.restate import restating_parser

    parser = restating_parser("restate", "test")
    assert parser.parse_args(["m.onnx", "--data", "d", "--out", "o.onnx"]).out == Path("o.onnx")
    for argv, option, refusal in (
        (["m.onnx", "--data", "d", "--out", ""], "--out", FILE_REFUSAL),
        (["m.onnx", "--data", "", "--out", "o.onnx"], "--data", REFUSAL),
    ):
        with pytest.raises(SystemExit) as exc:
            parser.parse_args(argv)
        assert exc.value.code == 2
        assert f"restate: error: argument {option}: {refusal}\n" in capsys.readouterr().err


def _path_options() -> list[tuple[str, argparse.Action]]:
    """``(command, action)`` of every path option of ``contactcal``'s commands."""
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return [
        (name, action)
        for name, parser in sub.choices.items()
        for action in parser._actions
        if action.type in (Path, folder_arg)
    ]


def test_the_options_that_may_name_a_folder_are_those_that_say_so() -> None:
    """The rule the hint follows: an option whose help or metavar names a folder (``DIR``) takes
    ``folder_arg`` (told to give '.'), every other path option a file (``type=Path``)."""
    options = _path_options()
    assert len(options) > 30  # every command's, the optional roles' included
    for name, action in options:
        says_folder = "folder" in (action.help or "") or "DIR" in str(action.metavar)
        assert (action.type is folder_arg) == says_folder, (name, action.dest)


def test_the_readme_quotes_both_refusals() -> None:
    """The README quoted the file refusal and said a folder option only "adds" the hint: its
    refusal, "a file or folder path", was quoted nowhere."""
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    text = " ".join(readme.split())  # its lines joined
    assert f"argument --model: {FILE_REFUSAL}" in text
    assert f"argument --out: {REFUSAL}" in text

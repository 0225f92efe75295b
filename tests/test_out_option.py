"""A destination a command cannot write is refused with the option that gave it first, its value
as given: ``--out OUT: ...`` (exit 2, one line), from every command and writer."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from procedural import write_dataset
from test_video import make_log, make_video

from contactcal.infer.cli import main
from contactcal.infer.files.destination import LinkOutputError, OutputError, by_option
from contactcal.infer.pipeline import args as pipeline_args

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A working folder holding the example session ``s/`` and a file ``afile``."""
    shutil.copytree(EXAMPLE, tmp_path / "s")
    (tmp_path / "afile").write_text("kept")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """The one line of a command that exits 2."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


UNDER_A_FILE = [  # (command line without the option, option, value under the file afile)
    (["calibrate", "s/manifest.csv", "--method", "classical"], "--out", "afile/cal"),
    (
        ["calibrate", "s/manifest.csv", "--method", "classical", "--out", "c"],
        "--overlay",
        "afile/o",
    ),
    (
        ["evaluate", "s/manifest.csv", "--labels", "s/masks", "--method", "classical"],
        "--out",
        "afile/e",
    ),
    (["demo", "--manifest", "s/manifest.csv"], "--out", "afile/d"),
    (
        ["measure", "--method", "classical", "--out", "r.json", "s/p00.0kpa.jpg"],
        "--overlay",
        "afile/o",
    ),
    (["procedural", "--fingers", "1"], "--out", "afile/p"),
]


@pytest.mark.parametrize(("argv", "option", "value"), UNDER_A_FILE)
def test_an_output_under_a_file_names_its_option(
    argv: list[str],
    option: str,
    value: str,
    here: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    line = refused([*argv, option, value], capsys)
    expected = f"contactcal: error: {option} {value}: {here / 'afile'}: is not a folder"
    assert line.startswith(expected), line
    assert (here / "afile").read_text() == "kept"
    assert sorted(p.name for p in here.iterdir()) == ["afile", "s"]


def test_a_calibration_output_refused_as_an_input_names_out(
    here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (here / "c").mkdir()
    shutil.copy(here / "s" / "rig.json", here / "c" / "calibration.csv")  # read as --rig
    argv = ["calibrate", "s/manifest.csv", "--method", "classical", "--rig", "c/calibration.csv"]
    line = refused([*argv, "--out", "c"], capsys)
    assert line.startswith("contactcal: error: --out c: "), line
    assert "calibration.csv: is an input of this run (c/calibration.csv)" in line, line
    assert sorted(p.name for p in (here / "c").iterdir()) == ["calibration.csv"]


def test_an_input_in_the_records_place_is_refused_as_no_record(
    here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``calibration.json`` in ``--out`` that is this run's own input (here its ``--rig``) is
    no calibration record: refused as such before any work, with the advice to move it away or
    give another ``--out`` (the earlier-record check runs before the outputs are staged)."""
    (here / "c").mkdir()
    shutil.copy(here / "s" / "rig.json", here / "c" / "calibration.json")  # read as --rig
    argv = ["calibrate", "s/manifest.csv", "--method", "classical", "--rig", "c/calibration.json"]
    line = refused([*argv, "--out", "c"], capsys)
    assert line.startswith("contactcal: error: c/calibration.json: not a contactcal calibration"), (
        line
    )
    assert line.endswith("move it away or give another --out"), line
    assert sorted(p.name for p in (here / "c").iterdir()) == ["calibration.json"]


def test_a_video_run_under_a_file_names_out(
    here: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    make_video(here / "v.avi", [0, 5, 10])
    make_log(here / "log.csv", [0, 5, 10], rng)
    argv = ["calibrate", "--video", "v.avi", "--pressure-log", "log.csv", "--method", "classical"]
    line = refused([*argv, "--out", "afile/v"], capsys)
    assert line.startswith(f"contactcal: error: --out afile/v: {here / 'afile'}: is not a"), line


def test_a_bench_report_refused_when_written_names_out(
    tmp_path: Path,
    small_bench_cli: None,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = write_dataset(tmp_path / "data", fingers=1)
    (tmp_path / "afile").write_text("kept")
    monkeypatch.chdir(tmp_path)
    argv = ["bench", "--data", "data", "--repeats", "1", "--timing-frames", "1"]
    line = refused([*argv, "--out", "afile/r"], capsys)  # refused before the work
    assert line.startswith(f"contactcal: error: --out afile/r: {tmp_path / 'afile'}: is not"), line
    # refused when the report is written (the folder became unwritable meanwhile)
    monkeypatch.setattr(pipeline_args, "check_out_folder", lambda *a: None)
    line = refused([*argv, "--out", "afile/r"], capsys)
    assert line.startswith(f"contactcal: error: --out afile/r: {tmp_path / 'afile'}: is not"), line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "data"]
    assert data.is_dir()


def test_synth_out_under_a_file_or_uncreatable_names_out(
    here: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("mitsuba")
    argv = ["synth", "--fingers", "1", "--quiet"]
    line = refused([*argv, "--out", "afile/d"], capsys)
    assert line.startswith(f"contactcal: error: --out afile/d: {here / 'afile'}: is not a"), line

    def no_mkdir(self: Path, *args: object, **kwargs: object) -> None:
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", no_mkdir)
    line = refused([*argv, "--out", "d"], capsys)
    assert line == (
        "contactcal: error: --out d: cannot create the dataset folder (Permission denied); "
        "expected a folder that can be written"
    ), line


def _denied(*args: object, **kwargs: object) -> None:
    raise PermissionError(13, "Permission denied")


@pytest.mark.parametrize(
    ("value", "target", "name"),
    [("d/sub", Path, "mkdir"), ("d", tempfile, "mkdtemp")],  # its parent; its staging folder
)
def test_procedural_out_uncreatable_names_out(
    value: str,
    target: object,
    name: str,
    here: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(target, name, _denied)
    line = refused(["procedural", "--fingers", "1", "--out", value], capsys)
    assert line == (
        f"contactcal: error: --out {value}: cannot create the dataset folder (Permission "
        "denied); expected a folder that can be written"
    ), line
    assert sorted(p.name for p in here.iterdir()) == ["afile", "s"]


def test_by_option_names_the_innermost_option_and_keeps_the_class(tmp_path: Path) -> None:
    options = {"--out": Path("o"), "--overlay": Path("o/ov")}
    exc = LinkOutputError(f"{Path('o/ov/a.png').absolute()}: is a symbolic link")
    named = by_option("o/ov/a.png", exc, options)
    assert type(named) is LinkOutputError
    assert str(named) == f"--overlay o/ov: {Path('o/ov/a.png').absolute()}: is a symbolic link"
    folder = OSError(f"{Path('o').absolute()}: cannot create the output folder (Permission denied)")
    named = by_option("o/x.json", folder, options)
    assert type(named) is ValueError  # exit 2 as every bad input
    assert str(named) == "--out o: cannot create the output folder (Permission denied)"
    other = OutputError("elsewhere")
    assert by_option(tmp_path / "x.json", other, options) is other  # no option gave it

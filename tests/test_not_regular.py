"""Input files that are not regular files (a device, a FIFO, or a link to one) are refused
unread, in one line naming the file, exit 2: never read until memory runs out nor waited on."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import threading
from collections.abc import Iterator
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


class WaitingWriter:
    """A FIFO with a writer waiting for a reader to open it (a thread): opening it for reading
    would not block, and reading it would get nothing; it is :attr:`opened` once a reader did.
    """

    def __init__(self, path: Path) -> None:
        os.mkfifo(path)
        self.path = path
        self._thread = threading.Thread(target=self._write, daemon=True)
        self._thread.start()

    def _write(self) -> None:
        with open(self.path, "wb"):  # blocks until a reader opens the FIFO
            pass

    @property
    def opened(self) -> bool:
        """Whether a reader opened the FIFO (and so released the writer)."""
        self._thread.join(timeout=0.5)  # a reader that opened it released the writer
        return not self._thread.is_alive()

    def release(self) -> None:
        """Open the FIFO for reading, releasing the writer, and wait for it to end."""
        fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)
        try:
            self._thread.join()
        finally:
            os.close(fd)


@pytest.fixture
def fifo(tmp_path: Path) -> Iterator[WaitingWriter]:
    """A FIFO ``calibration.json`` in ``tmp_path``, a writer waiting (:class:`WaitingWriter`)."""
    writer = WaitingWriter(tmp_path / "calibration.json")
    yield writer
    writer.release()


def test_a_hashed_file_that_is_a_fifo_is_refused_unopened(fifo: WaitingWriter) -> None:
    """``sha256_file`` opened the file blocking, after its caller's type check: a FIFO put there
    in between was waited on (and here, with a writer, hashed as empty)."""
    from contactcal.infer.files.digest import sha256_file

    with pytest.raises(ValueError, match="not a regular file .*; expected a video file"):
        sha256_file(fifo.path, "a video file", ValueError)
    assert not fifo.opened


def test_a_calibration_that_is_not_a_regular_file_is_refused_unread(
    fifo: WaitingWriter, tmp_path: Path
) -> None:
    """``load_curve`` read the path as text: /dev/zero until memory ran out, a FIFO waited on
    for a writer, a folder "not a readable contactcal calibration ([Errno 21] ...)"."""
    from contactcal.infer.calibration.load import load_curve

    expected = "expected the calibration.json that `contactcal calibrate` wrote"
    with pytest.raises(ValueError, match=f"calibration.json: not a regular file .*; {expected}"):
        load_curve(fifo.path)
    assert not fifo.opened
    (tmp_path / "folder.json").mkdir()
    with pytest.raises(ValueError, match=f"^{tmp_path}/folder.json: is a folder; {expected}$"):
        load_curve(tmp_path / "folder.json")


def test_an_earlier_calibration_that_is_not_a_regular_file_is_not_read(
    fifo: WaitingWriter, tmp_path: Path
) -> None:
    """The earlier record of ``calibrate --out`` was read as text after an ``is_file`` check: a
    FIFO put there in between was waited on. It is no record (its run is refused), never
    opened."""
    from contactcal.infer.calibration.out_folder import held_record

    with pytest.raises(ValueError, match=f"^{fifo.path}: not a regular file .*another --out$"):
        held_record(tmp_path)
    assert not fifo.opened
    assert held_record(tmp_path / "none") is None


def test_a_folder_is_refused_by_the_shared_reader_naming_what_was_expected(
    tmp_path: Path,
) -> None:
    """A folder read as an input raised IsADirectoryError, each reader wording it its own way
    (", expected", ", not an image file", "; expected")."""
    from contactcal.infer.files.regular import read_input_bytes

    with pytest.raises(ValueError, match=f"^{tmp_path}: is a folder; expected the X file$"):
        read_input_bytes(tmp_path, "the X file", ValueError)


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["measure", "--rig", "{bad}", FRAME, "--out", "-"], "the rig config JSON file"),
        (["calibrate", "{bad}", "--out", "{out}"], "the manifest CSV file (e.g. session"),
        (["measure", "{bad}", "--out", "-"], "a JPEG file"),
        (  # not the frames' hint ("give the frames' file names")
            ["measure", "--reference", "{bad}", FRAME, "--out", "-"],
            "the session's zero-pressure frame (an image file)",
        ),
        (["measure", "--model", "{bad}", FRAME, "--out", "-"], "the ONNX model file"),
        (
            ["calibrate", "--video", "{bad}", "--pressure-log", "{bad}", "--out", "{out}"],
            "the pressure log CSV file",
        ),
    ],
)
def test_a_folder_given_as_an_input_file_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], expected: str
) -> None:
    from contactcal.infer.cli import main

    bad = tmp_path / "odd.jpg"
    bad.mkdir()
    fill = {"bad": str(bad), "out": str(tmp_path / "out")}
    assert main([a.format(**fill) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"{bad}: is a folder; expected {expected}" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", ["fifo", "folder"])
def test_a_restating_tools_model_that_is_not_a_file_is_refused_unread(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    """``python -m contactcal.train.floor`` (and ``interval``, ``change_gate``: the same
    ``read_model``) read MODEL with ``Path.read_bytes``: a FIFO was waited on (or, with a writer,
    read as an empty model), /dev/zero read until a MemoryError traceback, a folder refused as
    "not a readable ONNX model ([Errno 21] Is a directory: ...)"."""
    pytest.importorskip("onnx")
    from contactcal.train.floor import main

    bad, out = tmp_path / "model.onnx", tmp_path / "new.onnx"
    writer = WaitingWriter(bad) if kind == "fifo" else None
    if writer is None:
        bad.mkdir()
    try:
        assert main([str(bad), "--percentile", "1", "--out", str(out)]) == 2
        assert writer is None or not writer.opened
    finally:
        if writer is not None:
            writer.release()
    err = capsys.readouterr().err
    says = "is a folder" if writer is None else "not a regular file (a device, pipe or socket)"
    assert err == f"error: {bad}: {says}; expected a .onnx file written by contactcal export\n"
    assert not out.exists()


def _earlier_results(fifo: Path) -> object:
    from contactcal.infer.pipeline.commands import _results_held

    return _results_held(fifo)


def _earlier_evaluation(fifo: Path) -> object:
    from contactcal.infer.evaluate.command import earlier_evaluation_note

    (fifo.parent / "evaluation.png").write_bytes(b"png")
    return earlier_evaluation_note(fifo.parent, fifo.parent / "manifest.csv")


def _frame_record(fifo: Path) -> object:
    from contactcal.synth.dataset_folder import read_frame_record

    return read_frame_record(fifo)


def _run_config(fifo: Path) -> object:
    from contactcal.train.run_folder import read_run_info

    return read_run_info(fifo.parent)


#: Reader of an earlier output → (the file it reads, and what it returns or raises for a FIFO).
EARLIER_OUTPUTS = {
    "measure's results": (_earlier_results, "results.json", "unreadable as results"),
    "evaluate's evaluation": (
        _earlier_evaluation,
        "evaluation.json",
        "evaluation.png, not readable as an evaluation",
    ),
    "a synth frame record": (
        _frame_record,
        "p05.0kpa.json",
        "not a regular file .*; expected a frame record a `contactcal synth` run wrote",
    ),
    "a train run's config": (
        _run_config,
        "config.json",
        "not a regular file .*; expected the config.json a `contactcal train` run wrote",
    ),
}


@pytest.mark.parametrize("case", list(EARLIER_OUTPUTS))
def test_an_earlier_output_that_is_a_fifo_is_not_opened(tmp_path: Path, case: str) -> None:
    """These readers checked ``is_file`` (or globbed the folder) and then read the file as text:
    a FIFO there (for synth, any ``frames/*.json``: a resume hung on it) was waited on for a
    writer, and read as empty when one was waiting, as here."""
    reader, name, expected = EARLIER_OUTPUTS[case]
    fifo = WaitingWriter(tmp_path / name)
    try:
        try:
            got = str(reader(fifo.path))
        except ValueError as exc:
            got = str(exc)
        assert re.search(expected, got), got
        assert "\n" not in got
        assert not fifo.opened
    finally:
        fifo.release()

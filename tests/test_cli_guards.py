"""Guards of the command line a newcomer hits: ``--out -`` where a folder is written, the change
gate flag where no U-Net runs, a report into the labels folder, an interrupted run, an output
folder that is a link, a folder given as a frame, and a curve that cannot tell pressures apart."""

from __future__ import annotations

import errno
import io
import json
import os
import sys
from pathlib import Path

import pytest

from contactcal.infer.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
MANIFEST = str(EXAMPLE / "manifest.csv")


def _one_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize(
    "argv",
    [
        ["calibrate", MANIFEST, "--method", "classical"],
        ["evaluate", MANIFEST, "--labels", str(EXAMPLE / "masks"), "--method", "classical"],
        ["demo"],
    ],
)
def test_out_dash_is_refused_where_a_folder_is_written(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main([*argv, "--out", "-"]) == 2
    assert "--out -:" in _one_error(capsys) and not (tmp_path / "-").exists()


def test_evaluate_gate_flag_and_labels_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    masks = tmp_path / "masks"
    masks.mkdir()
    for f in (EXAMPLE / "masks").iterdir():
        (masks / f.name).write_bytes(f.read_bytes())
    base = ["evaluate", MANIFEST, "--labels", str(masks)]
    out = tmp_path / "ev"
    assert main([*base, "--method", "classical", "--no-change-gate", "--out", str(out)]) == 2
    err = _one_error(capsys)
    assert "--no-change-gate applies to the U-Net only" in err
    assert err.endswith("drop it, or use --method unet or --method both"), err
    assert main([*base, "--method", "classical", "--out", str(masks)]) == 2
    assert "inside the labels folder" in _one_error(capsys)
    assert sorted(p.name for p in masks.iterdir()) == sorted(
        p.name for p in (EXAMPLE / "masks").iterdir()
    )
    assert not out.exists()


def test_interrupt_is_one_line_and_leaves_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    from contactcal.infer.image import read as image_read

    def stop(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(image_read.ImageFile, "read", stop)
    out = tmp_path / "cal"
    assert main(["calibrate", MANIFEST, "--method", "classical", "--out", str(out)]) == 130
    assert "interrupted" in _one_error(capsys)
    assert not out.exists() or not any(out.iterdir())


def test_output_folder_link_and_unwritable_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    real = tmp_path / "real"
    real.mkdir()
    (real / "calibration.json").write_text("{}")
    os.symlink(real, tmp_path / "link")
    argv = ["calibrate", MANIFEST, "--method", "classical", "--out", str(tmp_path / "link")]
    assert main(argv) == 2
    assert "symbolic link to a folder" in _one_error(capsys)
    assert (real / "calibration.json").read_text() == "{}"
    # A new folder below the link was created through it (the review's linkdir/sub).
    argv[-1] = str(tmp_path / "link" / "sub")
    assert main(argv) == 2
    assert "link: is a symbolic link to a folder" in _one_error(capsys)
    assert sorted(p.name for p in real.iterdir()) == ["calibration.json"]
    frame = str(EXAMPLE / "p10.0kpa.jpg")
    assert main(["measure", "--out", "/proc/x.json", frame]) == 2
    msg = _one_error(capsys)
    assert "/proc/x.json: cannot write into its folder /proc" in msg and ".tmp" not in msg


def test_a_folder_given_as_a_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "frames").mkdir()
    assert main(["measure", "--out", str(tmp_path / "r.json"), str(tmp_path / "frames")]) == 2
    assert "frames: is a folder; expected an image file" in _one_error(capsys)


def test_a_curve_that_cannot_tell_pressures_apart_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for method, resolves in (("classical", False), ("unet", True)):
        out = tmp_path / method
        assert main(["calibrate", MANIFEST, "--method", method, "--out", str(out)]) == 0
        said = "its inverse cannot tell pressures apart" in capsys.readouterr().out
        res = json.loads((out / "calibration.json").read_text())["phases"]["loading"]
        assert res["resolution"]["resolves"] is resolves and said is not resolves


@pytest.mark.parametrize(
    ("pressures", "areas", "contacts", "resolves"),
    [
        ([0, 2, 4, 6, 8, 10], [0, 0, 50, 90, 120, 140], [0, 0, 1, 1, 1, 1], True),
        ([0, 2, 4, 6, 8, 10], [100, 101, 99, 100, 101, 100], [1, 1, 1, 1, 1, 1], False),
        ([0, 5], [100, 200], [1, 1], None),  # one step above the onset: not measured
    ],
)
def test_curve_resolution(
    pressures: list[float], areas: list[float], contacts: list[int], resolves: bool | None
) -> None:
    import numpy as np

    from contactcal.infer.calibration.fit import CurveConfig
    from contactcal.infer.calibration.session import fit_phase
    from contactcal.infer.calibration.steps import Step

    steps = [
        Step("loading", i, float(p), np.array([float(a)]), np.array([bool(c)]), (None,), ("f",))
        for i, (p, a, c) in enumerate(zip(pressures, areas, contacts, strict=True))
    ]
    res = fit_phase(steps, CurveConfig(), "px").resolution()
    assert res is not None and res["resolves"] is resolves


def test_ctrl_c_waits_for_the_block_to_finish() -> None:
    import signal

    from contactcal.infer.files.interrupt import deferred_interrupt

    done = []
    # Python's own Ctrl-C handler, also where the suite runs as a background job (SIGINT ignored)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with deferred_interrupt():
                signal.raise_signal(signal.SIGINT)
                done.append("renamed")  # still runs: the interrupt waits for the block
    finally:
        signal.signal(signal.SIGINT, before)
    assert done == ["renamed"]


def test_a_frame_without_a_ring_says_so(tmp_path: Path) -> None:
    pytest.importorskip("onnxruntime")
    import cv2
    import numpy as np

    from contactcal.infer.methods.registry import make_method
    from contactcal.infer.methods.unet.method import NO_RING_NOTE
    from contactcal.infer.pipeline.measure import measure_files

    black = tmp_path / "black.png"
    cv2.imwrite(str(black), np.zeros((300, 400), np.uint8))
    unet = make_method("unet")
    (m,) = measure_files([black], unet)
    assert NO_RING_NOTE in m.result.note and not m.result.contact
    ref = EXAMPLE / "p00.0kpa.jpg"
    (m,) = measure_files([EXAMPLE / "p10.0kpa.jpg"], unet, ref)
    assert NO_RING_NOTE not in m.result.note and m.result.contact


def test_rig_json_with_a_bom_and_a_bad_mm_per_px(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A rig.json saved by Notepad (UTF-8 with BOM) reads; a bad --mm-per-px names the flag."""
    from contactcal.infer.pipeline.scale import load_rig_config

    rig = tmp_path / "rig.json"
    rig.write_bytes(b"\xef\xbb\xbf" + b'{"mm_per_px": 0.0118, "image_width_px": 2592}')
    assert load_rig_config(rig).mm_per_px == 0.0118
    frame = str(Path(__file__).resolve().parents[1] / "examples" / "session" / "p05.0kpa.jpg")
    assert main(["measure", "--mm-per-px", "0", "--out", "-", frame]) == 2
    assert capsys.readouterr().err.startswith("contactcal: error: --mm-per-px 0: mm_per_px must")


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ('{"mm_per_px": 0.126, "image_width_px": 400, "mmperpx": 3}', "unknown key 'mmperpx'"),
        ('{"mm_per_px": 0.126, "image_width_px": 400, "mm_per_px": 0.2}', "'mm_per_px' is given"),
    ],
)
def test_rig_json_with_a_misspelt_or_repeated_key_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, said: str
) -> None:
    """json would drop a misspelt key, or keep the last of two values, without a word."""
    rig = tmp_path / "rig.json"
    rig.write_text(text)
    frame = str(Path(__file__).resolve().parents[1] / "examples" / "session" / "p05.0kpa.jpg")
    assert main(["measure", "--rig", str(rig), "--out", "-", frame]) == 2
    err = _one_error(capsys)
    assert str(rig) in err and said in err


def test_a_folder_given_as_rig_config_is_named_as_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--rig naming a folder (the rig's folder, not its rig.json) says so, without the OS's
    errno text."""
    frame = str(Path(__file__).resolve().parents[1] / "examples" / "session" / "p05.0kpa.jpg")
    assert main(["measure", "--rig", str(tmp_path), "--out", "-", frame]) == 2
    err = _one_error(capsys)
    assert f"{tmp_path}: is a folder; expected the rig config JSON file (rig.json)" in err, err


def test_sigterm_is_handled_as_ctrl_c(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    import signal

    from contactcal.infer.image import read as image_read

    def term(*args: object, **kwargs: object) -> None:
        signal.raise_signal(signal.SIGTERM)

    monkeypatch.setattr(image_read.ImageFile, "read", term)
    out = tmp_path / "cal"
    before = signal.getsignal(signal.SIGTERM)
    code = main(["calibrate", MANIFEST, "--method", "classical", "--out", str(out)])
    assert code == 128 + signal.SIGTERM
    assert "stopped by SIGTERM" in _one_error(capsys)
    assert not out.exists() or not any(out.iterdir())
    assert signal.getsignal(signal.SIGTERM) is before  # restored after the command


def test_an_ignored_sighup_stays_ignored() -> None:
    import signal

    from contactcal.infer.files.interrupt import stop_signals_interrupt

    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)  # as nohup leaves it
    try:
        with stop_signals_interrupt():
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            signal.raise_signal(signal.SIGHUP)  # ignored: the block goes on
    finally:
        signal.signal(signal.SIGHUP, before)


def test_sigterm_waits_for_a_commit_to_finish() -> None:
    import signal

    from contactcal.infer.files.interrupt import (
        Terminated,
        deferred_interrupt,
        stop_signals_interrupt,
    )

    done = []
    with pytest.raises(Terminated), stop_signals_interrupt():
        with deferred_interrupt():
            signal.raise_signal(signal.SIGTERM)
            done.append("renamed")  # still runs: the signal waits for the block
    assert done == ["renamed"]


def test_unet_options_without_a_unet_and_zero_threads_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--model with --method classical was silently ignored; --threads 0 printed argparse's
    usage line before its error."""
    out = tmp_path / "cal"
    model = str(Path(__file__).resolve().parents[1] / "models" / "contact_unet.onnx")
    argv = ["calibrate", MANIFEST, "--method", "classical", "--model", model, "--out", str(out)]
    assert main(argv) == 2
    err = _one_error(capsys)
    assert "--model applies to the U-Net only" in err
    assert err.endswith("or add --overlay DIR (it draws the U-Net's outline too)"), err
    video = ["calibrate", "--video", "v.avi", "--pressure-log", "log.csv", *argv[2:]]
    assert main(video) == 2  # no --overlay with a video: its --preview is offered
    err = _one_error(capsys)
    assert err.endswith(
        "drop it, use --method unet, or add --preview (it draws the U-Net's outline)"
    )
    assert main(["calibrate", MANIFEST, "--threads", "0", "--out", str(out)]) == 2
    n = os.cpu_count() or 1
    want = f"expected 1-{n} (this machine has {n} CPUs)"
    assert _one_error(capsys) == f"contactcal: error: --threads 0: {want}"
    # a slip of the finger started 100000 OpenCV threads (16 GB) before: refused first
    assert main(["calibrate", MANIFEST, "--threads", "100000", "--out", str(out)]) == 2
    assert _one_error(capsys) == f"contactcal: error: --threads 100000: {want}"
    assert not out.exists()


class _FullStdout(io.StringIO):
    """A standard output on a full disk."""

    def write(self, text: str) -> int:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.parametrize("command", ["measure", "calibrate"])
def test_a_failing_standard_output_is_named(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    monkeypatch.setattr(sys, "stdout", _FullStdout())
    if command == "measure":
        argv = ["measure", str(EXAMPLE / "p05.0kpa.jpg"), "--mm-per-px", "0.02", "--out", "-"]
    else:
        argv = ["calibrate", MANIFEST, "--out", str(tmp_path / "cal")]
    assert main([*argv, "--method", "classical"]) == 2
    line = _one_error(capsys)
    assert "writing to standard output failed (No space left on device)" in line
    assert "[Errno" not in line


def test_measure_writes_only_a_json_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``measure --out`` must end in .json (or be -): a manifest's name was replaced by JSON."""
    manifest = tmp_path / "manifest.csv"
    manifest.write_text("file,pressure_kpa\n")
    frame = str(EXAMPLE / "p05.0kpa.jpg")
    for out, why in ((manifest, "a name like a manifest's"), (tmp_path / "x.png", "an image name")):
        assert main(["measure", "--method", "classical", "--out", str(out), frame]) == 2
        line = _one_error(capsys)
        assert f"--out {out}: expected a JSON file name ending in .json" in line and why in line
    assert manifest.read_text() == "file,pressure_kpa\n"
    assert not (tmp_path / "x.png").exists()


def test_no_standard_output_at_all_is_not_an_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Started with stdout closed (``>&-``: ``sys.stdout is None``), a run writes its outputs
    and exits 0, as ``print`` does nothing then; it used to end in an AttributeError."""
    monkeypatch.setattr(sys, "stdout", None)
    out = tmp_path / "m.json"
    argv = ["measure", str(EXAMPLE / "p05.0kpa.jpg"), "--method", "classical", "--out", str(out)]
    assert main(argv) == 0
    assert json.loads(out.read_text())[0]["contact"] is True
    assert main([*argv[:-1], "-"]) == 2  # --out -: where its JSON would go is closed


def test_a_full_standard_output_inside_a_run_keeps_its_own_message(tmp_path: Path) -> None:
    """A :class:`StdoutError` raised while a run's outputs are staged is not renamed to the
    output folders' "no room" message (it names standard output already), and an OSError that
    is not renamed is re-raised as it was (it was made its own cause)."""
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.files.stdout import StdoutError

    with pytest.raises(StdoutError, match="writing to standard output failed"):
        with run_outputs() as outs:
            outs.stage(tmp_path / "a.json").write_text("{}")
            raise StdoutError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert not (tmp_path / "a.json").exists()
    with pytest.raises(FileNotFoundError) as caught:
        with run_outputs():
            raise FileNotFoundError(errno.ENOENT, "gone", "x.png")
    assert caught.value.__cause__ is None  # not itself


def test_a_linked_manifest_reads_the_rig_json_of_its_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Frames are found beside the manifest file a link points to; so is its rig.json (not a
    rig.json beside the link). Without any scale, the run says its areas are in px, and
    load_curve refuses to take them as mm²."""
    from contactcal.infer.calibration.load import load_curve

    linked = tmp_path / "elsewhere"
    linked.mkdir()
    (linked / "rig.json").write_text('{"mm_per_px": 0.05, "image_width_px": 400}')
    (linked / "manifest.csv").symlink_to(EXAMPLE / "manifest.csv")
    direct, via_link = tmp_path / "direct", tmp_path / "link"
    assert main(["calibrate", MANIFEST, "--method", "classical", "--out", str(direct)]) == 0
    argv = ["calibrate", str(linked / "manifest.csv"), "--method", "classical"]
    assert main([*argv, "--out", str(via_link)]) == 0
    assert "no pixel scale" not in capsys.readouterr().out
    a, b = (json.loads((d / "calibration.json").read_text()) for d in (direct, via_link))
    assert b["area_unit"] == "mm²" and a["steps"] == b["steps"]
    bare = tmp_path / "bare"
    bare.mkdir()
    frames = [f"{EXAMPLE / n},{p}" for n, p in (("p00.0kpa.jpg", 0), ("p10.0kpa.jpg", 10))]
    frames += [f"{EXAMPLE / f'p{k:04.1f}kpa.jpg'},{k}" for k in (4, 6, 8, 12, 16, 20)]
    (bare / "m.csv").write_text("file,pressure_kpa\n" + "\n".join(frames) + "\n")
    out = tmp_path / "px"
    assert main(["calibrate", str(bare / "m.csv"), "--method", "classical", "--out", str(out)]) == 0
    assert "note: no pixel scale" in capsys.readouterr().out
    assert load_curve(out / "calibration.json", area_unit="px").area_unit == "px"
    with pytest.raises(ValueError, match="its areas are in px, expected mm²"):
        load_curve(out / "calibration.json", area_unit="mm²")


@pytest.mark.parametrize("method", ["classical", "unet"])
def test_a_dark_reference_frame_is_refused(
    method: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A black 0 kPa frame (lights off, lens cap) in a lit session: one line naming it, exit 2,
    instead of a run whose change gate compares with black and whose ROIs come from each frame."""
    import shutil

    import cv2
    import numpy as np

    session = tmp_path / "s"
    shutil.copytree(EXAMPLE, session)
    cv2.imwrite(str(session / "p00.0kpa.jpg"), np.zeros((300, 400), np.uint8))
    out = tmp_path / "out"
    argv = ["calibrate", str(session / "manifest.csv"), "--method", method, "--out", str(out)]
    assert main(argv) == 2
    line = _one_error(capsys)
    assert str(session / "p00.0kpa.jpg") in line and "shows no window ring" in line
    assert not out.exists()


def test_bit_depth_out_of_range_and_an_empty_manifest_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frame = str(EXAMPLE / "p05.0kpa.jpg")
    assert main(["measure", frame, "--bit-depth", "17", "--out", str(tmp_path / "m.json")]) == 2
    assert _one_error(capsys).startswith("contactcal: error: --bit-depth 17: expected 1-16")
    empty = tmp_path / "m.csv"
    empty.write_text("file,pressure_kpa\n")
    assert main(["calibrate", str(empty), "--out", str(tmp_path / "c")]) == 2
    assert "under the header 'file,pressure_kpa'" in _one_error(capsys)


class _FullOnFlush(io.StringIO):
    """A block-buffered standard output on a full disk: its writes fail when flushed."""

    def flush(self) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.parametrize("stream", [_FullStdout, _FullOnFlush])
@pytest.mark.parametrize("command", ["measure", "calibrate"])
def test_a_failing_standard_output_after_the_outputs_says_they_are_whole(
    command: str, stream: type, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """The summary printed after a run's outputs were moved into place failed with the bare
    "what it printed is incomplete" and exit 2, as if the run had written nothing; and the
    note on the calibration a run replaced, printed there, was lost."""
    out = tmp_path / ("m.json" if command == "measure" else "cal")
    frames = [str(EXAMPLE / "p05.0kpa.jpg")] if command == "measure" else [MANIFEST]
    argv = [command, *frames, "--method", "classical", "--out", str(out)]
    if command == "calibrate":  # an earlier calibration, which the failing run replaces
        assert main(argv) == 0
        capsys.readouterr()
    monkeypatch.setattr(sys, "stdout", stream())
    assert main(argv) == 2
    line = _one_error(capsys)
    assert "writing to standard output failed (No space left on device)" in line
    written = f"the run's outputs were written, whole: {out}"
    if command == "calibrate":
        assert f"{written}; replaced the calibration that {out} held (created " in line
    else:
        assert line.endswith(written)
    written = out if command == "measure" else out / "calibration.json"
    assert json.loads(written.read_text())


class _InterruptedStdout(io.StringIO):
    """Ctrl-C while the summary is printed (e.g. blocked on a stalled pipe)."""

    def write(self, text: str) -> int:
        raise KeyboardInterrupt


def test_an_interrupt_after_the_outputs_says_they_are_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """Ctrl-C while the summary was printed said "none was written" of a calibration already
    moved into place, and lost the note on the one it replaced."""
    out = tmp_path / "cal"
    argv = ["calibrate", MANIFEST, "--method", "classical", "--out", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    monkeypatch.setattr(sys, "stdout", _InterruptedStdout())
    assert main(argv) == 130
    line = _one_error(capsys)
    written = f"interrupted; the run's outputs were written, whole: {out}; replaced the calibration"
    assert written in line and "none was written" not in line
    assert json.loads((out / "calibration.json").read_text())

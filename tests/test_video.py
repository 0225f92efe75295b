"""``calibrate --video/--camera``: pressure log, steady steps, frame extraction, live capture.

The videos are made here from the example session's stills: each step's still held, with ramps
between steps (consecutive stills blended), and a pressure log sampled at 20 Hz with noise well
within the tolerance. Frames are written with FFV1 (lossless in this OpenCV build), so a kept
frame is pixel-identical to its still.
"""

from __future__ import annotations

import csv
import hashlib
import itertools
import json
import os
import re
from collections.abc import Sequence
from functools import partial
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.calibration.phases import LOADING, UNLOADING
from contactcal.infer.cli import main
from contactcal.infer.files.atomic import run_outputs
from contactcal.infer.video.coverage import check_coverage
from contactcal.infer.video.extract import (
    Extractor,
    extract_frames,
    open_video,
    video_frames,
)
from contactcal.infer.video.live import (
    LogPoller,
    capture_frames,
    open_camera,
    returned_to_zero,
)
from contactcal.infer.video.log import PressureLogError, read_pressure_log
from contactcal.infer.video.step_config import StepConfig
from contactcal.infer.video.steps import detect_steps, hold_scatter_kpa

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
FPS = 10.0
LOG_HZ = 20.0
NOISE_KPA = 0.03  # the log's noise on a held step: well within the default ±0.1 kPa
CFG = StepConfig(settle_s=0.3)


def _still(kpa: int) -> np.ndarray:
    return cv2.imread(str(EXAMPLE / f"p{kpa:04.1f}kpa.jpg"), cv2.IMREAD_COLOR)


def _segments(kpas: Sequence[int], hold_s: float, ramp_s: float) -> list[tuple[float, int]]:
    """Start time of each hold, in order; hold k lasts hold_s, then a ramp of ramp_s."""
    return [(k * (hold_s + ramp_s), p) for k, p in enumerate(kpas)]


def _pressure_at(
    t: float, kpas: Sequence[int], hold_s: float, ramp_s: float
) -> tuple[float, int, float]:
    """True pressure at t, the hold it follows and the ramp fraction (0 while held)."""
    period = hold_s + ramp_s
    k = min(int(t // period), len(kpas) - 1)
    into = t - k * period
    if into <= hold_s or k == len(kpas) - 1:
        return float(kpas[k]), k, 0.0
    a = (into - hold_s) / ramp_s
    return (1 - a) * kpas[k] + a * kpas[k + 1], k, a


def make_video(
    path: Path, kpas: Sequence[int], hold_s: float = 1.2, ramp_s: float = 0.5, fourcc: str = "FFV1"
) -> list[tuple[float, float]]:
    """Write the video; return each frame's (time, true pressure)."""
    stills = {p: _still(p) for p in set(kpas)}
    h, w = next(iter(stills.values())).shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), FPS, (w, h))
    assert writer.isOpened()
    n = round(len(kpas) * (hold_s + ramp_s) * FPS)
    frames = []
    for i in range(n):
        t = i / FPS
        p, k, a = _pressure_at(t, kpas, hold_s, ramp_s)
        img = stills[kpas[k]]
        if a > 0:
            img = cv2.addWeighted(img, 1 - a, stills[kpas[k + 1]], a, 0.0)
        writer.write(img)
        frames.append((t, p))
    writer.release()
    return frames


def make_log(
    path: Path,
    kpas: Sequence[int],
    rng: np.random.Generator,
    hold_s: float = 1.2,
    ramp_s: float = 0.5,
    extra_s: float = 0.0,
    offset_kpa: float = 0.0,
) -> None:
    """The controller's log of the same run (samples offset from the frames by 1/40 s), the
    gauge reading ``offset_kpa`` above the true pressure."""
    end = len(kpas) * (hold_s + ramp_s) + extra_s
    lines = ["time_s,pressure_kpa,setpoint_kpa"]
    for t in np.arange(0.025, end, 1 / LOG_HZ):
        p, k, _ = _pressure_at(float(t), kpas, hold_s, ramp_s)
        noisy = p + offset_kpa + rng.uniform(-NOISE_KPA, NOISE_KPA)
        lines.append(f"{t:.4f},{noisy:.4f},{kpas[k]}")
    path.write_text("\n".join(lines) + "\n")


def _extract_warned(
    video: Path, log: Path, out: Path, cfg: StepConfig = CFG, live: bool = False
) -> tuple[Extractor, list[str]]:
    """Extract and check as ``calibrate --video`` does (``live``: as a camera run): the
    extractor and the warnings printed under the table."""
    with run_outputs([video, log]) as outs:
        ex = Extractor(cfg, out / "frames", outs.stage)
        logs = iter([read_pressure_log(log)])
        extract_frames(video_frames(open_video(video)), ex, lambda: next(logs, None))
        warnings = check_coverage(ex, None if live else video)
        (out / "frames").mkdir(parents=True, exist_ok=True)
        (out / "frames" / "manifest.csv").write_text(ex.manifest_text())
    return ex, warnings


def _extract(video: Path, log: Path, out: Path, cfg: StepConfig = CFG) -> Extractor:
    return _extract_warned(video, log, out, cfg)[0]


def test_log_validation(tmp_path: Path) -> None:
    bad = {
        "time_s,pressure\n0,1\n": "lacks column",
        "time_s,pressure_kpa\n0,1\n1,nan\n": "row 2: pressure_kpa 'nan'",
        "time_s,pressure_kpa\n0,1\n2,1\n1,1\n": "row 3: time_s 1 is not after",
        "time_s,pressure_kpa\n0,1\n1,1500\n": "row 2: pressure_kpa 1500 is outside",
        "time_s,pressure_kpa\n": "no samples",
    }
    for k, (text, expected) in enumerate(bad.items()):
        path = tmp_path / f"log{k}.csv"
        path.write_text(text)
        with pytest.raises(PressureLogError, match=expected) as err:
            read_pressure_log(path)
        assert str(path) in str(err.value)


def test_steps_up_and_down(tmp_path: Path, rng: np.random.Generator) -> None:
    kpas = [0, 2, 4, 6, 4, 2, 0]
    make_log(tmp_path / "log.csv", kpas, rng)
    steps = detect_steps(read_pressure_log(tmp_path / "log.csv"), CFG)
    assert [round(s.pressure_kpa) for s in steps] == kpas
    assert [s.phase for s in steps] == [LOADING] * 4 + [UNLOADING] * 3
    for k, (s, (start, _)) in enumerate(zip(steps, _segments(kpas, 1.2, 0.5), strict=True)):
        assert abs(s.pressure_kpa - round(s.pressure_kpa)) <= NOISE_KPA
        # settling skipped: the ramp enters the step's band (2 × tolerance) just before the hold
        slope = abs(kpas[k] - kpas[k - 1]) / 0.5 if k else np.inf
        assert s.start_s >= start - 2 * CFG.tolerance_kpa / slope + CFG.settle_s


def test_extraction_groups_steps(tmp_path: Path, rng: np.random.Generator) -> None:
    kpas = [0, 5, 10, 5, 0]
    truth = make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    ex = _extract(tmp_path / "v.avi", tmp_path / "log.csv", tmp_path / "out")
    with open(tmp_path / "out" / "frames" / "manifest.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["file", "pressure_kpa", "phase", "time_s"]
    by_step = [
        list(g) for _, g in itertools.groupby(rows, key=lambda r: r["pressure_kpa"] + r["phase"])
    ]
    phases = [LOADING] * 3 + [UNLOADING] * 2
    assert [(round(float(g[0]["pressure_kpa"])), g[0]["phase"]) for g in by_step] == list(
        zip(kpas, phases, strict=True)
    )
    for group, (start, kpa) in zip(by_step, _segments(kpas, 1.2, 0.5), strict=True):
        times = [float(r["time_s"]) for r in group]
        # every kept frame: after the settle time, at a true pressure within the tolerance
        assert min(times) >= start + CFG.settle_s
        for t in times:
            true = truth[round(t * FPS)][1]
            assert abs(true - kpa) <= CFG.tolerance_kpa + NOISE_KPA
        held = [t for t, p in truth if start + CFG.settle_s <= t <= start + 1.2]
        assert len(group) >= len(held) - 2  # at most one lost at each end to the log sampling
        still = _still(kpa)
        pure = [r for r in group if float(r["time_s"]) <= start + 1.2]
        for r in pure:  # lossless: the kept frame is the still
            assert np.array_equal(cv2.imread(str(tmp_path / "out" / "frames" / r["file"])), still)
    assert sum(len(v) for v in ex.kept.values()) == len(rows)


def _capture_live(tmp_path: Path) -> Extractor:
    """The camera path on ``v.avi`` and ``log.csv`` in ``tmp_path``, with a fake clock (frame i
    arrives at i / FPS), stopping as ``calibrate --camera`` does."""
    ticks = itertools.count()
    clock = lambda: next(ticks) / FPS  # noqa: E731
    with run_outputs() as outs:
        live = Extractor(CFG, tmp_path / "live" / "frames", outs.stage)
        frames = capture_frames(cv2.VideoCapture(str(tmp_path / "v.avi")), clock)
        extract_frames(frames, live, LogPoller(tmp_path / "log.csv"), stop=returned_to_zero)
    return live


def test_live_capture_matches_file(tmp_path: Path, rng: np.random.Generator) -> None:
    """The camera path, fed a video file and a fake clock, keeps the file path's frames and
    stops once the log is back at 0 kPa (at rest) (the video's trailing frames are not read)."""
    kpas = [0, 4, 8, 4, 0, 0, 0]  # a long final rest: the capture stops before its end
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    by_file = _extract(tmp_path / "v.avi", tmp_path / "log.csv", tmp_path / "file")
    live = _capture_live(tmp_path)
    assert live.last_time_s < by_file.last_time_s - 1.0  # stopped early
    for step, kept in live.kept.items():
        assert kept == by_file.kept[step][: len(kept)]
        assert len(kept) == len(by_file.kept[step]) or step == max(live.kept)
    last = live.kept[max(live.kept)]
    assert live.steps[max(live.kept)].pressure_kpa < CFG.tolerance_kpa
    assert last[-1][1] - last[0][1] >= CFG.settle_s


def test_live_capture_stops_at_rest_offset(tmp_path: Path, rng: np.random.Generator) -> None:
    """A gauge reading 0.15 kPa at rest (above --tolerance-kpa, within REST_KPA) still stops
    the capture once the log is back at rest after the highest step."""
    kpas = [0, 4, 8, 4, 0, 0, 0]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng, offset_kpa=0.15)
    live = _capture_live(tmp_path)
    end_s = len(kpas) * (1.2 + 0.5)
    assert live.last_time_s < end_s - 1.0  # stopped early, not at the video's end
    last = live.steps[max(live.kept)]
    assert CFG.tolerance_kpa < last.pressure_kpa < 0.5 and last.index > 2


def test_live_capture_goes_on_past_a_low_unloading_step(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    """An unloading step at 0.4 kPa (within REST_KPA, above the 0 kPa reference's band) does
    not stop the capture: its 0 kPa step comes next and is captured."""
    kpas = [0, 4, 8, 4, 0, 0, 0, 0]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", [0, 4, 8, 4, 0.4, 0, 0, 0], rng)
    live = _capture_live(tmp_path)
    kept = sorted(live.steps[i].pressure_kpa for i in live.kept)
    assert kept[0] < 2 * CFG.tolerance_kpa and any(0.3 < p < 0.5 for p in kept)
    assert live.last_time_s < len(kpas) * (1.2 + 0.5) - 1.0  # still stopped early
    last = live.steps[max(live.kept)]
    assert last.pressure_kpa < 2 * CFG.tolerance_kpa and last.index > 4


def _unreachable(*args: object) -> None:
    raise AssertionError(f"not to be reached: {args}")


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(argv)
    return code, capsys.readouterr().err


def test_bad_inputs_exit_2(
    tmp_path: Path,
    rng: np.random.Generator,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    kpas = [0, 5, 10]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    (tmp_path / "bad.avi").write_bytes(b"not a video")
    (tmp_path / "vids").mkdir()
    lines = (tmp_path / "log.csv").read_text().splitlines()
    (tmp_path / "nocol.csv").write_text("\n".join(["time_s,kpa", *lines[1:]]) + "\n")
    (tmp_path / "unsorted.csv").write_text("\n".join([*lines[:3], lines[2], *lines[3:]]) + "\n")
    make_log(tmp_path / "long.csv", [*kpas, 5], rng)  # a step after the video's end
    ramp = [f"{t:.1f},{t:.1f},{t:.1f}" for t in range(6)]  # 1 Hz, never steady
    (tmp_path / "sparse.csv").write_text("\n".join([lines[0], *ramp]) + "\n")
    for name in ("null.avi", "null.csv"):  # a device: /dev/zero would be read forever
        (tmp_path / name).symlink_to(os.devnull)
    os.mkfifo(tmp_path / "fifo.csv")  # reading it would wait for a writer forever
    odd = "not a regular file (a device, pipe or socket); expected"
    out = tmp_path / "out"
    cases = {
        ("v.avi", "sparse.csv"): "6 samples, 1.00 s apart (median)",
        ("null.avi", "log.csv"): f"null.avi: {odd} a video file",
        ("v.avi", "null.csv"): f"null.csv: {odd} the pressure log",
        ("v.avi", "fifo.csv"): f"fifo.csv: {odd} the pressure log",
        ("bad.avi", "log.csv"): "bad.avi: cannot be read as a video",
        ("missing.avi", "log.csv"): "missing.avi: video not found",
        ("vids", "log.csv"): "vids: is a folder; expected a video file",
        ("v.avi", "nocol.csv"): "lacks column(s) ['pressure_kpa']",
        ("v.avi", "unsorted.csv"): "row 3: time_s",
        ("v.avi", "long.csv"): "ends at 5.00 s, before step 5 kPa (unloading",
    }
    for (video, log), expected in cases.items():
        argv = [
            "calibrate",
            "--video",
            str(tmp_path / video),
            "--pressure-log",
            str(tmp_path / log),
        ]
        code, err = _run([*argv, "--out", str(out), "--method", "classical"], capsys)
        assert code == 2 and expected in err and err.count("\n") == 1, err
        assert not out.exists()
    for unit, per_kpa, top in (("bar", 100, "0.10"), ("MPa", 1000, "0.010")):  # not kPa
        rows = [
            f"{t},{float(p) / per_kpa:.6f},{s}" for t, p, s in (r.split(",") for r in lines[1:])
        ]
        (tmp_path / f"{unit}.csv").write_text("\n".join([lines[0], *rows]) + "\n")
        argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
        argv += [str(tmp_path / f"{unit}.csv"), "--out", str(out), "--method", "classical"]
        with monkeypatch.context() as m:  # refused before a frame of the video is read
            m.setattr(cv2, "VideoCapture", _unreachable)
            code, err = _run(argv, capsys)
        expected = f"{tmp_path / unit}.csv: the highest pressure_kpa is {top}"  # a reading
        assert code == 2 and expected in err and err.count("\n") == 1, err  # the log's name
        assert "below 1 kPa; expected a sweep in kPa" in err and not out.exists()
    for argv in (
        ["calibrate", str(EXAMPLE / "manifest.csv"), "--video", str(tmp_path / "v.avi")],
        ["calibrate", "--video", str(tmp_path / "v.avi")],
        ["calibrate", "--pressure-log", str(tmp_path / "log.csv")],
        [
            "calibrate",
            "--video",
            str(tmp_path / "v.avi"),
            "--pressure-log",
            str(tmp_path / "log.csv"),
            "--step-tolerance-kpa",
            "0.2",
        ],
    ):
        code, err = _run([*argv, "--out", str(out)], capsys)
        assert code == 2 and err.startswith("contactcal: error: calibrate:"), err
    assert not out.exists()


def test_video_areas_equal_stills(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    """The video path measures exactly what ``calibrate MANIFEST`` measures on the stills: FFV1
    is lossless, so every kept frame's area equals its still's (relative difference 0)."""
    kpas = [0, 3, 6, 12, 20]
    make_video(tmp_path / "v.avi", kpas, hold_s=0.8)
    make_log(tmp_path / "log.csv", kpas, rng, hold_s=0.8)
    stills = tmp_path / "stills.csv"
    stills.write_text(
        "file,pressure_kpa\n" + "".join(f"{EXAMPLE}/p{p:04.1f}kpa.jpg,{p}\n" for p in kpas)
    )
    from contactcal.infer.files.digest import sha256_file
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    scale = json.loads((EXAMPLE / "rig.json").read_text())
    offset = {"boundary_offset_mm": 0.1, "boundary_offset_model_sha256": sha256_file(DEFAULT_MODEL)}
    (tmp_path / "rig.json").write_text(json.dumps({**scale, **offset}))  # the offset applies too
    rig = ["--rig", str(tmp_path / "rig.json")]
    assert main(["calibrate", str(stills), "--out", str(tmp_path / "st"), *rig]) == 0
    argv = ["--video", str(tmp_path / "v.avi"), "--pressure-log", str(tmp_path / "log.csv")]
    out = tmp_path / "vid"
    assert (
        main(["calibrate", *argv, "--settle-s", "0.3", "--preview", "--out", str(out), *rig]) == 0
    )
    assert "frames" in capsys.readouterr().out
    still_area = {
        round(p["pressure_kpa"]): p["area_px"]
        for p in json.loads((tmp_path / "st" / "calibration.json").read_text())["points"]
    }
    record = json.loads((out / "calibration.json").read_text())
    assert record["extra"]["boundary_offset_mm"] == 0.1
    points = record["points"]
    final = (out / "frames" / "manifest.csv").resolve()  # recorded where it stays, not staged
    assert record["extra"]["manifest"] == str(final) == record["inputs"]["manifest"]["file"]
    assert (final.parent / record["extra"]["reference_frame"]).is_file()  # not a staged path
    assert final.is_file()
    assert {round(p["pressure_kpa"]) for p in points} == set(kpas) and len(points) > 3 * len(kpas)
    for p in points:
        assert p["area_px"] == still_area[round(p["pressure_kpa"])]
    cap = cv2.VideoCapture(str(next(out.glob("preview.*"))))
    assert cap.isOpened() and cap.read()[0]


def test_the_record_names_the_video_and_the_log_with_their_sha256(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    """A lab auditing a calibration can tell which recording and which log produced it: the
    video's and the pressure log's paths and sha256 are in ``inputs.recording`` (they were only
    in ``argv``)."""
    kpas = [0, 4, 8, 12]
    make_video(tmp_path / "v.avi", kpas, hold_s=0.8)
    make_log(tmp_path / "log.csv", kpas, rng, hold_s=0.8)
    argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
    argv += [str(tmp_path / "log.csv"), "--settle-s", "0.3", "--out", str(tmp_path / "cal")]
    assert main(argv) == 0, capsys.readouterr().err
    record = json.loads((tmp_path / "cal" / "calibration.json").read_text())

    def sha(name: str) -> str:
        return hashlib.sha256((tmp_path / name).read_bytes()).hexdigest()

    assert record["inputs"]["recording"] == {
        "video": {"file": str((tmp_path / "v.avi").resolve()), "sha256": sha("v.avi")},
        "camera": None,
        "pressure_log": {"file": str((tmp_path / "log.csv").resolve()), "sha256": sha("log.csv")},
    }


def test_a_video_changed_after_it_was_hashed_is_refused(tmp_path: Path) -> None:
    """The recorded sha256 is taken before decoding: a file that changed by the end of its
    decoding (here: written on) is refused, naming it, rather than recorded with a stale digest."""
    make_video(tmp_path / "v.avi", [0, 4], hold_s=0.2, ramp_s=0.1)
    video = open_video(tmp_path / "v.avi")
    with open(tmp_path / "v.avi", "ab") as fh:
        fh.write(b"more")
    with pytest.raises(ValueError, match=r"v\.avi: the video changed while it was read"):
        list(video_frames(video))


def test_a_camera_run_records_its_index_and_the_log_as_parsed(
    tmp_path: Path,
    rng: np.random.Generator,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera run (fed ``v.avi`` with a fake clock) records the camera's index and the sha256
    of the log's bytes it parsed: its last read, a row still being written left out."""
    kpas = [0, 4, 8, 4, 0, 0, 0]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    whole = (tmp_path / "log.csv").read_bytes()
    (tmp_path / "log.csv").write_bytes(whole + b"99.0,0.0")  # a row still being written
    ticks = itertools.count()
    fake = partial(capture_frames, clock=lambda: next(ticks) / FPS)
    camera = lambda i: cv2.VideoCapture(str(tmp_path / "v.avi"))  # noqa: E731
    monkeypatch.setattr("contactcal.infer.video.live.open_camera", camera)
    monkeypatch.setattr("contactcal.infer.video.live.capture_frames", fake)
    argv = ["calibrate", "--camera", "0", "--pressure-log", str(tmp_path / "log.csv")]
    assert main([*argv, "--settle-s", "0.3", "--out", str(tmp_path / "cal")]) == 0, (
        capsys.readouterr().err
    )
    record = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert record["inputs"]["recording"] == {
        "video": None,
        "camera": 0,
        "pressure_log": {
            "file": str((tmp_path / "log.csv").resolve()),
            "sha256": hashlib.sha256(whole).hexdigest(),
        },
    }


def test_staging_left_by_a_killed_run_is_no_earlier_recording(tmp_path: Path) -> None:
    """A ``frames/`` folder holding only the staging entries of a killed run (SIGKILL: its
    process gone) is fresh: they are removed; a running process's staging is refused, said."""
    import os
    import subprocess
    import sys

    from contactcal.infer.video.fresh_out import check_fresh_frames

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    frames = tmp_path / "out" / "frames"
    (frames / f".f000005.png.{dead.pid}.abc123.tmp").mkdir(parents=True)
    (frames / f".f000005.png.{dead.pid}.abc123.tmp" / "f000005.png").write_bytes(b"x")
    (frames / f".manifest.csv.{dead.pid}.x_9.tmp").write_text("partial")
    check_fresh_frames(frames)
    assert list(frames.iterdir()) == []
    (frames / f".f000001.png.{os.getpid()}.live.tmp").mkdir()  # a run still going
    with pytest.raises(ValueError, match=f"another run \\(process {os.getpid()}\\)"):
        check_fresh_frames(frames)
    (frames / "f000001.png").write_bytes(b"x")  # a frame: an earlier recording
    with pytest.raises(ValueError, match="holds the frames of an earlier recording"):
        check_fresh_frames(frames)


def test_a_preview_of_an_earlier_recording_is_refused(
    tmp_path: Path,
    rng: np.random.Generator,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An --out whose frames/ the user removed but which still holds an earlier recording's
    preview is refused before any work: a run without --preview would leave that preview beside
    its calibration. The line names the file and what to do; nothing is written."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "preview.mp4").write_bytes(b"earlier")
    make_log(tmp_path / "log.csv", [0, 6, 12, 0], rng, hold_s=0.8)
    argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
    argv += [str(tmp_path / "log.csv"), "--out", str(out)]
    with monkeypatch.context() as m:  # refused before the video is opened
        m.setattr(cv2, "VideoCapture", _unreachable)
        code, err = _run(argv, capsys)
    expected = f"{out / 'preview.mp4'}: the preview of an earlier recording; expected a new "
    expected += "--out folder for each recording (or remove that file first)"
    assert code == 2 and expected in err and err.count("\n") == 1, err
    assert [p.name for p in out.iterdir()] == ["preview.mp4"]
    assert (out / "preview.mp4").read_bytes() == b"earlier"
    from contactcal.infer.video.fresh_out import check_fresh_recording

    (out / "preview.avi").write_bytes(b"earlier")  # both formats: both named
    with pytest.raises(ValueError, match=r"preview\.mp4 and .*preview\.avi: .*those files first"):
        check_fresh_recording(out)


def test_a_vent_to_zero_is_left_out_and_a_rerun_is_refused(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    """Up in steps, then straight back to 0 kPa: the one-pressure unloading pass is no curve, so
    it is left out (said), not a failed run; a second recording into the same --out is refused."""
    kpas = [0, 6, 12, 0]
    make_video(tmp_path / "v.avi", kpas, hold_s=0.8)
    make_log(tmp_path / "log.csv", kpas, rng, hold_s=0.8)
    out = tmp_path / "out"
    argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
    code, err = _run([*argv, str(tmp_path / "log.csv"), "--out", str(out)], capsys)
    assert code == 0, err
    assert "left out: a one-pressure unloading pass is no curve" in err
    rows = (out / "frames" / "manifest.csv").read_text().splitlines()[1:]
    assert {r.split(",")[2] for r in rows} == {"loading"}
    record = json.loads((out / "calibration.json").read_text())
    steps = sorted({round(p["pressure_kpa"]) for p in record["points"]})
    assert steps == [0, 6, 12]  # the logged pressures (noise ±0.02 kPa)
    code, err = _run([*argv, str(tmp_path / "log.csv"), "--out", str(out)], capsys)
    assert code == 2 and "holds the frames of an earlier recording" in err, err
    manifest = str(EXAMPLE / "manifest.csv")  # a stills calibration there first: said, replaced
    stills = tmp_path / "stills"
    assert main(["calibrate", manifest, "--method", "classical", "--out", str(stills)]) == 0
    capsys.readouterr()
    scaled = ["--mm-per-px", "0.05"]  # its record is in mm² (a run without a scale is refused)
    assert main([*argv, str(tmp_path / "log.csv"), *scaled, "--out", str(stills)]) == 0
    assert f"note: replaced the calibration that {stills} held (created " in capsys.readouterr().out
    for flat, expected in (  # one steady step only: at rest (no sweep), or at 5 kPa
        ([0, 0], "flat.csv: the highest pressure_kpa is 0.0"),
        ([5, 5], "flat.csv: the steady steps found hold 1 loading pressure"),
    ):
        make_log(tmp_path / "flat.csv", flat, rng, hold_s=0.8)
        make_video(tmp_path / "flat.avi", flat, hold_s=0.8)
        argv = ["calibrate", "--video", str(tmp_path / "flat.avi"), "--pressure-log"]
        code, err = _run([*argv, str(tmp_path / "flat.csv"), "--out", str(tmp_path / "f")], capsys)
        assert code == 2 and expected in err, err
        assert not (tmp_path / "f").exists()


def test_missing_camera_is_one_line(capfd: pytest.CaptureFixture[str]) -> None:
    level = cv2.utils.logging.getLogLevel()
    with pytest.raises(ValueError, match="camera 97: cannot be opened"):
        open_camera(97)
    err = capfd.readouterr().err
    assert "WARN" not in err and "[ERROR" not in err  # OpenCV's backend messages held back
    assert cv2.utils.logging.getLogLevel() == level
    with pytest.raises(ValueError, match=r"--camera -1: expected a camera index >= 0"):
        open_camera(-1)  # OpenCV's "any camera": a segmentation fault with OpenCV 5.0


def _log_file(path: Path, times: np.ndarray, kpa: np.ndarray) -> Path:
    rows = "".join(f"{t:.4f},{p:.4f}\n" for t, p in zip(times, kpa, strict=True))
    path.write_text("time_s,pressure_kpa\n" + rows)
    return path


def test_a_log_too_noisy_for_the_tolerance_is_said(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    """A log scattering by ±0.12 kPa at its holds splits or loses them at --tolerance-kpa 0.1:
    the run says so with a tolerance that holds them (under the table, or in the error of a run
    it stopped), and with it all three steps are found; the test's usual ±0.03 kPa log, and a
    log rounded to 0.1 kPa flickering between two values at x.05 kPa, get no warning."""
    kpas = [0, 5, 10]
    make_video(tmp_path / "v.avi", kpas)
    t = np.arange(0.025, 5.1, 1 / LOG_HZ)
    true = np.array([_pressure_at(float(x), kpas, 1.2, 0.5)[0] for x in t])
    logs = {
        "usual": (true + rng.uniform(-NOISE_KPA, NOISE_KPA, t.size), False),
        "rounded": (np.round(true + 0.05 + rng.normal(0, 0.02, t.size), 1), False),
        "noisy": (true + rng.uniform(-0.12, 0.12, t.size), True),
    }
    said = "too much for --tolerance-kpa 0.1 (a band of ±0.1)"
    for name, (p, warned) in logs.items():
        log = _log_file(tmp_path / f"{name}.csv", t, p)
        scatter = hold_scatter_kpa(read_pressure_log(log), CFG)
        assert (scatter > 0.15) is warned, (name, scatter)
        try:
            ex, warnings = _extract_warned(tmp_path / "v.avi", log, tmp_path / f"out_{name}")
            text = " ".join(warnings)
        except ValueError as exc:  # a lost hold may stop the run: the finding is in its error
            text = str(exc)
        assert (said in text) is warned, (name, text)
        if not warned:
            found = sorted({s.pressure_kpa for s in ex.used_steps()})
            assert found == pytest.approx([0.0, 5.0, 10.0], abs=0.1) and not warnings, name
    given = float(text.split("give --tolerance-kpa ")[1].split()[0])
    fixed = StepConfig(given, CFG.settle_s)
    ex, warnings = _extract_warned(tmp_path / "v.avi", log, tmp_path / "out_fixed", fixed)
    found = sorted({s.pressure_kpa for s in ex.used_steps()})
    assert found == pytest.approx([0.0, 5.0, 10.0], abs=0.1) and not warnings


def test_a_sliver_of_the_log_between_two_frames_is_left_out_with_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """With --settle-s 0, a pause of two log samples (0.05 s) inside a ramp is a step no frame
    falls in: left out, said, rather than stopping the run as a video that misses a step."""
    kpas = [0, 5, 10]
    make_video(tmp_path / "v.avi", kpas)
    t = np.arange(0.025, 5.1, 1 / LOG_HZ)
    p = np.array([_pressure_at(float(x), kpas, 1.2, 0.5)[0] for x in t])
    pause = (t > 1.42) & (t < 1.48)  # two samples in the first ramp
    p[pause] = 2.2
    log = _log_file(tmp_path / "log.csv", t, p)
    ex = _extract(tmp_path / "v.avi", log, tmp_path / "out", StepConfig(settle_s=0.0))
    assert "note: step 2.2 kPa (loading, 1.43-1.48 s) of " in capsys.readouterr().err
    assert sorted({s.pressure_kpa for s in ex.used_steps()}) == [0.0, 5.0, 10.0]


def test_a_frameless_sliver_above_the_top_does_not_split_the_passes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A two-sample spike to 10.3 kPa on the way up to the 10 kPa hold is the log's highest
    step but holds no frame: the passes split at the 10 kPa hold, which stays loading."""
    kpas = [0, 5, 10, 5, 0]
    make_video(tmp_path / "v.avi", kpas)
    t = np.arange(0.025, 8.6, 1 / LOG_HZ)
    p = np.array([_pressure_at(float(x), kpas, 1.2, 0.5)[0] for x in t])
    p[(t > 3.1) & (t < 3.2)] = 10.3  # two samples in the ramp from 5 to 10 kPa
    log = _log_file(tmp_path / "log.csv", t, p)
    ex = _extract(tmp_path / "v.avi", log, tmp_path / "out", StepConfig(settle_s=0.0))
    assert "note: step 10.3 kPa (loading" in capsys.readouterr().err
    used = [(s.pressure_kpa, s.phase) for s in ex.used_steps()]
    assert used == [
        (0.0, LOADING),
        (5.0, LOADING),
        (10.0, LOADING),
        (5.0, UNLOADING),
        (0.0, UNLOADING),
    ]


def test_step_findings_name_the_option_and_a_second_cycle_is_refused(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    """A second loading cycle (read as unloading) is refused for a video, warned for a camera
    run; a settle time as long as the holds, neighbouring holds within the band and a glitch
    splitting a hold are warned, each naming what to check or the option that helps."""
    cycles = [0, 5, 10, 5, 0, 5, 10, 0]
    make_video(tmp_path / "two.avi", cycles)
    make_log(tmp_path / "two.csv", cycles, rng)
    cycle = r"two\.csv: the pressure (rises|falls) from .* not one cycle"
    with pytest.raises(ValueError, match=cycle):
        _extract(tmp_path / "two.avi", tmp_path / "two.csv", tmp_path / "o1")
    _, warnings = _extract_warned(
        tmp_path / "two.avi", tmp_path / "two.csv", tmp_path / "o1l", live=True
    )
    assert any("not one cycle" in w for w in warnings)
    kpas = [0, 5, 10, 5, 0]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    log, video = tmp_path / "log.csv", tmp_path / "v.avi"
    for cfg, said in (
        (StepConfig(0.1, 1.2), r"not over --settle-s 1.2 .* give a --settle-s below"),
        (StepConfig(3.0, 0.3), r"within the band of --tolerance-kpa 3 .* below half"),
    ):
        try:
            text = " ".join(_extract_warned(video, log, tmp_path / f"o{cfg.settle_s}", cfg)[1])
        except ValueError as exc:
            text = str(exc)
        assert re.search(said, text), (said, text)
    ex, warnings = _extract_warned(video, log, tmp_path / "o4")
    assert len(ex.used_steps()) == 5 and not warnings
    t = np.arange(0.025, 5 * 1.7, 1 / LOG_HZ)  # a one-sample glitch of +0.4 kPa in the 5 kPa hold
    p = np.array([_pressure_at(float(x), kpas, 1.2, 0.5)[0] for x in t])
    p += rng.uniform(-NOISE_KPA, NOISE_KPA, t.size)
    p[np.argmin(np.abs(t - 2.3))] += 0.4
    glitch = _log_file(tmp_path / "glitch.csv", t, p)
    _, warnings = _extract_warned(video, glitch, tmp_path / "o5")
    assert (
        len(warnings) == 1
        and "less than --tolerance-kpa 0.1 apart: one hold split" in (warnings[0])
    )


def test_video_step_options_are_refused_for_a_manifest(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    manifest = str(EXAMPLE / "manifest.csv")
    for option in ("--tolerance-kpa", "--settle-s", "--preview", "--duration-s"):
        value = [] if option == "--preview" else ["1"]
        assert main(["calibrate", manifest, option, *value, "--out", str(tmp_path / "c")]) == 2
        err = capsys.readouterr().err
        # it said "expected MANIFEST.csv, or --video ..." as if no manifest had been given
        assert f"{option} is for --video/--camera, not for MANIFEST.csv" in err
        assert err.count("\n") == 1 and "expected MANIFEST" not in err
        assert ("pooled with --step-tolerance-kpa" in err) is (option == "--tolerance-kpa")
    for option, value in (("--preview", []), ("--settle-s", ["1"])):  # and no input at all
        assert main(["calibrate", option, *value, "--out", str(tmp_path / "c")]) == 2
        assert "expected MANIFEST.csv, or --video" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_a_run_error_names_the_manifest_the_run_writes_not_its_staging_copy(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    """A recording without contact (0-2 kPa) stops with exit 1; its message names the manifest
    where the run writes it, not the staging copy that is gone once the run stops."""
    kpas = [0, 1, 2, 1, 0]
    make_video(tmp_path / "v.avi", kpas)
    make_log(tmp_path / "log.csv", kpas, rng)
    out = tmp_path / "cal"
    argv = ["calibrate", "--video", str(tmp_path / "v.avi"), "--pressure-log"]
    assert main([*argv, str(tmp_path / "log.csv"), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{out / 'frames' / 'manifest.csv'}: " in err and ".tmp" not in err
    assert not (out / "frames").exists()


def test_a_truncated_video_gets_one_line_without_ffmpegs_own(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    """FFmpeg logs its decoder's complaint ("[mjpeg @ …] overread") itself; in a fresh process
    the video run quiets it, so the command's one line is all that stderr holds."""
    import os
    import subprocess
    import sys

    kpas = [0, 5, 10, 15, 20]
    make_video(tmp_path / "v.avi", kpas, fourcc="MJPG")
    make_log(tmp_path / "log.csv", kpas, rng)
    data = (tmp_path / "v.avi").read_bytes()
    (tmp_path / "half.avi").write_bytes(data[: len(data) // 2 + 1001])  # cut inside a frame
    env = {k: v for k, v in os.environ.items() if k != "OPENCV_FFMPEG_LOGLEVEL"}
    argv = ["calibrate", "--video", str(tmp_path / "half.avi"), "--pressure-log"]
    argv += [str(tmp_path / "log.csv"), "--out", str(tmp_path / "out")]
    code = "import sys; from contactcal.infer.cli import main; sys.exit(main(sys.argv[1:]))"
    res = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, env=env, check=False
    )
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("contactcal: error: ")

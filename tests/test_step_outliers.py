"""Frames that disagree with their step's median area are named, not hidden by the median."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.calibration.curve import MM2, PX
from contactcal.infer.calibration.steps import (
    OffStep,
    Step,
    frames_off_their_step,
    off_step_warning,
    step_outlier_floor,
)
from contactcal.infer.cli import main
from contactcal.infer.pipeline.examples import example_manifest

STEPS = (0.0, 2.0, 4.0, 8.0, 14.0, 20.0)


def _step(areas: list[float], intervals: list[tuple[float, float] | None] | None = None) -> Step:
    """A loading step at 8 kPa of frames ``f0.jpg``, ``f1.jpg``, … (in contact when > 0)."""
    ivs = tuple(intervals) if intervals is not None else (None,) * len(areas)
    files = tuple(f"f{i}.jpg" for i in range(len(areas)))
    a = np.asarray(areas, dtype=np.float64)
    return Step("loading", 3, 8.0, a, a > 0, ivs, files)


def test_a_step_of_agreeing_frames_or_of_two_says_nothing() -> None:
    """Ordinary scatter (within 10 % or 5 mm²), a step at 0 and a pair (which one is off?)."""
    steps = [
        _step([100.0, 104.0, 95.0, 109.0]),
        _step([20.0, 16.0, 24.0]),  # near the onset: 4 mm² apart is under the floor
        _step([0.0, 0.0, 0.0]),
        _step([100.0, 160.0]),
    ]
    assert frames_off_their_step(steps, 5.0) == []


def test_the_frames_stated_interval_widens_its_tolerance() -> None:
    """15 % above the median: named unless the frame's own interval holds the median."""
    wide = _step([100.0, 100.0, 115.0], [(95.0, 105.0)] * 2 + [(98.0, 130.0)])
    assert frames_off_their_step([wide], 5.0) == []
    narrow = _step([100.0, 100.0, 115.0], [(95.0, 105.0)] * 2 + [(108.0, 122.0)])
    assert frames_off_their_step([narrow], 5.0) == [
        OffStep("f2.jpg", "loading", 8.0, 115.0, True, 100.0, 10.0)
    ]


def test_a_contact_disagreement_is_named_without_nan() -> None:
    """No contact in a step in contact is named whatever its interval; a contact in a step
    without contact too, against a median of 0 (no division, no NaN in the text)."""
    lost = _step([120.0, 0.0, 118.0], [(110.0, 130.0), (0.0, 140.0), (108.0, 128.0)])
    stray = _step([0.0, 0.0, 30.0])
    off = frames_off_their_step([lost, stray], 5.0)
    assert [(o.file, o.contact, o.step_median) for o in off] == [
        ("f1.jpg", False, 118.0),
        ("f2.jpg", True, 0.0),
    ]
    text = off_step_warning(off, MM2, 5.0, 5)
    assert "f1.jpg reads no contact against the step's median 118.0 mm²;" in text
    assert "f2.jpg reads 30.0 mm² against the step's median 0.0 mm² (no contact)" in text
    assert "look at those 2 frames" in text and "nan" not in text and "inf" not in text


def test_the_warning_names_the_frame_and_its_departure() -> None:
    off = [OffStep("p12.0kpa_b.jpg", "loading", 12.0, 151.2, True, 120.4, 12.04)]
    assert off_step_warning(off, MM2, 5.0, 5) == (
        "warning: step 12 kPa (loading): p12.0kpa_b.jpg reads 151.2 mm² against the step's "
        "median 120.4 mm² (+26 %); look at that frame (a slipped finger, an unsettled pressure "
        "or a mislabelled file): beyond 10 % of the step's median, 5 mm² and the frame's own "
        "stated interval (the record's extra.frames_off_their_step)"
    )
    many = off_step_warning(off * 7, MM2, 5.0, 5)
    assert many.count("p12.0kpa_b.jpg") == 5 and "; and 2 more; look at those 7 frames" in many


def test_the_px_floor_scales_with_the_frames_area() -> None:
    """5 mm² on the example rig is 320 px on its 400-px frames: the same membrane filmed 2592 px
    wide spans (2592/400)² as many pixels, so an onset step's ordinary 1000-px flip there is not
    named, while the same flip on 400-px frames is."""
    assert step_outlier_floor(MM2, 2592) == 5.0
    assert step_outlier_floor(PX, 400) == 320.0
    assert step_outlier_floor(PX, 2592) == pytest.approx(320.0 * 6.48**2)
    onset = _step([3000.0, 2000.0, 2900.0])
    assert frames_off_their_step([onset], step_outlier_floor(PX, 2592)) == []
    off = frames_off_their_step([onset], step_outlier_floor(PX, 400))
    assert [o.file for o in off] == ["f1.jpg"]
    text = off_step_warning(off, PX, step_outlier_floor(PX, 2592), 5)
    assert "beyond 10 % of the step's median, 13437 px and the frame's own" in text


def _three_per_step(tmp_path: Path, swap: dict[str, str]) -> Path:
    """Example frames copied three times per step (``p08.0_a.jpg``, ``_b``, ``_c``); ``swap``:
    a copy's name → the example frame copied under it instead (a frame of another step)."""
    src = example_manifest().parent
    s = tmp_path / "s"
    s.mkdir()
    shutil.copy(src / "rig.json", s / "rig.json")
    rows = []
    for p in STEPS:
        for rep in "abc":
            name = f"p{p:04.1f}_{rep}.jpg"
            shutil.copy(src / swap.get(name, f"p{p:04.1f}kpa.jpg"), s / name)
            rows.append(f"{name},{p}")
    (s / "manifest.csv").write_text("file,pressure_kpa\n" + "\n".join(rows) + "\n")
    return s / "manifest.csv"


@pytest.mark.parametrize("swapped", [False, True])
def test_calibrate_names_a_frame_off_its_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], swapped: bool
) -> None:
    """Copies of one frame per step agree: nothing said. A 14 kPa frame listed at 8 kPa (a
    mislabelled file): said under the table and recorded, not hidden by the step's median."""
    swap = {"p08.0_b.jpg": "p14.0kpa.jpg"} if swapped else {}
    out = tmp_path / "cal"
    assert main(["calibrate", str(_three_per_step(tmp_path, swap)), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    off = json.loads((out / "calibration.json").read_text())["extra"]["frames_off_their_step"]
    if not swapped:
        assert off == [] and "look at that frame" not in said, said
        return
    assert [(o["file"], o["phase"], o["pressure_kpa"], o["contact"]) for o in off] == [
        ("p08.0_b.jpg", "loading", 8.0, True)
    ]
    o = off[0]
    assert o["area"] > 1.2 * o["step_median"] > 0, o
    assert (
        f"warning: step 8 kPa (loading): p08.0_b.jpg reads {o['area']:.1f} mm² against the "
        f"step's median {o['step_median']:.1f} mm² (+"
    ) in said
    assert "look at that frame (a slipped finger" in said

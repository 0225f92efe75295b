"""Gauge readings → pressure steps (``contactcal.infer.pipeline.readings``) and a manifest
of readings read as steps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.calibration.phases import FROM_ORDER
from contactcal.infer.cli import main
from contactcal.infer.pipeline.manifest import READING_COLUMN, read_session
from contactcal.infer.pipeline.readings import DEFAULT_STEP_TOLERANCE_KPA, step_pressures

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def test_readings_of_one_step_take_its_median() -> None:
    got = step_pressures([5.02, 0.0, 4.98, 10.01, 5.01, 9.97, 0.01], 0.1)
    assert got == [5.01, 0.005, 5.01, 9.99, 5.01, 9.99, 0.005]


def test_setpoints_come_back_unchanged() -> None:
    """Exact repeated setpoints, and setpoints exactly one tolerance apart whatever the
    floating-point rounding of their difference (0.3 - 0.2 < 0.1), stay as they are."""
    fine = [round(0.1 * k, 10) for k in range(31)]
    assert step_pressures(fine, 0.1) == fine
    coarse = [0.0, 0.0, 2.5, 2.5, 2.5, 20.0]
    assert step_pressures(coarse, DEFAULT_STEP_TOLERANCE_KPA) == coarse
    assert step_pressures([], 0.1) == []


def test_zero_tolerance_keeps_every_reading_and_bad_tolerances_are_refused() -> None:
    readings = [5.02, 4.98, 5.01]
    assert step_pressures(readings, 0.0) == readings
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="expected a finite value >= 0"):
            step_pressures(readings, bad)


def test_a_step_is_measured_from_its_lowest_reading_not_chained() -> None:
    """Readings 0.06 kPa apart in a row are not one long step: each step spans < T."""
    got = step_pressures([0.0, 0.06, 0.12, 0.18], 0.1)
    assert got == [0.03, 0.03, 0.15, 0.15]


def _jittered(folder: Path, rng: np.random.Generator, unloading: bool = False) -> Path:
    """The example session with three frames per pressure, each with a gauge reading
    (±0.03 kPa), rows rising (then falling when ``unloading``); no phase column."""
    import csv
    import shutil

    rows = list(csv.DictReader(open(EXAMPLE / "manifest.csv", encoding="utf-8")))
    order = rows + (rows[-2::-1] if unloading else [])
    lines = ["file,pressure_kpa"]
    for n, r in enumerate(order):
        for k in range(3):
            name = f"{n:02d}_{k}_{r['file']}"
            shutil.copy(EXAMPLE / r["file"], folder / name)
            p = max(0.0, float(r["pressure_kpa"]) + rng.uniform(-0.03, 0.03))
            lines.append(f"{name},{p:.3f}")
    shutil.copy(EXAMPLE / "rig.json", folder / "rig.json")
    (folder / "manifest.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder / "manifest.csv"


def test_a_manifest_of_readings_is_read_as_steps(tmp_path: Path) -> None:
    """Rising-then-falling readings: two passes of the example's 21 pressures, three frames per
    step, each frame keeping its reading; with tolerance 0 the passes are lost."""
    manifest = _jittered(tmp_path, np.random.default_rng(3), unloading=True)
    session = read_session(manifest)
    assert session.phase_source == FROM_ORDER
    loading = [f for f in session.frames if f.phase == "loading"]
    assert len({f.pressure_kpa for f in loading}) == 21 and len(loading) == 63
    assert max(f.step for f in session.frames if f.phase == "unloading") == 19
    moved = [f for f in session.frames if READING_COLUMN in dict(f.extras)]
    assert session.grouped == len(moved) > 60
    f = moved[0]
    assert abs(float(dict(f.extras)[READING_COLUMN]) - f.pressure_kpa) < 0.06
    exact = read_session(manifest, 0.0)
    assert exact.grouped == 0 and exact.phase_source != FROM_ORDER


def test_calibrate_pools_readings_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "in").mkdir()
    manifest = _jittered(tmp_path / "in", np.random.default_rng(4))
    out = tmp_path / "cal"
    assert main(["calibrate", str(manifest), "--method", "classical", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    steps = record["steps"]
    assert len(steps) == 21 and all(s["n_frames"] == 3 for s in steps)
    assert record["extra"]["step_tolerance_kpa"] == DEFAULT_STEP_TOLERANCE_KPA
    assert record["extra"]["readings_grouped"] > 0
    assert f"note: {record['extra']['readings_grouped']} frame(s) read as" in printed
    argv = ["calibrate", str(manifest), "--out", str(tmp_path / "x"), "--step-tolerance-kpa"]
    assert main([*argv, "-1"]) == 2
    assert "--step-tolerance-kpa -1: expected a finite value >= 0 kPa" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()

"""Gauge readings → pressure steps (``contactcal.infer.pipeline.readings``) and a manifest
of readings read as steps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.calibration.phases import FROM_ORDER, PHASES
from contactcal.infer.cli import main
from contactcal.infer.pipeline.manifest import (
    READING_COLUMN,
    AtRest,
    ManifestError,
    Pooled,
    read_session,
)
from contactcal.infer.pipeline.readings import (
    DEFAULT_STEP_TOLERANCE_KPA,
    pooled_pressures,
    step_labels,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def test_readings_of_one_step_take_its_median() -> None:
    readings = [5.02, 0.0, 4.98, 10.01, 5.01, 9.97, 0.01]
    labels = step_labels(readings, 0.1)
    assert labels.tolist() == [1, 0, 1, 2, 1, 2, 0]
    assert pooled_pressures(readings, labels) == [5.01, 0.005, 5.01, 9.99, 5.01, 9.99, 0.005]


def test_setpoints_come_back_unchanged() -> None:
    """Exact repeated setpoints, and setpoints exactly one tolerance apart whatever the
    floating-point rounding of their difference (0.3 - 0.2 < 0.1), stay as they are."""
    fine = [round(0.1 * k, 10) for k in range(31)]
    assert step_labels(fine, 0.1).tolist() == list(range(31))
    coarse = [0.0, 0.0, 2.5, 2.5, 2.5, 20.0]
    labels = step_labels(coarse, DEFAULT_STEP_TOLERANCE_KPA)
    assert labels.tolist() == [0, 0, 1, 1, 1, 2]
    assert pooled_pressures(coarse, labels) == coarse
    assert step_labels([], 0.1).tolist() == []


def test_zero_tolerance_keeps_every_reading_and_bad_tolerances_are_refused() -> None:
    assert step_labels([5.02, 4.98, 5.02], 0.0).tolist() == [1, 0, 1]
    for bad in (-0.1, float("nan"), float("inf"), 1.5):
        with pytest.raises(ValueError, match="expected 0 to 1 kPa"):
            step_labels([5.0], bad)


def test_readings_chain_and_setpoints_closer_than_the_tolerance_merge() -> None:
    """Sorted readings less than T apart are one step however wide it gets (a held pressure's
    readings may span more than T); so setpoints 0.06 apart are one step at T = 0.1."""
    assert step_labels([0.0, 0.06, 0.12, 0.18, 1.0], 0.1).tolist() == [0, 0, 0, 0, 1]
    assert step_labels([0.0, 0.06, 0.12, 0.18, 1.0], 0.05).tolist() == [0, 1, 2, 3, 4]


def _readings_manifest(folder: Path, pressures: list[float], extra: str = "") -> Path:
    """A manifest of dummy files (``read_session`` only checks that they exist)."""
    lines = ["file,pressure_kpa" + ("," + extra if extra else "")]
    for k, p in enumerate(pressures):
        (folder / f"f{k:03d}.png").write_bytes(b"x")
        lines.append(f"f{k:03d}.png,{p:.4f}" + (f",{p:.4f}" if extra else ""))
    (folder / "manifest.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder / "manifest.csv"


def test_gaussian_gauge_jitter_keeps_both_passes(tmp_path: Path) -> None:
    """0-20-0 kPa in 1 kPa steps, three frames per step, Gaussian jitter of 0.03 kPa and the
    unloading pass 0.07 kPa below the loading one (a regulator's hysteresis): every session is
    read as two passes of 21 and 20 steps, each pass's step at its own readings' median (at
    a tolerance of 0.1 kPa, about a quarter of such sessions had a step split in two)."""
    rng = np.random.default_rng(5)
    setpoints = [*range(21), *range(19, -1, -1)]
    for n in range(40):
        folder = tmp_path / str(n)
        folder.mkdir()
        readings = [
            max(0.0, p - 0.07 * (k > 20) + rng.normal(0.0, 0.03))
            for k, p in enumerate(setpoints)
            for _ in range(3)
        ]
        session = read_session(_readings_manifest(folder, readings))
        assert session.phase_source == FROM_ORDER
        by_phase = {ph: [f for f in session.frames if f.phase == ph] for ph in PHASES}
        assert [len({f.pressure_kpa for f in fs}) for fs in by_phase.values()] == [21, 20]
        for fs in by_phase.values():
            for f in fs:
                same = [g for g in fs if g.pressure_kpa == f.pressure_kpa]
                mine = [float(dict(g.extras).get(READING_COLUMN, g.pressure_kpa)) for g in same]
                assert f.pressure_kpa == pytest.approx(float(np.median(mine)), abs=1e-6)


def test_a_reading_column_of_the_manifest_is_not_overwritten(tmp_path: Path) -> None:
    manifest = _readings_manifest(tmp_path, [0.0, 0.02, 4.98, 5.01], extra=READING_COLUMN)
    with pytest.raises(ManifestError, match=f"the column '{READING_COLUMN}', which the manifest"):
        read_session(manifest)
    assert read_session(manifest, 0.0).pooled is None


def test_merged_steps_name_the_tolerance(tmp_path: Path) -> None:
    manifest = _readings_manifest(tmp_path, [1.0, 1.6])
    with pytest.raises(ManifestError, match="at 1 pressure.*--step-tolerance-kpa"):
        read_session(manifest, 1.0)


def test_setpoints_finer_than_the_tolerance_are_refused_not_merged(tmp_path: Path) -> None:
    """Setpoints 0.1 kPa apart around the onset (as the guide advises for placing it) would
    chain into one step 2-3 kPa wide at the default tolerance: refused, naming the option; read
    as setpoints with tolerance 0, or at a tolerance below their spacing."""
    fine = [0.0, 1.0, *(round(2.0 + 0.1 * k, 1) for k in range(10)), 3.0, 4.0, 5.0]
    manifest = _readings_manifest(tmp_path, fine)
    with pytest.raises(ManifestError, match=r"pressures 2 to 3 kPa \(11 distinct values\) chain"):
        read_session(manifest)
    for tolerance in (0.0, 0.05):
        assert len({f.step for f in read_session(manifest, tolerance).frames}) == len(fine)


def _jittered(
    folder: Path,
    rng: np.random.Generator,
    unloading: bool = False,
    pressures: int | None = None,
    per_step: int = 3,
) -> Path:
    """The example session with ``per_step`` frames per pressure, each with a gauge reading
    (±0.03 kPa), rows rising (then falling when ``unloading``); no phase column. ``pressures``:
    only the first that many of its pressures (None: all 21)."""
    import csv
    import shutil

    rows = list(csv.DictReader(open(EXAMPLE / "manifest.csv", encoding="utf-8")))[:pressures]
    order = rows + (rows[-2::-1] if unloading else [])
    lines = ["file,pressure_kpa"]
    for n, r in enumerate(order):
        for k in range(per_step):
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
    assert session.pooled is not None and session.pooled.frames == len(moved) > 60
    f = moved[0]
    assert abs(float(dict(f.extras)[READING_COLUMN]) - f.pressure_kpa) < 0.06
    exact = read_session(manifest, 0.0)
    assert exact.pooled is None and exact.phase_source != FROM_ORDER


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
    pooled = record["extra"]["readings_pooled"]
    assert pooled["steps"] >= 15 and pooled["frames"] == 3 * pooled["steps"]
    assert f"note: {pooled['frames']} frame(s) in {pooled['steps']} step(s) pooled" in printed
    argv = ["calibrate", str(manifest), "--out", str(tmp_path / "x"), "--step-tolerance-kpa"]
    assert main([*argv, "-1"]) == 2
    assert "--step-tolerance-kpa -1: step tolerance -1.0 kPa: expected 0 to 1 kPa" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "x").exists()


def test_demo_takes_the_step_tolerance_of_calibrate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --manifest`` pools readings as ``calibrate`` does, ``--step-tolerance-kpa 0``
    keeps every reading a step (each method's record says which), a bad value exits 2."""
    (tmp_path / "in").mkdir()
    manifest = _jittered(tmp_path / "in", np.random.default_rng(5), pressures=7, per_step=2)
    steps = {}
    for t in (None, "0"):
        out = tmp_path / f"demo_{t}"
        given = [] if t is None else ["--step-tolerance-kpa", t]
        assert main(["demo", "--manifest", str(manifest), "--out", str(out), *given]) == 0
        for method in ("classical", "unet"):
            record = json.loads((out / method / "calibration.json").read_text(encoding="utf-8"))
            want = DEFAULT_STEP_TOLERANCE_KPA if t is None else 0.0
            assert record["extra"]["step_tolerance_kpa"] == want
            steps[t, method] = len(record["steps"])
    assert steps[None, "classical"] == steps[None, "unet"] == 7
    rows = manifest.read_text(encoding="utf-8").splitlines()[1:]
    distinct = len({float(r.split(",")[1]) for r in rows})  # 0 kPa readings clip to one
    assert len(rows) == 14 and distinct >= 12
    assert steps["0", "classical"] == steps["0", "unet"] == distinct
    capsys.readouterr()
    bad = ["demo", "--manifest", str(manifest), "--out", str(tmp_path / "x")]
    assert main([*bad, "--step-tolerance-kpa", "2"]) == 2
    assert "--step-tolerance-kpa 2: step tolerance 2.0 kPa: expected 0 to 1 kPa" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "x").exists()


def test_a_gauge_offset_at_rest_is_read_as_0_kpa(tmp_path: Path) -> None:
    """Readings down to -0.5 kPa are accepted: a step whose median is below 0 is given as 0 kPa,
    each frame keeping its reading; a step straddling 0 keeps its median; one reading alone
    (tolerance 0) likewise; "-0" is 0 and no reading below 0."""
    rest = _readings_manifest(tmp_path, [-0.03, 0.01, -0.01, 5.0, 10.0, 20.0])
    session = read_session(rest)
    zero = [f for f in session.frames if f.step == 0]
    assert [f.pressure_kpa for f in zero] == [0.0, 0.0, 0.0]
    assert sorted(dict(f.extras)[READING_COLUMN] for f in zero) == [-0.03, -0.01, 0.01]
    assert session.at_rest == AtRest(3, -0.03)
    assert session.pooled == Pooled(3, 1, (-0.03, 0.01))
    (tmp_path / "b").mkdir()
    straddling = _readings_manifest(tmp_path / "b", [-0.02, 0.02, 0.03, 5.0, 10.0])
    session = read_session(straddling)
    assert session.frames[0].pressure_kpa == 0.02 and session.at_rest is None
    alone = read_session(_readings_manifest(tmp_path / "b", [-0.02, 5.0, 10.0]), 0.0)
    assert alone.frames[0].pressure_kpa == 0.0 and alone.pooled is None
    assert alone.at_rest == AtRest(1, -0.02)
    signed = tmp_path / "b" / "manifest.csv"
    signed.write_text("file,pressure_kpa\nf000.png,-0\nf001.png,5\n", encoding="utf-8")
    session = read_session(signed)
    assert session.at_rest is None and dict(session.frames[0].extras) == {}
    assert str(session.frames[0].pressure_kpa) == "0.0"


def test_calibrate_says_which_readings_were_below_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = (EXAMPLE / "manifest.csv").read_text(encoding="utf-8").splitlines()
    lines = [rows[0]] + [
        r.replace(",0.0", ",-0.04", 1) if r.split(",")[1] == "0.0" else r for r in rows[1:]
    ]
    manifest = tmp_path / "manifest.csv"
    manifest.write_text("\n".join(lines) + "\n", encoding="utf-8")
    for r in rows[1:]:
        (tmp_path / r.split(",")[0]).write_bytes((EXAMPLE / r.split(",")[0]).read_bytes())
    out = tmp_path / "cal"
    assert main(["calibrate", str(manifest), "--method", "classical", "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    assert record["extra"]["readings_at_rest"] == {"frames": 1, "lowest_kpa": -0.04}
    assert record["points"][0]["pressure_kpa"] == 0.0
    assert "note: 1 frame(s) in steps read below 0 kPa (lowest reading -0.04 kPa" in (
        capsys.readouterr().out
    )


def test_a_rest_reading_below_0_is_no_reversal_of_the_passes(tmp_path: Path) -> None:
    """Rows rising then falling in 0.5 kPa steps with a rest reading of -0.3 kPa (0.3 below the
    0 kPa row, more than half a step): read as two passes, as with 0.0 in its place; a median
    rounded to -0.0 is 0.0."""
    p = [0.0, -0.3, 0.5, 1.0, 1.5, 2.0, 1.5, 1.0, 0.5, 0.0]
    session = read_session(_readings_manifest(tmp_path, p))
    assert session.phase_source == FROM_ORDER
    assert sum(f.phase == "unloading" for f in session.frames) == 4
    assert session.at_rest == AtRest(1, -0.3)
    rows = "".join(f"f{k:03d}.png,{v!r}\n" for k, v in enumerate([-3e-7, 1e-7, 5.0, 10.0]))
    (tmp_path / "manifest.csv").write_text("file,pressure_kpa\n" + rows, encoding="utf-8")
    tiny = read_session(tmp_path / "manifest.csv")
    assert str(tiny.frames[0].pressure_kpa) == "0.0" and tiny.at_rest is None


@pytest.mark.parametrize(("per_step", "sd"), [(3, 0.05), (10, 0.04)])
def test_jitter_is_never_taken_for_a_chain(tmp_path: Path, per_step: int, sd: float) -> None:
    """0-20-0 kPa in 1 kPa steps, Gaussian gauge jitter: a step whose readings happen to span
    the tolerance is no chain (a chain is several times wider than the session's other steps);
    none of 60 sessions refused."""
    rng = np.random.default_rng(11)
    setpoints = [*range(21), *range(19, -1, -1)]
    n = len(setpoints) * per_step
    for k in range(n):
        (tmp_path / f"f{k:04d}.png").write_bytes(b"x")
    for _ in range(60):  # the rule before refused 17-23 % of such sessions
        p = np.repeat(setpoints, per_step) + rng.normal(0.0, sd, n)
        rows = "".join(f"f{k:04d}.png,{v:.3f}\n" for k, v in enumerate(p))
        (tmp_path / "manifest.csv").write_text("file,pressure_kpa\n" + rows, encoding="utf-8")
        read_session(tmp_path / "manifest.csv")

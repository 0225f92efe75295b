"""Sessions as a rig records them: repeated frames per step, loading and unloading passes."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.calibration.load import UnassessedCurveWarning, load_curve
from contactcal.infer.calibration.phases import FROM_COLUMN, FROM_ORDER
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.steps import group_steps
from contactcal.infer.cli import main
from contactcal.infer.pipeline.examples import example_manifest

STEPS = (0.0, 2.0, 4.0, 8.0, 14.0, 20.0)


def _rig_session(tmp_path: Path, phase_column: bool = False) -> Path:
    """Copies of example frames: two per loading step, one per unloading step (reversed)."""
    src = example_manifest().parent
    s = tmp_path / "s"
    s.mkdir()
    shutil.copy(src / "rig.json", s / "rig.json")
    rows = []
    for rep in ("a", "b"):
        for p in STEPS:
            rows.append((f"p{p:04.1f}_{rep}.jpg", p, "loading"))
    rows.sort(key=lambda r: r[1])
    rows += [(f"p{p:04.1f}_u.jpg", p, "Unloading") for p in reversed(STEPS[:-1])]
    for name, p, _ in rows:
        shutil.copy(src / f"p{p:04.1f}kpa.jpg", s / name)
    head = "file,pressure_kpa,time_s" + (",phase" if phase_column else "")
    lines = [
        f"{n},{p},{i * 0.5}" + (f",{ph}" if phase_column else "")
        for i, (n, p, ph) in enumerate(rows)
    ]
    (s / "manifest.csv").write_text("\n".join([head, *lines]) + "\n", encoding="utf-8")
    return s / "manifest.csv"


@pytest.mark.parametrize("phase_column", [False, True])
def test_rig_session_with_repeats_and_unloading(tmp_path: Path, phase_column: bool) -> None:
    manifest = _rig_session(tmp_path, phase_column)
    assert main(["calibrate", str(manifest), "--out", str(tmp_path / "out")]) == 0
    rec = json.loads((tmp_path / "out" / "calibration.json").read_text(encoding="utf-8"))
    assert rec["phase_source"] == (FROM_COLUMN if phase_column else FROM_ORDER)
    assert set(rec["phases"]) == {"loading", "unloading"} and rec["inverse_phase"] == "loading"
    steps = {(s["phase"], s["pressure_kpa"]): s for s in rec["steps"]}
    assert [steps[("loading", p)]["n_frames"] for p in STEPS] == [2] * len(STEPS)
    assert [steps[("unloading", p)]["n_frames"] for p in STEPS[:-1]] == [1] * (len(STEPS) - 1)
    sp = steps[("loading", 8.0)]["spread"]  # two copies of one frame: no spread
    assert sp["min"] == sp["max"] == steps[("loading", 8.0)]["median_area"]
    # the same images on both passes: no hysteresis
    h = rec["hysteresis"]
    assert h["pressures_kpa"] == list(STEPS[:-1]) and h["max_abs_difference"] == 0.0
    assert h["onset_kpa"]["loading"] is not None and h["onset_kpa"]["unloading"] is not None
    pts = rec["points"]
    assert pts[0]["file"] == "p00.0_a.jpg" and pts[0]["phase"] == "loading"  # the reference
    assert all("time_s" in pt["extras"] for pt in pts) and len(pts) == 17
    assert all(pt["area_interval_mm2"] is not None for pt in pts)  # the U-Net states one
    with open(tmp_path / "out" / "calibration.csv", newline="", encoding="utf-8") as fh:
        assert len(list(csv.DictReader(fh))) == len(steps)
    with pytest.warns(UnassessedCurveWarning, match="unloading curve tells pressures apart"):
        down = load_curve(tmp_path / "out" / "calibration.json", phase="unloading")  # few steps
    assert down.band is not None and down.has_contact
    p, lo, hi, _ = load_curve(tmp_path / "out" / "calibration.json").pressure_interval_for_area(50)
    assert lo <= p <= hi


def test_inverse_phase_option(tmp_path: Path) -> None:
    manifest = _rig_session(tmp_path)
    out = tmp_path / "out"
    assert (
        main(["calibrate", str(manifest), "--inverse-phase", "unloading", "--out", str(out)]) == 0
    )
    rec = json.loads((out / "calibration.json").read_text(encoding="utf-8"))
    assert rec["inverse_phase"] == "unloading"
    assert rec["fit"] == rec["phases"]["unloading"]["fit"]


def test_inverse_phase_missing_is_an_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    manifest = example_manifest()
    out = tmp_path / "out"
    code = main(["calibrate", str(manifest), "--inverse-phase", "unloading", "--out", str(out)])
    assert code == 2 and not out.exists()
    assert "no unloading pass" in capsys.readouterr().err


def _passes_session(
    tmp_path: Path, loading: tuple[float, ...], unloading: tuple[float, ...]
) -> Path:
    """Example frames: a loading pass at ``loading`` kPa and an unloading one at ``unloading``."""
    src = example_manifest().parent
    s = tmp_path / "s"
    s.mkdir()
    shutil.copy(src / "rig.json", s / "rig.json")
    rows = ["file,pressure_kpa,phase"]
    for phase, kpas in (("loading", loading), ("unloading", unloading)):
        for p in kpas:
            name = f"p{p:04.1f}_{phase[0]}.jpg"
            shutil.copy(src / f"p{p:04.1f}kpa.jpg", s / name)
            rows.append(f"{name},{p},{phase}")
    (s / "manifest.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    return s / "manifest.csv"


@pytest.mark.parametrize(
    ("loading", "unloading", "inverse"),
    [
        ((0.0, 1.0, 2.0), (12.0, 10.0, 8.0), "loading"),  # the default pass never in contact
        ((0.0, 8.0, 10.0, 12.0), (2.0, 1.0), "unloading"),  # the one asked for never in contact
    ],
)
def test_inverted_pass_without_contact_is_refused(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    loading: tuple[float, ...],
    unloading: tuple[float, ...],
    inverse: str,
) -> None:
    """A record with ``inverse: null`` is no calibration: exit 1 (a RunError), one line naming
    the manifest and the pass, nothing written; the other pass is suggested."""
    manifest = _passes_session(tmp_path, loading, unloading)
    out = tmp_path / "out"
    code = main(["calibrate", str(manifest), "--inverse-phase", inverse, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and not out.exists(), err
    assert len(err.strip().splitlines()) == 1 and str(manifest) in err, err
    other = "unloading" if inverse == "loading" else "loading"
    assert f"the {inverse} pass" in err and "no contact" in err
    assert f"--inverse-phase {other}" in err


def test_steps_aggregate_by_median() -> None:
    pts = [
        CalibrationPoint(f"f{i}.png", 5.0, a > 0, a, None) for i, a in enumerate((10.0, 12.0, 90.0))
    ] + [CalibrationPoint("z.png", 0.0, False, 0.0, None)]
    steps = group_steps(pts, "px")["loading"]
    assert [s.pressure_kpa for s in steps] == [0.0, 5.0]
    s = steps[1]
    assert s.n == 3 and s.median == 12.0 and s.contact
    assert s.spread() == {"min": 10.0, "q25": 11.0, "q75": 51.0, "max": 90.0}
    assert np.isclose(steps[0].median, 0.0)


def test_hysteresis_matches_steps_of_a_noisy_log() -> None:
    """Steps from a logged sweep sit a few 0.01 kPa off the set points: still compared."""
    from contactcal.infer.calibration.curve import PX, Curve
    from contactcal.infer.calibration.hysteresis import hysteresis
    from contactcal.infer.calibration.steps import Step

    def steps(phase: str, pressures: list[float], areas: list[float]) -> list[Step]:
        return [
            Step(phase, k, p, np.array([a]), np.array([a > 0]), (None,), ("f",))
            for k, (p, a) in enumerate(zip(pressures, areas, strict=True))
        ]

    curve = Curve([0.0, 4.0, 6.0], [0.0, 10.0, 20.0], 2.0, PX)
    up = steps("loading", [0.0, 4.00, 6.0], [0.0, 10.0, 20.0])
    down = steps("unloading", [5.97, 4.01, 0.02], [22.0, 13.0, 0.0])
    h = hysteresis((up, curve), (down, curve))
    assert h["pressures_kpa"] == [0.0, 4.0, 6.0]
    assert h["difference"] == [0.0, 3.0, 2.0] and h["max_abs_at_kpa"] == 4.0
    far = steps("unloading", [5.5, 3.0], [22.0, 13.0])
    assert hysteresis((up, curve), (far, curve))["max_abs_difference"] is None
    # no brackets (a record's curve): the shift has no range
    assert h["onset_shift_range_kpa"] is None and h["onset_bracket_kpa"]["loading"] is None


def test_hysteresis_onset_shift_range_from_the_brackets() -> None:
    """Onsets known to lie in (2, 4] loading and (1, 3] unloading: the shift lies in (-3, 1)."""
    from contactcal.infer.calibration.curve import PX, Curve
    from contactcal.infer.calibration.hysteresis import hysteresis
    from contactcal.infer.calibration.table import _onset_shift

    up = Curve([2.0, 4.0], [0.0, 10.0], 3.0, PX, onset_bracket_kpa=(2.0, 4.0))
    down = Curve([1.0, 3.0], [0.0, 10.0], 2.5, PX, onset_bracket_kpa=(1.0, 3.0))
    h = hysteresis(([], up), ([], down))
    assert h["onset_shift_kpa"] == -0.5 and h["onset_shift_range_kpa"] == [-3.0, 1.0]
    assert h["onset_bracket_kpa"] == {"loading": [2.0, 4.0], "unloading": [1.0, 3.0]}
    assert _onset_shift(h) == [
        "onset shift (unloading - loading): -0.50 kPa, known to lie between -3 and +1 kPa "
        "from the steps"
    ]
    lowest = Curve([1.0, 3.0], [5.0, 10.0], 1.0, PX, onset_bracket_kpa=(None, 1.0))
    h = hysteresis(([], up), ([], lowest))
    assert h["onset_shift_range_kpa"] is None and "range unknown" in _onset_shift(h)[0]
    assert _onset_shift(hysteresis(([], up), ([], Curve([1.0], [0.0], None, PX)))) == []


def test_calibrate_warns_of_a_row_out_of_order(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One mistyped pressure (16 for 6 kPa) among rising rows: said and recorded, not silent."""
    from test_outputs import copy_session

    names = tuple(f"p{p:04.1f}kpa.jpg" for p in (0, 2, 4, 6, 8, 10, 12))
    s = copy_session(tmp_path, names)
    text = (s / "manifest.csv").read_text().replace("p06.0kpa.jpg,6.0", "p06.0kpa.jpg,16.0")
    (s / "manifest.csv").write_text(text)
    out = tmp_path / "cal"
    assert (
        main(["calibrate", str(s / "manifest.csv"), "--method", "classical", "--out", str(out)])
        == 0
    )
    said = capsys.readouterr().out
    assert "warning: row 4 (p06.0kpa.jpg, 16 kPa) breaks the rows' order" in said
    record = json.loads((out / "calibration.json").read_text())
    assert record["extra"]["rows_out_of_order"] == ["row 4 (p06.0kpa.jpg, 16 kPa)"]


def test_demo_montage_titles_say_the_pass(tmp_path: Path, monkeypatch) -> None:
    """Each montage tile is titled with its pressure and pass, as ``calibrate --overlay`` titles
    its overlays; the frame nearest to a montage pressure may be an unloading one."""
    from contactcal.infer.pipeline import demo

    manifest = _passes_session(tmp_path, (0.0, 2.0, 4.0, 8.0, 12.0), (13.0, 6.0, 1.0))
    titles: list[str] = []
    draw = demo.draw_overlay

    def spy(gray: np.ndarray, contours: dict, title: str) -> np.ndarray:
        titles.append(title)
        return draw(gray, contours, title)

    monkeypatch.setattr(demo, "draw_overlay", spy)
    assert main(["demo", "--manifest", str(manifest), "--out", str(tmp_path / "out")]) == 0
    assert titles == [
        *(f"{p:g} kPa, loading" for p in (0.0, 2.0, 4.0, 8.0)),
        "13 kPa, unloading",  # nearest to 14 and 20 kPa: shown once
    ]

"""A calibration says when it cannot resolve pressure: a flat curve, identical frames, the
onset's bracket between the last pressure without contact and the first in contact (never at or
below a no-contact pressure), the band over that bracket, and a resolution it cannot assess."""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.calibration.fit import CurveConfig, fit_monotone, fit_parametric
from contactcal.infer.calibration.load import (
    UnassessedCurveWarning,
    UnresolvedCurveError,
    load_curve,
)
from contactcal.infer.calibration.onset import (
    EXTRAPOLATED_RULE,
    FITTED_RULE,
    MIDPOINT_BELOW_RULE,
    MIDPOINT_NO_SLOPE_RULE,
)
from contactcal.infer.calibration.provenance import identical_frames
from contactcal.infer.calibration.session import PhaseFit, fit_phase
from contactcal.infer.calibration.steps import Step
from contactcal.infer.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
#: The example session's U-Net step areas (mm²) at 0, 5, 10 and 20 kPa (contact from 3 kPa).
COARSE_P = [0.0, 5.0, 10.0, 20.0]
COARSE_A = [0.0, 71.2, 116.9, 143.8]
FAST = CurveConfig(n_bootstrap=50)


def _phase(pressures: list[float], areas: list[float], contacts: list[int]) -> PhaseFit:
    steps = [
        Step("loading", i, float(p), np.array([float(a)]), np.array([bool(c)]), (None,), ("f",))
        for i, (p, a, c) in enumerate(zip(pressures, areas, contacts, strict=True))
    ]
    return fit_phase(steps, FAST, "mm²")


# --- onset: in its bracket, one rule for both models ------------------------------------------


def test_a_coarse_concave_start_puts_the_onset_inside_its_bracket() -> None:
    # The line through 5 and 10 kPa reaches 0 mm² below 0 kPa, where the frame shows no
    # contact: the onset was clamped to 0.00 kPa; it is the bracket's midpoint, and says so.
    curve = fit_monotone(COARSE_P, COARSE_A, [0, 1, 1, 1])
    assert curve.onset_kpa == pytest.approx(2.5)
    assert curve.onset_bracket_kpa == (0.0, 5.0)
    assert curve.onset_rule == MIDPOINT_BELOW_RULE


def test_one_contact_step_gives_the_same_midpoint_rule() -> None:
    curve = fit_monotone([0.0, 1.0, 2.0, 20.0], [0.0, 0.0, 0.0, 143.8], [0, 0, 0, 1])
    assert curve.onset_kpa == pytest.approx(11.0)
    assert curve.onset_bracket_kpa == (2.0, 20.0)
    assert curve.onset_rule == MIDPOINT_NO_SLOPE_RULE


def test_an_extrapolation_inside_the_bracket_is_kept() -> None:
    p = np.arange(11.0)
    a = np.where(p > 3.0, 4.0 * (p - 3.0) ** 2, 0.0)  # 4, 16 at 4, 5 kPa: 3.67 kPa
    curve = fit_monotone(p, a, a > 0)
    assert curve.onset_kpa == pytest.approx(4 - 4 / 12)
    assert curve.onset_bracket_kpa == (3.0, 4.0)
    assert curve.onset_rule == EXTRAPOLATED_RULE


def test_a_parametric_onset_pinned_to_a_no_contact_frame_moves_to_the_midpoint() -> None:
    # Saturating areas from an onset at 1 kPa, but the 2 kPa frame shows no contact: the
    # least-squares onset sits on the bracket's low end (2 kPa) and was kept there.
    p = np.array([0.0, 2.0, 4.0, 6.0, 8.0, 10.0])
    a = np.where(p > 2.0, 150.0 * (p - 1.0) / (3.0 + p - 1.0), 0.0)
    curve = fit_parametric(p, a, a > 0)
    assert curve is not None and curve.model is not None
    assert curve.onset_kpa == pytest.approx(3.0)
    assert curve.onset_bracket_kpa == (2.0, 4.0) and curve.onset_rule == MIDPOINT_BELOW_RULE
    assert curve.model.k_kpa > 0 and curve.area_at(4.0) > 0


def test_a_parametric_onset_inside_the_bracket_is_kept() -> None:
    p = np.arange(0.0, 11.0)
    a = np.where(p > 2.5, 150.0 * (p - 2.5) / (3.0 + p - 2.5), 0.0)
    curve = fit_parametric(p, a, a > 0)
    assert curve is not None and curve.onset_kpa == pytest.approx(2.5, abs=1e-3)
    assert curve.onset_rule == FITTED_RULE and curve.onset_bracket_kpa == (2.0, 3.0)


# --- the band over the onset's bracket --------------------------------------------------------


@pytest.mark.parametrize(
    ("pressures", "areas", "contacts", "bracket"),
    [
        (COARSE_P, COARSE_A, [0, 1, 1, 1], (0.0, 5.0)),
        ([0.0, 1.0, 2.0, 20.0], [0.0, 0.0, 0.0, 143.8], [0, 0, 0, 1], (2.0, 20.0)),
    ],
)
def test_the_inverse_band_spans_the_bracket_below_the_first_contact_area(
    pressures: list[float], areas: list[float], contacts: list[int], bracket: tuple[float, float]
) -> None:
    curve = _phase(pressures, areas, contacts).curve
    lo, hi = bracket
    first = curve.area_at(hi)
    for area in (0.0, 5.0, 0.9 * first):
        p, p_lo, p_hi, _ = curve.pressure_interval_for_area(area)
        assert lo <= p_lo <= lo + 1e-5 * (hi - lo) and hi - 1e-5 * (hi - lo) <= p_hi <= hi
        assert p_lo <= p <= p_hi


def test_the_band_above_the_bracket_is_the_bootstrap_band() -> None:
    p = np.arange(0.0, 11.0)
    a = np.where(p > 2.5, 150.0 * (p - 2.5) / (3.0 + p - 2.5), 0.0)
    curve = _phase(list(p), list(a), list(a > 0)).curve
    assert curve.band is not None
    _, p_lo, p_hi, _ = curve.pressure_interval_for_area(float(curve.area_at(7.0)))
    assert 3.0 < p_lo <= 7.0 <= p_hi < 10.0


# --- resolution --------------------------------------------------------------------------------


def test_a_flat_curve_does_not_resolve_even_with_a_perfect_fit() -> None:
    # Identical areas from 5 to 20 kPa: a zero cross-validated error, a zero rise.
    res = _phase([0, 5, 10, 15, 20], [0, 116.9, 116.9, 116.9, 116.9], [0, 1, 1, 1, 1]).resolution()
    assert res is not None and res["resolves"] is False
    assert "no more than 5% of its largest area (5.85 of 116.9 " in res["reason"]
    assert res["floor"] == pytest.approx(0.05 * 116.9)


def test_a_small_rise_below_the_floor_does_not_resolve() -> None:
    areas = [0, 100.0, 100.5, 101.0, 101.5, 102.0, 102.5]  # a 2.5 % rise, a perfect line
    res = _phase([0, 2, 4, 6, 8, 10, 12], areas, [0, 1, 1, 1, 1, 1, 1]).resolution()
    assert res is not None and res["resolves"] is False


def test_a_resolution_that_cannot_be_assessed_says_why() -> None:
    res = _phase(COARSE_P, COARSE_A, [0, 1, 1, 1]).resolution()
    assert res is not None and res["resolves"] is None and res["cv_rmse"] is None
    assert res["reason"].startswith("not assessed: no cross-validated error")
    res = _phase([0.0, 1.0, 2.0, 20.0], [0, 0, 0, 143.8], [0, 0, 0, 1]).resolution()
    assert res is not None and res["resolves"] is None
    assert res["reason"].startswith("not assessed: 1 step(s) in contact above the onset")


def test_a_rising_curve_resolves() -> None:
    p = np.arange(0.0, 11.0)
    a = np.where(p > 2.5, 150.0 * (p - 2.5) / (3.0 + p - 2.5), 0.0)
    res = _phase(list(p), list(a), list(a > 0)).resolution()
    assert res is not None and res["resolves"] is True and res["reason"] is None


# --- identical frames ---------------------------------------------------------------------------


def test_identical_frames_at_different_pressures_are_found() -> None:
    inputs = {
        "frames": [
            {"file": "a.jpg", "sha256": "1"},
            {"file": "b.jpg", "sha256": "2"},
            {"file": "b.jpg", "sha256": "2"},  # a repeat at the same pressure: fine
            {"file": "c.jpg", "sha256": "1"},
            {"file": "d.jpg", "sha256": "3"},
            {"file": "e.jpg", "sha256": "3"},  # the same set point on the way down: fine
        ]
    }
    assert identical_frames(inputs, [0.0, 5.0, 5.0, 10.0, 4.015, 3.999]) == [
        {"sha256": "1", "files": ["a.jpg", "c.jpg"], "pressures_kpa": [0.0, 10.0]}
    ]


# --- the command line: printed and recorded ------------------------------------------------------


def _session(tmp_path: Path, name: str, rows: list[tuple[str, float]]) -> Path:
    s = tmp_path / "S"
    if not s.exists():
        s.mkdir()
        shutil.copy(EXAMPLE / "rig.json", s / "rig.json")
    for file, _ in rows:
        source = "p10.0kpa.jpg" if file.startswith("c") else file
        shutil.copy(EXAMPLE / source, s / file)
    manifest = s / f"{name}.csv"
    manifest.write_text("file,pressure_kpa\n" + "".join(f"{f},{p}\n" for f, p in rows))
    return manifest


def test_a_frozen_camera_is_said_and_not_read_as_a_calibration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = [("p00.0kpa.jpg", 0.0), *((f"c{k}.jpg", 5.0 * k) for k in range(1, 5))]
    manifest = _session(tmp_path, "flat", rows)
    out = tmp_path / "o"
    assert main(["calibrate", str(manifest), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "its inverse cannot tell pressures apart" in printed
    said = "byte-identical frames at different pressures: 4 frames (c1.jpg … c4.jpg) at 5, 10, "
    assert said + "15, 20 kPa" in printed
    record = json.loads((out / "calibration.json").read_text())
    assert record["phases"]["loading"]["resolution"]["resolves"] is False
    (group,) = record["extra"]["identical_frames"]
    assert group["files"] == ["c1.jpg", "c2.jpg", "c3.jpg", "c4.jpg"]
    with pytest.raises(UnresolvedCurveError, match="no more than 5% of its largest area"):
        load_curve(out / "calibration.json")


def test_a_coarse_session_records_its_bracket_and_warns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = [(f"p{p:04.1f}kpa.jpg", p) for p in COARSE_P]
    out = tmp_path / "o"
    assert main(["calibrate", str(_session(tmp_path, "coarse", rows)), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "onset 2.50 kPa, between 0 kPa (no contact) and 5 kPa (contact)" in printed
    assert "warning: the loading onset is the midpoint of the bracket" in printed
    assert "warning: whether the loading curve resolves pressure is not assessed" in printed
    loading = json.loads((out / "calibration.json").read_text())["phases"]["loading"]
    assert loading["onset_bracket_kpa"] == [0.0, 5.0]
    assert loading["onset_rule"] == MIDPOINT_BELOW_RULE
    assert loading["resolution"]["resolves"] is None and loading["resolution"]["reason"]
    # read back with a warning (it was read silently, although calibrate warned)
    with pytest.warns(UnassessedCurveWarning, match="not assessed: no cross-validated error"):
        curve = load_curve(out / "calibration.json")
    _, p_lo, p_hi, _ = curve.pressure_interval_for_area(5.0)
    assert p_lo < 0.01 and p_hi > 4.99
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_curve(out / "calibration.json", allow_unresolved=True)

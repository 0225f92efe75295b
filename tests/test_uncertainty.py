"""Uncertainty of the calibration: parametric fit, CV model choice, bootstrap band, inverse."""

from __future__ import annotations

import numpy as np
import pytest

from contactcal.infer.calibration.fit import CurveConfig, fit_parametric
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.select import choose_model
from contactcal.infer.calibration.session import fit_session

P = np.arange(0.0, 21.0, 1.0)
TRUE = (3.2, 4.0, 150.0)  # p0 kPa, K kPa, A_max mm²


def _form(p: np.ndarray, p0: float = TRUE[0], k: float = TRUE[1], a: float = TRUE[2]):
    x = np.maximum(p - p0, 0.0)
    return a * x / (k + x)


def _points(areas_by_repeat: np.ndarray) -> list[CalibrationPoint]:
    """Points of a session with ``areas_by_repeat[r, i]`` the r-th frame at pressure P[i]."""
    return [
        CalibrationPoint(f"r{r}_{i}.png", float(P[i]), bool(a > 0), float(a), float(a), step=i)
        for r, row in enumerate(areas_by_repeat)
        for i, a in enumerate(row)
    ]


def test_parametric_fit_recovers_its_parameters() -> None:
    curve = fit_parametric(P, _form(P), _form(P) > 0)
    assert curve is not None and curve.model is not None
    m = curve.model
    assert (m.p0_kpa, m.k_kpa, m.a_max) == pytest.approx(TRUE, rel=1e-3)
    assert curve.onset_kpa == pytest.approx(TRUE[0], rel=1e-3)
    # the analytic inverse inverts the form
    for area in (10.0, 75.0, 120.0):
        p, warning = curve.pressure_for_area(area)
        assert warning is None and float(_form(np.array([p]))[0]) == pytest.approx(area, rel=1e-3)


def test_cv_picks_parametric_on_noisy_parametric_data() -> None:
    picks = []
    for seed in range(10):  # seeded noise; the choice is statistical, so over 10 sessions
        rng = np.random.default_rng(seed)
        noisy = np.maximum(_form(P) + np.where(_form(P) > 0, rng.normal(0.0, 1.0, P.size), 0), 0)
        curve, sel = choose_model(P, noisy, _form(P) > 0, CurveConfig(), "mm²")
        picks.append(sel["model"] == "parametric")
        assert (curve.model is not None) == picks[-1]
    assert sum(picks) >= 8, picks


def test_cv_picks_isotonic_on_a_shape_the_form_cannot_follow() -> None:
    # a plateau, then a second rise: no single saturating curve follows it
    area = np.where(P < 3, 0.0, np.where(P < 10, 40.0 + P, 150.0 + P))
    curve, sel = choose_model(P, area, area > 0, CurveConfig(), "mm²")
    assert sel["model"] == "isotonic" and curve.model is None
    assert sel["cv_rmse"]["isotonic"] < sel["cv_rmse"]["parametric"]


def test_cv_needs_enough_contact_steps() -> None:
    p = np.array([0.0, 1.0, 2.0, 3.0])
    a = np.array([0, 0, 5.0, 9.0])
    _, sel = choose_model(p, a, a > 0, CurveConfig(), "mm²")
    assert sel["model"] == "isotonic" and sel["cv_rmse"]["parametric"] is None


def _noisy_session(seed: int, repeats: int = 3, sigma: float = 3.0) -> list[CalibrationPoint]:
    rng = np.random.default_rng(seed)
    truth = _form(P)
    areas = truth + np.where(truth > 0, rng.normal(0.0, sigma, (repeats, P.size)), 0.0)
    return _points(np.maximum(areas, 0.0))


def test_band_is_deterministic_and_contains_the_fit() -> None:
    cfg = CurveConfig(n_bootstrap=60, seed=3)
    a = fit_session(_noisy_session(1), "mm²", cfg).curve
    b = fit_session(_noisy_session(1), "mm²", cfg).curve
    c = fit_session(_noisy_session(1), "mm²", CurveConfig(n_bootstrap=60, seed=4)).curve
    assert a.band is not None and b.band is not None and c.band is not None
    np.testing.assert_array_equal(a.band.lo, b.band.lo)
    np.testing.assert_array_equal(a.band.hi, b.band.hi)
    assert not np.array_equal(a.band.hi, c.band.hi)
    fit = np.array([a.area_at(q) for q in a.band.pressures_kpa])
    assert np.all(a.band.lo <= fit) and np.all(fit <= a.band.hi)
    assert a.band.level == 0.9 and a.band.n_resamples == 60
    assert np.any(a.band.hi - a.band.lo > 0.5)  # the noise shows


def test_inverse_with_interval_is_monotone() -> None:
    curve = fit_session(_noisy_session(2), "mm²", CurveConfig(n_bootstrap=60)).curve
    lo_a, hi_a = curve.area_range()
    rows = [curve.pressure_interval_for_area(a) for a in np.linspace(lo_a, hi_a * 1.1, 80)]
    p, p_lo, p_hi = (np.array([r[i] for r in rows]) for i in range(3))
    assert np.all(np.diff(p) >= 0) and np.all(np.diff(p_lo) >= 0) and np.all(np.diff(p_hi) >= 0)
    assert np.all(p_lo <= p) and np.all(p <= p_hi)
    assert rows[-1][3] is not None and "clamped" in rows[-1][3]
    table = curve.inverse_table_with_interval()
    assert all(lo <= p <= hi for _, p, lo, hi in table)


def test_frame_intervals_widen_the_band() -> None:
    plain = _points(_form(P)[None, :])
    stated = [
        CalibrationPoint(
            r.file,
            r.pressure_kpa,
            r.contact,
            r.area_px,
            r.area_mm2,
            area_interval_mm2=(r.area_px * 0.9, r.area_px * 1.1),
        )
        for r in plain
    ]
    cfg = CurveConfig(n_bootstrap=60)
    narrow = fit_session(plain, "mm²", cfg).curve.band
    wide = fit_session(stated, "mm²", cfg).curve.band
    assert narrow is not None and wide is not None
    assert np.mean(wide.hi - wide.lo) > 2 * np.mean(narrow.hi - narrow.lo)


def test_band_coverage_on_synthetic_repeat_sessions() -> None:
    """How often the truth lies in the 90 % band, over seeded noisy repeat sessions."""
    truth = _form(P)
    hits = []
    for seed in range(8):
        curve = fit_session(_noisy_session(100 + seed), "mm²", CurveConfig(n_bootstrap=100)).curve
        assert curve.band is not None
        for q, t in zip(P, truth, strict=True):
            if t > 0:
                lo, hi = curve.band.at(float(q))
                hits.append(lo <= t <= hi)
    coverage = float(np.mean(hits))
    print(f"synthetic coverage of the 90 % band: {coverage:.3f} over {len(hits)} steps")
    assert coverage >= 0.7


@pytest.mark.parametrize("model", ["isotonic", "parametric"])
@pytest.mark.parametrize("seed", [2, 5, 7])
def test_inverse_table_columns_interpolate_to_the_interval(seed: int, model: str) -> None:
    """A controller interpolating ``pressure_lo_kpa``/``pressure_hi_kpa`` linearly was up to
    10 kPa off `pressure_interval_for_area` (no rows where the band's edges bend or jump), and
    ``pressure_kpa`` up to 17 kPa off a nearly flat parametric curve (rows every step only)."""
    cfg = CurveConfig(curve_model=model, n_bootstrap=60)
    c = fit_session(_noisy_session(seed, sigma=12.0), "mm²", cfg).curve
    assert c.band is not None and (c.model is not None) == (model == "parametric")
    table = np.array(c.inverse_table_with_interval())
    assert np.all(np.diff(table[:, 0]) >= 0) and np.all(np.diff(table[:, 1:], axis=0) >= 0)
    lo, hi = c.area_range()
    q = np.setdiff1d(np.random.default_rng(seed).uniform(lo, hi, 2000), table[:, 0])
    exact = np.array([c.pressure_interval_for_area(a)[:3] for a in q])
    # exact for the piecewise-linear fit; the smooth form between its 257 samples
    atol = 1e-9 if c.model is None else 0.02
    for k in range(3):
        got = np.interp(q, table[:, 0], table[:, k + 1])
        np.testing.assert_allclose(got, exact[:, k], atol=atol, err_msg=f"column {k + 1}")

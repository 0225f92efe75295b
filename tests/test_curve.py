"""Tests of the calibration fit and curve (isotonic fit, robust monotone fit, onset, inverse)."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from contactcal.infer.calibration.band import Band
from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.fit import CurveConfig, estimate_onset, fit_monotone
from contactcal.infer.calibration.isotonic import despike, isotonic_fit

P = np.arange(0.0, 11.0)  # 1 kPa steps


def _quadratic(p: np.ndarray, onset: float = 3.0, c: float = 4.0) -> np.ndarray:
    return np.where(p > onset, c * (p - onset) ** 2, 0.0)


# --- isotonic_fit -------------------------------------------------------------------------


def test_isotonic_reference_values() -> None:
    np.testing.assert_allclose(isotonic_fit([1, 2, 3, 4], [1, 3, 2, 4]), [1, 2.5, 2.5, 4])
    np.testing.assert_allclose(isotonic_fit([0, 1, 2], [3, 2, 1]), [2, 2, 2])
    np.testing.assert_allclose(isotonic_fit([0, 1, 2, 3], [1, 2, 3, 4]), [1, 2, 3, 4])
    # Weighted: the heavy point dominates its pool.
    np.testing.assert_allclose(isotonic_fit([0, 1], [4, 1], [3, 1]), [3.25, 3.25])
    # Output aligned with the (unsorted) input order.
    np.testing.assert_allclose(isotonic_fit([2, 0, 1], [1, 0, 3]), [2, 0, 2])
    # Ties in x share one value.
    np.testing.assert_allclose(isotonic_fit([0, 1, 1], [0, 1, 3]), [0, 2, 2])


@pytest.mark.parametrize(
    ("x", "y", "w"),
    [([0, 1], [0], None), ([], [], None), ([0, 1], [0, np.nan], None), ([0, 1], [0, 1], [1, 0])],
)
def test_isotonic_bad_input(x: list, y: list, w: list | None) -> None:
    with pytest.raises(ValueError, match="isotonic_fit"):
        isotonic_fit(x, y, w)


def test_despike_identity_on_monotone_and_removes_spikes() -> None:
    y = np.array([0.0, 1, 4, 9, 16, 25])
    np.testing.assert_array_equal(despike(y), y)
    np.testing.assert_array_equal(despike(y, window=5), y)
    spiked = y.copy()
    spiked[2] = 100
    np.testing.assert_array_equal(despike(spiked), [0, 1, 9, 9, 16, 25])  # neighbours kept
    dipped = y.copy()
    dipped[3] = 0
    np.testing.assert_array_equal(despike(dipped), [0, 1, 4, 4, 16, 25])
    assert despike(np.array([0.0, 1, 2, 3, 50]))[-1] == 5  # Tukey end rule: 3*3 - 2*2
    np.testing.assert_array_equal(despike(np.array([90.0, 1, 2, 3])), [1, 1, 2, 3])
    np.testing.assert_array_equal(despike(spiked, window=1), spiked)
    with pytest.raises(ValueError, match="odd"):
        despike(y, window=4)


finite = st.floats(0, 1e4, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=1, max_size=30))
def test_isotonic_property(y: list[float]) -> None:
    x = np.arange(len(y), dtype=float)
    f = isotonic_fit(x, y)
    assert np.all(np.isfinite(f)) and np.all(np.diff(f) >= 0)
    assert f.min() >= min(y) and f.max() <= max(y)


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=2, max_size=30), st.randoms(use_true_random=False))
def test_fit_monotone_property(areas: list[float], rnd) -> None:
    p = np.arange(len(areas), dtype=float) * 1.5
    order = list(range(len(areas)))
    rnd.shuffle(order)  # input in any order
    curve = fit_monotone(p[order], np.asarray(areas)[order])
    f = curve.fit_area
    assert np.all(np.isfinite(f)) and np.all(np.diff(f) >= 0)
    assert f.min() >= 0 and f.max() <= max(areas)
    np.testing.assert_array_equal(curve.pressures_kpa, p)
    if curve.has_contact:
        amin, amax = curve.area_range()
        for target in np.linspace(amin, amax, 7):
            q, warning = curve.pressure_for_area(target)
            assert warning is None
            assert curve.area_at(q) == pytest.approx(target, rel=1e-9, abs=1e-9 * amax)
        assert curve.pressure_for_area(amax * 2 + 1)[1] is not None


# --- robust fit -----------------------------------------------------------------------------


def test_noisy_data_monotone_and_close() -> None:
    rng = np.random.default_rng(0)
    truth = _quadratic(P)
    noisy = np.clip(truth + rng.normal(0, 3, P.size) * (truth > 0), 0, None)
    curve = fit_monotone(P, noisy, truth > 0)
    assert np.all(np.diff(curve.fit_area) >= 0)
    assert np.max(np.abs(curve.fit_area - truth)) < 10


def test_outlier_spike_does_not_pull_neighbours_up() -> None:
    truth = _quadratic(P)
    spiked = truth.copy()
    spiked[6] = 1000.0  # truth 36
    curve = fit_monotone(P, spiked, truth > 0)
    np.testing.assert_allclose(curve.fit_area[[5, 7, 8]], truth[[5, 7, 8]])
    assert curve.fit_area[6] <= truth[7]


def test_isolated_miss_inside_contact_range_is_interpolated() -> None:
    truth = _quadratic(P)
    areas, contact = truth.copy(), truth > 0
    areas[7], contact[7] = 0.0, False
    curve = fit_monotone(P, areas, contact)
    assert curve.fit_area[7] == pytest.approx((truth[6] + truth[8]) / 2)
    assert curve.onset_kpa == estimate_onset(P, truth, truth > 0)


def test_bad_inputs() -> None:
    with pytest.raises(ValueError, match="finite and >= 0"):
        fit_monotone(P, np.where(P > 5, np.nan, 0.0))
    with pytest.raises(ValueError, match="finite and >= 0"):
        fit_monotone(P, -_quadratic(P) - 1)
    with pytest.raises(ValueError, match="finite and >= 0"):
        fit_monotone(P, np.full(P.size, np.inf))
    with pytest.raises(ValueError, match="lengths"):
        fit_monotone(P, _quadratic(P)[:-1])
    with pytest.raises(ValueError, match="duplicate pressure"):
        fit_monotone([0, 1, 1], [0, 1, 2])
    with pytest.raises(ValueError, match=">= 2 pressure steps"):
        fit_monotone([0], [1])
    with pytest.raises(ValueError, match="median_window"):
        CurveConfig(median_window=2)


# --- onset ------------------------------------------------------------------------------------


def test_onset_known_curve_with_false_positive() -> None:
    p = P + 0.5  # 0.5, 1.5, ... 10.5 kPa
    areas = _quadratic(p)
    contact = areas > 0
    areas[1], contact[1] = 2.0, True  # isolated false positive at 1.5 kPa
    onset = estimate_onset(p, areas, contact)
    assert onset is not None and abs(onset - 3.0) < 0.5
    curve = fit_monotone(p, areas, contact)
    assert curve.fit_area[1] == 0.0
    assert curve.area_at(onset - 0.1) == 0.0


def test_onset_on_grid_is_bracketed() -> None:
    # Onset exactly on a no-contact frame: linear extrapolation from the first two contact
    # frames (4, 16 at 4 and 5 kPa) gives 4 - 4/12 = 3.67, inside [3, 4].
    onset = estimate_onset(P, _quadratic(P), _quadratic(P) > 0)
    assert onset == pytest.approx(4 - 4 / 12)


def test_onset_rule_edge_cases() -> None:
    p6 = np.arange(6.0)
    c = np.array([0, 1, 0, 1, 1, 1], bool)  # lone contact then a miss: not the onset
    assert 2.0 <= estimate_onset(p6, c * 10.0, c) <= 3.0
    c = np.array([0, 0, 1, 1, 0, 1], bool)  # a miss inside the contact range: no reset
    assert 1.0 <= estimate_onset(p6, c * p6, c) <= 2.0
    c = np.array([0, 1, 0, 0, 0, 0], bool)  # a lone false positive is no contact
    assert estimate_onset(np.arange(6.0), c * 10.0, c) is None
    c = np.ones(4, bool)  # contact from the first frame: not calibrated below it
    assert estimate_onset(np.arange(4.0), [5.0, 6, 7, 8], c) == 0.0


def test_all_zero_areas() -> None:
    curve = fit_monotone(P, np.zeros(P.size))
    assert curve.onset_kpa is None and not curve.has_contact
    np.testing.assert_array_equal(curve.fit_area, 0.0)
    assert curve.area_at(5.0) == 0.0
    with pytest.raises(ValueError, match="no contact in this calibration; cannot invert"):
        curve.pressure_for_area(10.0)
    with pytest.raises(ValueError, match="cannot invert"):
        curve.inverse_table()


# --- inverse ---------------------------------------------------------------------------------


def test_inverse_round_trip_and_clamping() -> None:
    curve = fit_monotone(P, _quadratic(P), area_unit="mm²")
    for target in (0.5, 4.0, 10.0, 99.0, 196.0):
        q, warning = curve.pressure_for_area(target)
        assert warning is None
        assert curve.area_at(q) == pytest.approx(target)
    assert curve.pressure_for_area(100.0) == (8.0, None)
    q, warning = curve.pressure_for_area(300.0)
    assert q == 10.0
    assert warning == "target 300 mm² above calibrated maximum 196 mm² at 10 kPa; clamped"
    assert curve.pressure_for_area(0.0) == (curve.onset_kpa, None)
    with pytest.raises(ValueError):
        curve.pressure_for_area(-1.0)
    with pytest.raises(ValueError):
        curve.pressure_for_area(float("nan"))
    assert curve.pressure_for_area(np.float32(100.0)) == curve.pressure_for_area(np.array(100))
    for not_a_number in ("100", None, True, np.array([100.0])):  # float() read the first three
        with pytest.raises(TypeError, match="pressure_for_area: expected an area in mm²"):
            curve.pressure_for_area(not_a_number)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="area_at: expected a pressure in kPa"):
        curve.area_at("8")  # type: ignore[arg-type]


def test_inverse_flat_segment_returns_lowest_pressure() -> None:
    curve = Curve(np.array([0.0, 1, 2, 3, 4]), np.array([0.0, 10, 20, 20, 30]), 0.5)
    assert curve.pressure_for_area(20.0) == (2.0, None)
    assert curve.pressure_for_area(25.0) == (3.5, None)
    assert curve.area_at(2.5) == 20.0
    assert curve.area_at(0.4) == 0.0
    assert curve.area_at(99.0) == 30.0


def test_inverse_below_first_contact_without_bracket_warns() -> None:
    curve = fit_monotone([0.0, 1, 2], [5.0, 6, 7])
    assert curve.onset_kpa == 0.0
    q, warning = curve.pressure_for_area(2.0)
    assert q == 0.0 and warning is not None and "below smallest calibrated area" in warning


def test_inverse_table() -> None:
    curve = fit_monotone(P, _quadratic(P), config=CurveConfig(table_step=50.0))
    table = curve.inverse_table()
    _, knot_areas = curve.knots()
    assert [a for a, _ in table] == sorted({0.0, 50.0, 100.0, 150.0, 196.0, *knot_areas})
    by_area = dict(table)
    assert by_area[0.0] == curve.onset_kpa and by_area[100.0] == 8.0 and table[-1][1] == 10.0
    auto = fit_monotone(P, _quadratic(P)).inverse_table()
    assert all(b[0] > a[0] and b[1] > a[1] for a, b in itertools.pairwise(auto))
    assert len(auto) <= 102 and auto[1][0] == 2.0  # 196 / 100 -> 1-2-5 step 2


def test_inverse_table_interpolates_to_the_curves_own_inverse() -> None:
    """A controller interpolating the table linearly got pressures up to 2 kPa off the curve:
    the rows skipped the isotonic fit's breakpoints and the ends of its flat segments."""
    pressures = np.arange(0.0, 11.0)
    curve = fit_monotone(pressures, [0, 0, 0, 10, 30, 30, 30, 80, 120, 150, 150])
    table = curve.inverse_table(step=50.0)
    areas, kpa = (np.array(col) for col in zip(*table, strict=True))
    assert np.all(np.diff(areas) >= 0) and np.all(np.diff(kpa) > 0)
    _, y = curve.knots()
    flat = float(y[np.diff(y, append=np.inf) == 0][0])  # the fit's flat segment (30 mm²)
    assert [p for a, p in table if a == flat] == [4.0, 6.0]  # its lowest and highest pressure
    assert [p for a, p in table if a == y[-1]] == [curve.pressure_for_area(y[-1])[0]]
    q = np.setdiff1d(np.linspace(0.0, float(y[-1]), 601), areas)
    exact = [curve.pressure_for_area(a)[0] for a in q]
    np.testing.assert_allclose(np.interp(q, areas, kpa), exact, atol=1e-9)
    fit = curve.fit_area
    band = Band(pressures, np.maximum(fit - 5.0, 0.0), fit + 5.0, 0.9, 10, 0)
    rows = dataclasses.replace(curve, band=band).inverse_table_with_interval(step=50.0)
    assert set(table) <= {r[:2] for r in rows}  # and rows where the band's edges bend
    assert all(lo <= p <= hi for _, p, lo, hi in rows)


def test_a_clamp_warning_tells_the_target_from_the_limit() -> None:
    """A target just above the largest area read "target 143.8 mm² above calibrated maximum
    143.8 mm²"."""
    curve = fit_monotone(P, _quadratic(P))
    top = curve.area_range()[1]
    _, warning = curve.pressure_for_area(top + 0.004)
    assert warning is not None and f"target {top + 0.004:.6g} mm² above" in warning
    assert f"calibrated maximum {top:.6g} mm²" in warning
    _, warning = curve.pressure_for_area(top + 5.0)  # 4 digits where they suffice
    assert f"target {top + 5.0:.4g} mm² above calibrated maximum {top:.4g} mm²" in warning

"""Tests of the reduced membrane/finger contact model (`contactcal.synth.mechanics`)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from contactcal.synth.mechanics import (
    CLAMP_MARGIN_FRACTION,
    equilibrium_area_mm2,
    hertz_area_mm2,
    onset_pressure_kpa,
    solve_contact,
    tension_for_onset,
)
from contactcal.synth.mechanics_params import FingerParams, MembraneParams

# Fitted fingertip parameters (R mm, E0 MPa, beta 1/N) from the header of
# shared/reference/fingertip_contact_area.csv (SORI, PNAS 2024).
USERS = {"user1": (9.0, 0.013, 0.9), "user2": (7.75, 0.020, 0.7), "user3": (9.0, 0.019, 0.5)}
REFERENCE_CSV = Path(__file__).resolve().parents[2] / "shared/reference/fingertip_contact_area.csv"


def finger(user: str = "user1", **kw: object) -> FingerParams:
    r, e0, beta = USERS[user]
    pad: dict[str, object] = {"width_mm": 16.0, "length_mm": 23.0, "aspect": 1.35}
    hertz: dict[str, object] = {"radius_mm": r, "e0_mpa": e0, "beta_per_n": beta}
    pose: dict[str, object] = {"offset_mm": (0.0, 0.0), "yaw_rad": 0.0, "tilt_rad": 0.0}
    args = pad | hertz | pose | kw
    return FingerParams(**args)  # type: ignore[arg-type]


def membrane(onset_kpa: float = 3.0, gap_mm: float = 1.5, a: float = 12.5) -> MembraneParams:
    return MembraneParams(a, tension_for_onset(onset_kpa, gap_mm, a), gap_mm, 0.75)


HARMONICS = ((0.03, 0.3), (0.02, 1.0), (0.01, 2.0))
PERTURBED = dict(offset_mm=(1.0, -0.5), yaw_rad=0.4, tilt_rad=0.2, harmonics=HARMONICS)
GRID = np.arange(-13.5, 13.5, 0.02) + 0.01  # 0.02 mm pixel centres over the clamp disc


def test_zero_pressure_is_flat_without_contact() -> None:
    s = solve_contact(0.0, finger(), membrane())
    x, y = np.meshgrid(GRID[::10], GRID[::10])
    assert not s.in_contact and s.area_mm2 == 0.0 and s.indentation_mm == 0.0
    assert not s.inside(x, y).any()
    assert np.all(s.membrane_z(x, y) == 0.0)
    assert s.boundary_polygon().shape == (0, 2)


def test_below_onset_is_a_cap_without_contact() -> None:
    m = membrane(onset_kpa=3.0)
    s = solve_contact(2.7, finger(**PERTURBED), m)
    assert not s.in_contact and s.area_mm2 == 0.0
    assert not s.inside(np.array([0.0, 1.0]), 0.0).any()
    apex = m.gap_mm * 0.9 ** (1 / 3)  # Hencky membrane: h ∝ p^(1/3), h = gap at onset
    assert s.plateau_z_mm == pytest.approx(apex) and apex < m.gap_mm
    assert s.membrane_z(0.0, 0.0) == pytest.approx(apex)
    assert s.membrane_z(12.6, 0.0) == 0.0 and s.membrane_z(0.0, -20.0) == 0.0


def test_onset_formula_and_roundtrip() -> None:
    assert onset_pressure_kpa(MembraneParams(12.5, 0.08, 1.5, 0.75)) == pytest.approx(3.072)
    rng = np.random.default_rng(0)
    for _ in range(50):
        on, g, a = rng.uniform(2, 4), rng.uniform(1, 2), rng.uniform(11.5, 13.5)
        m = MembraneParams(a, tension_for_onset(on, g, a), g, rng.uniform(0.5, 1.0))
        p_on = onset_pressure_kpa(m)
        assert 2.0 <= p_on <= 4.0 and p_on == pytest.approx(on)
        assert not solve_contact(p_on - 1e-3, finger(), m).in_contact
        assert solve_contact(p_on + 1e-3, finger(), m).in_contact


def test_equilibrium_is_hertz_fixed_point() -> None:
    for user in USERS:
        f = finger(user)
        for p in (0.5, 3.0, 10.0, 20.0):
            area = equilibrium_area_mm2(p, f)
            assert area > 0 and area == pytest.approx(hertz_area_mm2(p / 1000 * area, f), rel=1e-9)
    assert equilibrium_area_mm2(0.0, finger()) == 0.0
    assert equilibrium_area_mm2(10.0, finger(beta_per_n=0.0)) > 0


@pytest.mark.skipif(not REFERENCE_CSV.exists(), reason="shared reference data not present")
def test_hertz_law_matches_rigid_surface_data() -> None:
    with REFERENCE_CSV.open() as fh:
        rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    for r in rows:
        if r["surface"] == "pla":
            a = hertz_area_mm2(float(r["force_n"]), finger(r["user"]))
            assert a == pytest.approx(float(r["area_mm2"]), rel=0.25), r


@pytest.mark.parametrize("user", list(USERS))
def test_area_monotone_and_growth_slows(user: str) -> None:
    for f in (finger(user), finger(user, **PERTURBED)):
        ps = np.arange(0.0, 20.01, 0.1)
        areas = np.array([solve_contact(p, f, membrane()).area_mm2 for p in ps])
        assert np.all(np.diff(areas) >= -1e-9)
        area = dict(zip(np.round(ps, 1), areas, strict=True))
        assert (area[8.0] - area[4.0]) / 4 > (area[20.0] - area[15.0]) / 5 > 0


@pytest.mark.parametrize("aspect", [1.2, 1.35, 1.5])
def test_aspect_at_10kpa(aspect: float) -> None:
    s = solve_contact(10.0, finger(aspect=aspect, width_mm=18.0, yaw_rad=0.7), membrane())
    long_ax, short_ax = s.semi_axes_mm
    assert 1.2 <= long_ax / short_ax <= 1.5
    assert s.area_mm2 == pytest.approx(math.pi * long_ax * short_ax, rel=1e-5)
    rel = s.boundary_polygon(2048) - np.array(s.centre_mm)
    along = rel @ np.array([math.cos(0.7), math.sin(0.7)])
    assert along.max() == pytest.approx(long_ax, rel=1e-4)


def test_reference_users_table() -> None:
    m = membrane(onset_kpa=3.0)
    print("\nuser   onset_kpa  A(5)  A(10)  A(20) mm²  [Hertz fixed point 5/10/20]")
    for user in USERS:
        f = finger(user)
        areas = [solve_contact(p, f, m).area_mm2 for p in (5.0, 10.0, 20.0)]
        eq = [equilibrium_area_mm2(p, f) for p in (5.0, 10.0, 20.0)]
        cols = "  ".join(f"{v:5.1f}" for v in areas)
        fixed = " ".join(f"{v:5.1f}" for v in eq)
        print(f"{user}  {onset_pressure_kpa(m):8.2f}  {cols}   [{fixed}]")
        assert all(30.0 <= v <= 300.0 for v in areas), (user, areas)
        assert all(60.0 <= v <= 300.0 for v in areas[1:]), (user, areas)
    # README: the fixed point is about 100, 140, 190 mm² for user1.
    eq1 = [equilibrium_area_mm2(p, finger("user1")) for p in (5.0, 10.0, 20.0)]
    assert eq1 == pytest.approx([100.0, 140.0, 190.0], rel=0.1)


def test_height_continuity_and_gap_at_onset() -> None:
    m = membrane(onset_kpa=3.0, gap_mm=1.5)
    f = finger(**PERTURBED)
    p_on = onset_pressure_kpa(m)
    below, above = solve_contact(p_on - 1e-6, f, m), solve_contact(p_on + 1e-6, f, m)
    assert below.plateau_z_mm == pytest.approx(m.gap_mm, rel=1e-5)
    assert above.plateau_z_mm == pytest.approx(m.gap_mm, rel=1e-5)
    for p in (3.5, 10.0, 20.0):
        s = solve_contact(p, f, m)
        assert (
            s.indentation_mm == pytest.approx(s.plateau_z_mm - m.gap_mm) and s.indentation_mm >= 0
        )
        c = np.array(s.centre_mm)
        rel = s.boundary_polygon(1024) - c
        z_in = s.membrane_z(*(c + rel * (1 - 1e-6)).T)
        z_out = s.membrane_z(*(c + rel * (1 + 1e-6)).T)
        assert np.allclose(z_in, s.plateau_z_mm) and np.allclose(z_out, s.plateau_z_mm, atol=1e-6)


def test_membrane_z_shape_and_bounds() -> None:
    s = solve_contact(12.0, finger(**PERTURBED), membrane())
    x, y = np.meshgrid(GRID[::8], GRID[::8])
    z = s.membrane_z(x, y)
    assert z.shape == x.shape and z.dtype == np.float64 and np.isfinite(z).all()
    assert z.min() >= 0.0 and z.max() == pytest.approx(s.plateau_z_mm)
    assert np.all(z[x**2 + y**2 >= s.clamp_radius_mm**2] == 0.0)
    assert np.all(z[s.inside(x, y)] == s.plateau_z_mm)
    assert s.membrane_z(GRID[:, None], GRID[None, :5]).shape == (GRID.size, 5)
    assert s.inside(0.0, 0.0).shape == ()


def test_inside_pixel_count_matches_area() -> None:
    for p in (4.0, 10.0, 20.0):
        s = solve_contact(p, finger(**PERTURBED), membrane())
        x, y = np.meshgrid(GRID, GRID)
        assert s.inside(x, y).sum() * 0.02**2 == pytest.approx(s.area_mm2, rel=0.01)


def test_patch_is_kept_inside_the_clamp() -> None:
    f = finger(offset_mm=(9.0, 2.0), width_mm=18.0, length_mm=26.0, e0_mpa=0.005, beta_per_n=0.1)
    m = membrane(a=11.5)
    s = solve_contact(20.0, f, m)
    poly = s.boundary_polygon(2048)
    assert np.hypot(*poly.T).max() <= (1 - CLAMP_MARGIN_FRACTION) * 11.5 + 1e-9
    assert np.isfinite(s.membrane_z(poly[:, 0] * 1.01, poly[:, 1] * 1.01)).all()


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: solve_contact(-1.0, finger(), membrane()), "pressure_kpa"),
        (lambda: solve_contact(float("nan"), finger(), membrane()), "pressure_kpa"),
        (lambda: solve_contact(float("inf"), finger(), membrane()), "pressure_kpa"),
        (lambda: finger(radius_mm=0.0), "radius_mm"),
        (lambda: finger(radius_mm=float("nan")), "radius_mm"),
        (lambda: finger(e0_mpa=-0.01), "e0_mpa"),
        (lambda: finger(aspect=0.9), "aspect"),
        (lambda: finger(offset_mm=(0.0,)), "offset_mm"),
        (lambda: finger(harmonics=((0.3, 0.0), (0.3, 1.0))), "harmonics"),
        (lambda: MembraneParams(12.5, 0.0, 1.5, 0.75), "tension_n_per_mm"),
        (lambda: MembraneParams(12.5, -0.1, 1.5, 0.75), "tension_n_per_mm"),
        (lambda: MembraneParams(0.0, 0.08, 1.5, 0.75), "clamp_radius_mm"),
        (lambda: MembraneParams(12.5, 0.08, -0.1, 0.75), "gap_mm"),
        (lambda: MembraneParams(12.5, 0.08, float("nan"), 0.75), "gap_mm"),
        (lambda: tension_for_onset(3.0, -1.0, 12.5), "gap_mm"),
        (lambda: tension_for_onset(3.0, 1.5, 0.0), "clamp_radius_mm"),
        (lambda: hertz_area_mm2(-1.0, finger()), "force_n"),
        (lambda: solve_contact(5.0, finger(), membrane()).boundary_polygon(2), "n >= 3"),
    ],
)
def test_bad_inputs_raise(call: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()  # type: ignore[operator]


@pytest.mark.parametrize("slope", [0.15, 0.5])
def test_departure_slope_leaves_the_edge_at_that_slope(slope: float) -> None:
    """The membrane keeps the plateau and the clamp, and leaves the edge at ``slope``."""
    import dataclasses

    plain = solve_contact(12.0, finger(**PERTURBED), membrane())
    m = dataclasses.replace(membrane(), departure_slope=slope)
    s = solve_contact(12.0, finger(**PERTURBED), m)
    assert s.departure_slope == slope and s.area_mm2 == plain.area_mm2  # shape only
    assert s.plateau_z_mm == plain.plateau_z_mm
    x, y = np.meshgrid(GRID[::8], GRID[::8])
    z, z0 = s.membrane_z(x, y), plain.membrane_z(x, y)
    assert z.min() >= 0.0 and np.all(z <= z0) and np.all(z[s.inside(x, y)] == s.plateau_z_mm)
    assert np.all(z[x**2 + y**2 >= s.clamp_radius_mm**2] == 0.0)
    # along the long axis (yaw 0.4) from the patch centre, just outside the boundary
    c, u = np.array(s.centre_mm), np.array([math.cos(0.4), math.sin(0.4)])
    rb = float(np.hypot(*(s.boundary_polygon(4096)[0] - c)))
    h = 1e-4
    z_at = [float(s.membrane_z(*(c + (rb + d) * u))) for d in (h, 2 * h)]
    plain_at = [float(plain.membrane_z(*(c + (rb + d) * u))) for d in (h, 2 * h)]
    assert z_at[0] == pytest.approx(s.plateau_z_mm, abs=1e-3)  # continuous at the edge
    dz, dz0 = (z_at[1] - z_at[0]) / h, (plain_at[1] - plain_at[0]) / h
    assert dz - dz0 == pytest.approx(-slope, rel=0.01)
    assert abs(dz0) < 0.01  # the clamped annulus alone leaves with zero slope


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan")])
def test_departure_slope_is_checked(bad: float) -> None:
    import dataclasses

    with pytest.raises(ValueError, match="departure_slope"):
        dataclasses.replace(membrane(), departure_slope=bad)

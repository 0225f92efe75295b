"""Reduced contact mechanics of the inflated membrane against a fingertip.

Units: lengths mm, forces N, stresses MPa = N/mm², tension N/mm; pressures are kPa at the API
(``p [MPa] = p [kPa] / 1000``). World frame as in `docs/CONVENTIONS.md` (z up, towards the finger).
Full derivation and reference table: `docs/mechanics.md`.

Model (one call to `solve_contact` per pressure):

1. Free membrane: paraboloid cap ``z(r) = h (1 - r²/a²)`` with the large-deflection (Hencky)
   law of a thin membrane without pre-tension, ``h ∝ p^(1/3)``: ``h = g (p / p_on)^(1/3)``
   (clamp radius ``a``, gap ``g``). Most of the inflation happens at low pressure (69 % of the
   gap at a third of the onset pressure), which is what brings the inner ring back and shrinks
   it at 1-2 kPa as in the paper (docs/fidelity.md); a linear law ``h = p a² / (4 T)`` would
   not.
   A membrane without pre-tension is slack at rest: below ``SLACK_TAUT_KPA`` its cap carries
   seeded wrinkles of amplitude ``slack_mm`` (fading linearly), which scatter the flat
   membrane's reflection of the LGP (the paper sees no inner ring at 0 kPa).
2. Onset: the apex reaches the finger at gap ``g``; ``p_on = 4 T g / a²`` defines the
   effective tension ``T`` at onset used for the shape in contact.
3. Area: Hertz finger law ``A_h(F) = pi (0.75 R F / E_f(F))^(2/3)``, ``E_f = E0 (1 + beta F)``
   (SORI, PNAS 2024; rigid surface). With ``F = p A`` the equilibrium ``A = A_h(p A)`` becomes,
   for ``s = sqrt(A)``, the monotone cubic ``beta p s³ + s = pi^1.5 0.75 R p / E0`` (unique positive
   root, Newton from an upper bound). It is multiplied by ``1 - exp(-(p - p_on)/tau)`` so the area
   is 0 at onset and continuous.
4. Shape: ``b = sqrt(A / (pi aspect))`` (across the finger), ``l = aspect b`` (along it), softly
   saturated by the pad with a sharp soft clip ``clip(x) = x / (1 + x⁴)^(1/4)``:
   ``b_s = (W/2) clip(b/(W/2))``, ``l_s = (L/2) clip(l/(L/2))`` (≈ identity well below the pad
   size, unlike ``tanh`` which already trims 18 % at 84 % of it).
5. Placement: centre = finger offset + ``R sin(tilt)`` along the finger (clipped to
   ``CENTRE_MAX_FRACTION a`` from the axis); long axis at ``yaw``; tilt adds an egg-shaped first
   harmonic ``eps_1 = TILT_EGG_GAIN sin(tilt)`` (phase 0: the +finger end is fuller); user harmonics
   n = 2, 3, ... follow. If the boundary leaves the disc of radius ``(1 - CLAMP_MARGIN_FRACTION) a``
   the whole patch is scaled about its centre until it fits (documented shrink, not a clip).
6. Surface in contact: plateau at ``z_top = max(g, p/(4T) ((a² - rm²) - 2 rm² ln(a/rm)))``,
   ``rm = sqrt(area/pi)`` (the formula equals g at onset); along each ray from the centre an
   axisymmetric clamped-annulus profile from r_b(phi) to the clamp R_c(phi) (see `membrane_shape`).
   The ``max(g, .)`` matters just after onset, where the uncoupled area law would put the plateau
   below the finger; the indentation ``z_top - g`` is therefore >= 0. It is then softly capped
   at ``MAX_INDENTATION_MM`` (the pulp's compliance is finite; with the several-mm gaps the
   renderer needs for a shrinking inner ring, the raw formula would indent 5+ mm).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from contactcal.synth.mechanics_params import (
    TILT_EGG_GAIN,
    FingerParams,
    MembraneParams,
    _finite,
    _positive,
    _require,
)
from contactcal.synth.membrane_shape import (
    AREA_POLYGON_POINTS,
    ContactState,
    boundary_radius,
    polygon_area_mm2,
)

__all__ = [
    "CENTRE_MAX_FRACTION",
    "CLAMP_MARGIN_FRACTION",
    "INFLATION_EXPONENT",
    "MAX_INDENTATION_MM",
    "SLACK_TAUT_KPA",
    "TILT_EGG_GAIN",
    "ContactState",
    "FingerParams",
    "MembraneParams",
    "equilibrium_area_mm2",
    "hertz_area_mm2",
    "onset_pressure_kpa",
    "solve_contact",
    "tension_for_onset",
]

CLAMP_MARGIN_FRACTION = 0.08  # patch kept within (1 - this) a, leaving room for the annulus
MAX_INDENTATION_MM = 3.0  # finger pulp indentation saturates near this (soft clip); the
#   uncoupled height law alone would push a soft membrane (large gap, low tension) 5+ mm in
SLACK_TAUT_KPA = 0.5  # kPa: the slack membrane's wrinkles fade linearly to 0 by this pressure
INFLATION_EXPONENT = 1.0 / 3.0  # free cap h ∝ p^this: 1/3 = Hencky membrane (no pre-tension);
#   1 = pre-tensioned (linear) membrane, whose inner ring only returns just before contact
CENTRE_MAX_FRACTION = 0.5  # |patch centre| <= this * a; beyond, the finger is off the membrane
Semi = tuple[float, float]  # (long, short) semi-axes, mm


def _soft_clip(x: float) -> float:
    """Saturating map ``x / (1 + x⁴)^(1/4)``: slope 1 at 0, limit 1; sharper knee than tanh."""
    return x / (1.0 + x**4) ** 0.25


def onset_pressure_kpa(membrane: MembraneParams) -> float:
    """First-contact pressure p_on = 4 T g / a² (kPa)."""
    m = membrane
    return 1000.0 * 4.0 * m.tension_n_per_mm * m.gap_mm / m.clamp_radius_mm**2


def tension_for_onset(onset_kpa: float, gap_mm: float, clamp_radius_mm: float) -> float:
    """Effective tension T (N/mm) that makes contact start at `onset_kpa` for this gap and clamp."""
    _positive("tension_for_onset.onset_kpa", onset_kpa)
    _positive("tension_for_onset.gap_mm", gap_mm)
    _positive("tension_for_onset.clamp_radius_mm", clamp_radius_mm)
    return onset_kpa / 1000.0 * clamp_radius_mm**2 / (4.0 * gap_mm)


def hertz_area_mm2(force_n: float, finger: FingerParams) -> float:
    """Finger contact area (mm²) on a rigid flat at normal force `force_n` (N), load-stiffened."""
    _require(
        _finite(force_n) and force_n >= 0.0, "hertz_area_mm2.force_n", "finite >= 0 N", force_n
    )
    e_f = finger.e0_mpa * (1.0 + finger.beta_per_n * force_n)
    return math.pi * (0.75 * finger.radius_mm * force_n / e_f) ** (2.0 / 3.0)


def _check_pressure(pressure_kpa: float) -> None:
    _require(
        _finite(pressure_kpa) and float(pressure_kpa) >= 0.0,
        "pressure_kpa",
        "a finite pressure >= 0 kPa",
        pressure_kpa,
    )


def equilibrium_area_mm2(pressure_kpa: float, finger: FingerParams) -> float:
    """Positive root A of A = A_h(p A) (mm²), before the onset ramp and pad saturation."""
    _check_pressure(pressure_kpa)
    p = pressure_kpa / 1000.0
    c = math.pi**1.5 * 0.75 * finger.radius_mm * p / finger.e0_mpa
    k = finger.beta_per_n * p
    if c == 0.0:
        return 0.0
    s = c if k == 0.0 else min(c, (c / k) ** (1.0 / 3.0))  # both bound the root from above
    for _ in range(200):  # convex increasing cubic: Newton from the right is monotone
        step = (k * s**3 + s - c) / (3.0 * k * s * s + 1.0)
        s -= step
        if abs(step) <= 1e-13 * s:
            break
    return s * s


def _fit_scale(centre: np.ndarray, rb: np.ndarray, ang: np.ndarray, rmax: float) -> float:
    """Largest s <= 1 with |centre + s rb e(ang)| <= rmax for all samples."""
    e = np.stack([np.cos(ang), np.sin(ang)], axis=1) * rb[:, None]
    cd = e @ centre
    vv = np.einsum("ij,ij->i", e, e)
    s = (-cd + np.sqrt(cd * cd - vv * (centre @ centre - rmax * rmax))) / vv
    return float(min(1.0, s.min()))


def _patch_semi_axes(pressure_kpa: float, p_on: float, finger: FingerParams, tau: float) -> Semi:
    """(long, short) semi-axes (mm) of the ramped Hertz area, softly saturated by the pad."""
    ramp = -math.expm1(-(pressure_kpa - p_on) / tau)
    area = equilibrium_area_mm2(pressure_kpa, finger) * ramp
    b = math.sqrt(area / (math.pi * finger.aspect))
    hw, hl = 0.5 * finger.width_mm, 0.5 * finger.length_mm
    return (hl * _soft_clip(finger.aspect * b / hl), hw * _soft_clip(b / hw))


def _patch_centre(finger: FingerParams, a: float) -> np.ndarray:
    """Patch centre (mm): offset + R sin(tilt) along the finger, within CENTRE_MAX_FRACTION a."""
    yaw = float(finger.yaw_rad)
    u = np.array([math.cos(yaw), math.sin(yaw)])
    offset = np.asarray(finger.offset_mm, dtype=np.float64)
    centre = offset + finger.radius_mm * math.sin(finger.tilt_rad) * u
    cmax = CENTRE_MAX_FRACTION * a
    if np.hypot(*centre) > cmax:
        centre *= cmax / np.hypot(*centre)
    return centre


def _patch_harmonics(finger: FingerParams) -> tuple[tuple[int, float, float], ...]:
    """(n, eps_n, phase_n): the tilt's egg shape (n = 1) then the user's harmonics (n >= 2)."""
    harm: tuple[tuple[int, float, float], ...] = ()
    if finger.tilt_rad != 0.0:
        harm = ((1, TILT_EGG_GAIN * math.sin(finger.tilt_rad), 0.0),)
    return harm + tuple(
        (n, float(e), float(ph)) for n, (e, ph) in enumerate(finger.harmonics, start=2)
    )


def _plateau_height(pressure_kpa: float, area_mm2: float, membrane: MembraneParams) -> float:
    """Plateau height z_top (mm): annulus formula, at least the gap, indentation softly capped."""
    a, t, g = membrane.clamp_radius_mm, membrane.tension_n_per_mm, membrane.gap_mm
    p = pressure_kpa / 1000.0
    rm2 = area_mm2 / math.pi
    if rm2 > 0:
        z_formula = p / (4.0 * t) * ((a * a - rm2) - rm2 * math.log(a * a / rm2))
    else:
        z_formula = p * a * a / (4.0 * t)  # the free cap's apex
    return g + MAX_INDENTATION_MM * _soft_clip(max(0.0, z_formula - g) / MAX_INDENTATION_MM)


def _free_cap(
    pressure_kpa: float, p_on: float, finger: FingerParams, membrane: MembraneParams
) -> ContactState:
    """State without contact: the paraboloid cap of apex ``g (p / p_on)^INFLATION_EXPONENT``."""
    a = membrane.clamp_radius_mm
    gap = p_on / 1000.0 * a * a / (4.0 * membrane.tension_n_per_mm)
    slack = membrane.slack_mm * max(0.0, 1.0 - pressure_kpa / SLACK_TAUT_KPA)
    return ContactState(
        pressure_kpa=pressure_kpa,
        onset_kpa=p_on,
        in_contact=False,
        centre_mm=(float(finger.offset_mm[0]), float(finger.offset_mm[1])),
        semi_axes_mm=(0.0, 0.0),
        yaw_rad=float(finger.yaw_rad),
        area_mm2=0.0,
        plateau_z_mm=gap * (pressure_kpa / p_on) ** INFLATION_EXPONENT,
        slack_mm=slack,
        slack_seed=membrane.slack_seed,
        indentation_mm=0.0,
        clamp_radius_mm=float(a),
    )


def solve_contact(
    pressure_kpa: float, finger: FingerParams, membrane: MembraneParams
) -> ContactState:
    """Solve the reduced membrane/finger contact at one pressure.

    Steps 3-6 of the module docstring: area and semi-axes, centre, harmonics, fit in the clamp,
    boundary area, plateau height.

    Args:
        pressure_kpa: inflation pressure (kPa), finite and >= 0.
        finger: fingertip parameters and pose.
        membrane: clamp, tension, gap and onset ramp.

    Returns:
        `ContactState`; without contact (pressure <= onset) it describes the paraboloid cap.

    Raises:
        ValueError: on a negative or non-finite pressure or wrong parameter types.
    """
    _check_pressure(pressure_kpa)
    _require(isinstance(finger, FingerParams), "finger", "FingerParams", type(finger).__name__)
    _require(
        isinstance(membrane, MembraneParams), "membrane", "MembraneParams", type(membrane).__name__
    )
    pressure_kpa = float(pressure_kpa)
    a = membrane.clamp_radius_mm
    p_on = onset_pressure_kpa(membrane)
    if pressure_kpa <= p_on:
        return _free_cap(pressure_kpa, p_on, finger, membrane)
    semi = _patch_semi_axes(pressure_kpa, p_on, finger, membrane.onset_ramp_kpa)
    centre = _patch_centre(finger, a)
    harm = _patch_harmonics(finger)
    yaw = float(finger.yaw_rad)
    phi = np.linspace(0.0, 2.0 * np.pi, AREA_POLYGON_POINTS, endpoint=False)
    rb = boundary_radius(np.cos(phi), np.sin(phi), semi, harm)
    scale = _fit_scale(centre, rb, phi + yaw, (1.0 - CLAMP_MARGIN_FRACTION) * a)
    patch = ContactState(
        pressure_kpa=pressure_kpa,
        onset_kpa=p_on,
        in_contact=True,
        centre_mm=(float(centre[0]), float(centre[1])),
        semi_axes_mm=(semi[0] * scale, semi[1] * scale),
        yaw_rad=yaw,
        area_mm2=0.0,  # filled in below from the boundary polygon
        plateau_z_mm=0.0,
        indentation_mm=0.0,
        clamp_radius_mm=float(a),
        harmonics=harm,
        departure_slope=float(membrane.departure_slope),
    )
    area_b = polygon_area_mm2(patch.boundary_polygon(AREA_POLYGON_POINTS))
    z_top = _plateau_height(pressure_kpa, area_b, membrane)
    return replace(
        patch, area_mm2=area_b, plateau_z_mm=z_top, indentation_mm=z_top - membrane.gap_mm
    )

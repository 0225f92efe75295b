"""Reduced contact mechanics of the inflated membrane against a fingertip.

Units: lengths mm, forces N, stresses MPa = N/mm², tension N/mm; pressures are kPa at the API
(``p [MPa] = p [kPa] / 1000``). World frame as in `docs/CONVENTIONS.md` (z up, towards the finger).
Full derivation and reference table: `docs/mechanics.md`.

Model (one call to `solve_contact` per pressure):

1. Free membrane: small-slope paraboloid cap ``z(r) = h (1 - r²/a²)``, ``h = p a² / (4 T)``
   (clamp radius ``a``, effective tension ``T``).
2. Onset: the apex reaches the finger at gap ``g`` when ``p_on = 4 T g / a²``.
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
from dataclasses import dataclass

import numpy as np

from contactcal.synth.membrane_shape import (
    AREA_POLYGON_POINTS,
    ContactState,
    boundary_radius,
    polygon_area_mm2,
)

__all__ = [
    "CENTRE_MAX_FRACTION",
    "CLAMP_MARGIN_FRACTION",
    "MAX_INDENTATION_MM",
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

TILT_EGG_GAIN = 0.25  # eps_1 per sin(tilt): 0.3 rad tilt -> 7 % egg asymmetry
CLAMP_MARGIN_FRACTION = 0.08  # patch kept within (1 - this) a, leaving room for the annulus
MAX_INDENTATION_MM = 3.0  # finger pulp indentation saturates near this (soft clip); the
#   uncoupled height law alone would push a soft membrane (large gap, low tension) 5+ mm in
CENTRE_MAX_FRACTION = 0.5  # |patch centre| <= this * a; beyond, the finger is off the membrane


def _soft_clip(x: float) -> float:
    """Saturating map ``x / (1 + x⁴)^(1/4)``: slope 1 at 0, limit 1; sharper knee than tanh."""
    return x / (1.0 + x**4) ** 0.25


def _require(ok: bool, what: str, expected: str, got: object) -> None:
    if not ok:
        raise ValueError(f"contactcal.synth.mechanics: {what}: expected {expected}, got {got!r}")


def _finite(x: object) -> bool:
    try:
        return math.isfinite(float(x))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False


def _positive(name: str, x: object) -> None:
    _require(_finite(x) and float(x) > 0.0, name, "a finite number > 0", x)  # type: ignore[arg-type]


@dataclass(frozen=True)
class FingerParams:
    """Fingertip pad, Hertz parameters and pose over the membrane."""

    width_mm: float  # mm, pad width W (13-18); smaller -> patch width saturates earlier
    length_mm: float  # mm, pad length L (20-26), >= width; caps the long semi-axis at L/2
    radius_mm: float  # mm, Hertz sphere radius R (7-10); larger -> larger area at equal force
    e0_mpa: float  # MPa, small-load modulus E0 (0.01-0.02); stiffer -> smaller area
    beta_per_n: float  # 1/N, load stiffening beta (0.5-0.9); larger -> earlier area saturation
    aspect: float  # long/short axis ratio (1.2-1.5), >= 1; long axis along the finger
    offset_mm: tuple[float, float]  # mm, finger's lowest point (x, y) over the membrane centre
    yaw_rad: float  # rad, finger direction about +z (world x = 0)
    tilt_rad: float  # rad, pitch change; shifts patch R sin(tilt) along finger, egg-shapes it
    harmonics: tuple[tuple[float, float], ...] = ()  # (eps_n, phase_n rad) for n = 2, 3, ...

    def __post_init__(self) -> None:
        for name in ("width_mm", "length_mm", "radius_mm", "e0_mpa"):
            _positive(f"FingerParams.{name}", getattr(self, name))
        _require(
            self.length_mm >= self.width_mm,
            "FingerParams.length_mm",
            ">= width_mm",
            (self.length_mm, self.width_mm),
        )
        b = self.beta_per_n
        _require(_finite(b) and b >= 0.0, "FingerParams.beta_per_n", "finite >= 0", b)
        _require(
            _finite(self.aspect) and self.aspect >= 1.0,
            "FingerParams.aspect",
            "finite >= 1 (long/short)",
            self.aspect,
        )
        off = self.offset_mm
        _require(
            isinstance(off, tuple) and len(off) == 2 and all(_finite(v) for v in off),
            "FingerParams.offset_mm",
            "a tuple of 2 finite floats (mm)",
            off,
        )
        _require(_finite(self.yaw_rad), "FingerParams.yaw_rad", "a finite angle", self.yaw_rad)
        t = self.tilt_rad
        _require(_finite(t) and abs(t) < 0.5 * math.pi, "FingerParams.tilt_rad", "|tilt| < pi/2", t)
        h = self.harmonics
        ok = isinstance(h, tuple) and all(
            isinstance(e, tuple) and len(e) == 2 and all(_finite(v) for v in e) for e in h
        )
        _require(ok, "FingerParams.harmonics", "a tuple of (eps, phase) float pairs", h)
        total = sum(abs(e[0]) for e in h) + TILT_EGG_GAIN * abs(math.sin(t))
        _require(total < 0.5, "FingerParams.harmonics", "sum |eps_n| (+ tilt egg) < 0.5", total)


@dataclass(frozen=True)
class MembraneParams:
    """Clamped, pre-tensioned membrane and its gap to the finger."""

    clamp_radius_mm: float  # mm, clamp circle radius a (11.5-13.5); larger -> softer, earlier onset
    tension_n_per_mm: float  # N/mm, effective tension T (0.05-0.12); larger -> later onset
    gap_mm: float  # mm, flat membrane to finger's lowest point (1-2), >= 0; larger -> later onset
    onset_ramp_kpa: float  # kPa, ramp tau (0.5-1); smaller -> area jumps faster after onset

    def __post_init__(self) -> None:
        _positive("MembraneParams.clamp_radius_mm", self.clamp_radius_mm)
        _positive("MembraneParams.tension_n_per_mm", self.tension_n_per_mm)
        _positive("MembraneParams.onset_ramp_kpa", self.onset_ramp_kpa)
        g = self.gap_mm
        _require(_finite(g) and g >= 0.0, "MembraneParams.gap_mm", "finite >= 0 (mm)", g)


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


def solve_contact(
    pressure_kpa: float, finger: FingerParams, membrane: MembraneParams
) -> ContactState:
    """Solve the reduced membrane/finger contact at one pressure.

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
    a, t, g = membrane.clamp_radius_mm, membrane.tension_n_per_mm, membrane.gap_mm
    p_on = onset_pressure_kpa(membrane)
    p = pressure_kpa / 1000.0
    cap = p * a * a / (4.0 * t)
    if pressure_kpa <= p_on:
        off = (float(finger.offset_mm[0]), float(finger.offset_mm[1]))
        return ContactState(
            pressure_kpa,
            p_on,
            False,
            off,
            (0.0, 0.0),
            float(finger.yaw_rad),
            0.0,
            cap,
            0.0,
            float(a),
        )
    ramp = -math.expm1(-(pressure_kpa - p_on) / membrane.onset_ramp_kpa)
    area = equilibrium_area_mm2(pressure_kpa, finger) * ramp
    b = math.sqrt(area / (math.pi * finger.aspect))
    hw, hl = 0.5 * finger.width_mm, 0.5 * finger.length_mm
    semi = (hl * _soft_clip(finger.aspect * b / hl), hw * _soft_clip(b / hw))
    yaw = float(finger.yaw_rad)
    u = np.array([math.cos(yaw), math.sin(yaw)])
    centre = (
        np.asarray(finger.offset_mm, dtype=np.float64)
        + finger.radius_mm * math.sin(finger.tilt_rad) * u
    )
    cmax = CENTRE_MAX_FRACTION * a
    if np.hypot(*centre) > cmax:
        centre *= cmax / np.hypot(*centre)
    harm: tuple[tuple[int, float, float], ...] = ()
    if finger.tilt_rad != 0.0:
        harm = ((1, TILT_EGG_GAIN * math.sin(finger.tilt_rad), 0.0),)
    harm += tuple((n, float(e), float(ph)) for n, (e, ph) in enumerate(finger.harmonics, start=2))
    phi = np.linspace(0.0, 2.0 * np.pi, AREA_POLYGON_POINTS, endpoint=False)
    rb = boundary_radius(np.cos(phi), np.sin(phi), semi, harm)
    scale = _fit_scale(centre, rb, phi + yaw, (1.0 - CLAMP_MARGIN_FRACTION) * a)
    semi = (semi[0] * scale, semi[1] * scale)
    state = ContactState(
        pressure_kpa,
        p_on,
        True,
        (float(centre[0]), float(centre[1])),
        semi,
        yaw,
        0.0,
        0.0,
        0.0,
        float(a),
        harm,
    )
    area_b = polygon_area_mm2(state.boundary_polygon(AREA_POLYGON_POINTS))
    rm2 = area_b / math.pi
    z_formula = p / (4.0 * t) * ((a * a - rm2) - rm2 * math.log(a * a / rm2)) if rm2 > 0 else cap
    z_top = g + MAX_INDENTATION_MM * _soft_clip(max(0.0, z_formula - g) / MAX_INDENTATION_MM)
    return ContactState(
        pressure_kpa,
        p_on,
        True,
        state.centre_mm,
        semi,
        yaw,
        area_b,
        z_top,
        z_top - g,
        float(a),
        harm,
    )

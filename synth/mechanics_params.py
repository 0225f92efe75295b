"""Parameters of the reduced contact mechanics: fingertip and membrane (validated dataclasses).

Units and meaning: `contactcal.synth.mechanics` and `docs/mechanics.md`; both classes are
re-exported by `contactcal.synth.mechanics`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

TILT_EGG_GAIN = 0.25  # eps_1 per sin(tilt): 0.3 rad tilt -> 7 % egg asymmetry


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


#: Steepest departure of the membrane from the contact edge (dz/dr): a fingertip's surface slope
#: at the edge of a large patch (r_b ≈ 7 mm on a 9 mm sphere) is ~1.
MAX_DEPARTURE_SLOPE = 1.0


@dataclass(frozen=True)
class MembraneParams:
    """Clamped membrane, its gap to the finger and its slack at rest."""

    clamp_radius_mm: float  # mm, clamp circle radius a (11.5-13.5); larger -> softer, earlier onset
    tension_n_per_mm: float  # N/mm, effective tension T (0.05-0.12); larger -> later onset
    gap_mm: float  # mm, flat membrane to finger's lowest point (1-2), >= 0; larger -> later onset
    onset_ramp_kpa: float  # kPa, ramp tau (0.5-1); smaller -> area jumps faster after onset
    slack_mm: float = 0.0  # mm, wrinkle amplitude of the slack membrane at 0 kPa (gone by
    #   SLACK_TAUT_KPA); scatters the flat membrane's LGP reflex, absent at 0 kPa in the paper
    slack_seed: int = 0  # seed of the wrinkle pattern (one membrane = one pattern)
    # dz/dr (≥ 0, ≤ MAX_DEPARTURE_SLOPE) at which the free annulus leaves the contact edge: 0 is
    # the clamped annulus's zero slope (the v2 world: the inner ring ~0.6 mm outside the edge);
    # > 0, a membrane leaving a curved fingertip at its slope: the ring closes on the edge (~0.3),
    # then leaves no ring near it at all (~0.5). Shape only: the area-pressure law is unchanged.
    departure_slope: float = 0.0

    def __post_init__(self) -> None:
        _positive("MembraneParams.clamp_radius_mm", self.clamp_radius_mm)
        _positive("MembraneParams.tension_n_per_mm", self.tension_n_per_mm)
        _positive("MembraneParams.onset_ramp_kpa", self.onset_ramp_kpa)
        g = self.gap_mm
        _require(_finite(g) and g >= 0.0, "MembraneParams.gap_mm", "finite >= 0 (mm)", g)
        w = self.slack_mm
        _require(_finite(w) and w >= 0.0, "MembraneParams.slack_mm", "finite >= 0 (mm)", w)
        d = self.departure_slope
        _require(
            _finite(d) and 0.0 <= d <= MAX_DEPARTURE_SLOPE,
            "MembraneParams.departure_slope",
            f"finite in [0, {MAX_DEPARTURE_SLOPE}] (dz/dr)",
            d,
        )

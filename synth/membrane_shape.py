"""Geometry of the solved membrane: contact patch boundary, inside test and surface height.

`ContactState` is produced by `contactcal.synth.mechanics.solve_contact`; the physics of the
reduced model is documented there and in `docs/mechanics.md`. This module only evaluates the
resulting shape (all lengths in mm, world frame of `docs/CONVENTIONS.md`).

Patch frame: origin at the patch centre, angle ``phi`` measured from the long axis (the finger
direction, world angle ``yaw_rad``). The boundary is
``r_b(phi) = r_ellipse(phi) * (1 + sum_n eps_n cos(n (phi - phase_n)))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "AREA_POLYGON_POINTS",
    "ContactState",
    "boundary_radius",
    "polygon_area_mm2",
    "wrinkles",
]

AREA_POLYGON_POINTS = 4096  # shoelace resolution for `area_mm2` (relative error ~1e-6)


def boundary_radius(
    cos_phi: np.ndarray,
    sin_phi: np.ndarray,
    semi_axes_mm: tuple[float, float],
    harmonics: tuple[tuple[int, float, float], ...],
) -> np.ndarray:
    """Boundary radius r_b(phi) in the patch frame.

    Args:
        cos_phi: cos of the patch-frame angle, any shape, float64.
        sin_phi: sin of the patch-frame angle, same shape.
        semi_axes_mm: (long, short) semi-axes, mm.
        harmonics: (n, eps_n, phase_n [rad]) boundary perturbations.

    Returns:
        Radius (mm), float64, same shape as the inputs.
    """
    long_ax, short_ax = semi_axes_mm
    r = long_ax * short_ax / np.sqrt((short_ax * cos_phi) ** 2 + (long_ax * sin_phi) ** 2)
    if not harmonics:
        return r
    w = cos_phi + 1j * sin_phi  # exp(i phi); powers give cos(n phi), sin(n phi) without atan2
    factor = np.ones_like(r)
    for n, eps, phase in harmonics:
        factor += eps * np.real(w**n * np.exp(-1j * n * phase))
    return r * factor


@dataclass(frozen=True)
class ContactState:
    """Solved membrane state at one pressure (reduced model, see `contactcal.synth.mechanics`)."""

    pressure_kpa: float  # kPa, inflation pressure this state was solved for
    onset_kpa: float  # kPa, first-contact pressure p_on = 4 T g / a² of the membrane
    in_contact: bool  # True when pressure > onset (patch area > 0)
    centre_mm: tuple[float, float]  # mm, world (x, y) of the patch centre; finger offset if none
    semi_axes_mm: tuple[
        float, float
    ]  # mm, (long, short) after saturation/clamp fit; (0, 0) if none
    yaw_rad: float  # rad, world angle of the long axis (finger direction) about +z
    area_mm2: float  # mm², shoelace area of the perturbed boundary; 0.0 without contact
    plateau_z_mm: float  # mm, plateau height in contact; cap apex height without contact
    indentation_mm: float  # mm, finger indentation plateau_z - gap (>= 0); 0 without contact
    clamp_radius_mm: float  # mm, clamp circle radius a; membrane_z is 0 outside it
    harmonics: tuple[tuple[int, float, float], ...] = ()  # (n, eps_n, phase_n rad) incl. n=1 tilt
    slack_mm: float = 0.0  # mm, wrinkle amplitude of the (not yet taut) membrane; 0 in contact
    slack_seed: int = 0  # seed of the wrinkle pattern
    departure_slope: float = 0.0  # dz/dr leaving the contact edge (MembraneParams); v2 world: 0

    def _patch_polar(
        self, x_mm: np.ndarray, y_mm: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Return (r, rel_x, rel_y, cos_phi, sin_phi) about the patch centre."""
        rx = np.asarray(x_mm, dtype=np.float64) - self.centre_mm[0]
        ry = np.asarray(y_mm, dtype=np.float64) - self.centre_mm[1]
        rx, ry = np.broadcast_arrays(rx, ry)
        r = np.hypot(rx, ry)
        safe = np.where(r > 0.0, r, 1.0)
        cy, sy = np.cos(self.yaw_rad), np.sin(self.yaw_rad)
        cos_phi = np.where(r > 0.0, (rx * cy + ry * sy) / safe, 1.0)
        sin_phi = np.where(r > 0.0, (ry * cy - rx * sy) / safe, 0.0)
        return r, rx, ry, cos_phi, sin_phi

    def inside(self, x_mm: np.ndarray | float, y_mm: np.ndarray | float) -> np.ndarray:
        """Contact mask.

        Args:
            x_mm: world x (mm), any shape broadcastable with `y_mm`.
            y_mm: world y (mm).

        Returns:
            bool array of the broadcast shape; all False without contact.
        """
        x = np.asarray(x_mm, dtype=np.float64)
        y = np.asarray(y_mm, dtype=np.float64)
        if not self.in_contact:
            return np.zeros(np.broadcast_shapes(x.shape, y.shape), dtype=bool)
        r, _, _, c, s = self._patch_polar(x, y)
        return r <= boundary_radius(c, s, self.semi_axes_mm, self.harmonics)

    def membrane_z(self, x_mm: np.ndarray | float, y_mm: np.ndarray | float) -> np.ndarray:
        """Membrane height above the clamp plane.

        Without contact: paraboloid cap ``h (1 - r²/a²)``, plus the slack wrinkles
        ``slack_mm · wrinkles(x, y)`` under the same envelope. In contact: plateau ``plateau_z_mm``
        inside the patch and, along each ray from the patch centre, the clamped-annulus profile
        ``z_top f(r)`` from the boundary r_b to the clamp circle R_c (zero slope at r_b, 0 at R_c),
        lowered by ``s (r − r_b)(1 − t)²`` (``t = (r − r_b)/(R_c − r_b)``, ``s`` =
        ``departure_slope``) so that it leaves the edge at slope ``s`` and still ends at 0 at
        R_c (and never below 0).

        Args:
            x_mm: world x (mm), any shape broadcastable with `y_mm`.
            y_mm: world y (mm).

        Returns:
            float64 heights (mm) of the broadcast shape; 0 outside the clamp circle.
        """
        x = np.asarray(x_mm, dtype=np.float64)
        y = np.asarray(y_mm, dtype=np.float64)
        a = self.clamp_radius_mm
        if not self.in_contact:
            r2 = np.broadcast_to(x * x + y * y, np.broadcast_shapes(x.shape, y.shape))
            h = self.plateau_z_mm + self.slack_mm * wrinkles(x, y, self.slack_seed)
            return np.where(r2 < a * a, h * (1.0 - r2 / (a * a)), 0.0)
        r, rx, ry, c, s = self._patch_polar(x, y)
        rb = boundary_radius(c, s, self.semi_axes_mm, self.harmonics)
        cx, cy = self.centre_mm
        safe = np.where(r > 0.0, r, 1.0)
        cdote = (cx * rx + cy * ry) / safe  # centre · ray direction
        rc = -cdote + np.sqrt(cdote * cdote + a * a - (cx * cx + cy * cy))
        z = np.where(r <= rb, self.plateau_z_mm, 0.0)
        ann = (r > rb) & (r < rc)
        if np.any(ann):
            rr, b2, cc = r[ann], rb[ann] ** 2, rc[ann]
            num = 0.25 * (cc * cc - rr * rr) - 0.5 * b2 * np.log(cc / rr)
            den = 0.25 * (cc * cc - b2) - 0.5 * b2 * np.log(cc / rb[ann])
            z[ann] = self.plateau_z_mm * num / den
            if self.departure_slope > 0.0:
                t = (rr - rb[ann]) / (cc - rb[ann])
                drop = self.departure_slope * (rr - rb[ann]) * (1.0 - t) ** 2
                z[ann] = np.maximum(z[ann] - drop, 0.0)
        return z

    def boundary_polygon(self, n: int = 512) -> np.ndarray:
        """Contact boundary in world coordinates.

        Args:
            n: number of vertices (>= 3), counter-clockwise, not closed.

        Returns:
            (n, 2) float64 world (x, y) in mm; (0, 2) without contact.
        """
        if int(n) < 3:
            raise ValueError(f"boundary_polygon: expected n >= 3 vertices, got {n!r}")
        if not self.in_contact:
            return np.zeros((0, 2), dtype=np.float64)
        phi = np.linspace(0.0, 2.0 * np.pi, int(n), endpoint=False)
        rb = boundary_radius(np.cos(phi), np.sin(phi), self.semi_axes_mm, self.harmonics)
        ang = phi + self.yaw_rad
        return np.stack(
            [self.centre_mm[0] + rb * np.cos(ang), self.centre_mm[1] + rb * np.sin(ang)], axis=1
        )


WRINKLE_WAVES = 8  # plane waves summed into the slack membrane's wrinkles
WRINKLE_PERIOD_MM = (1.5, 4.0)  # wavelength range of the wrinkles, mm


def wrinkles(x_mm: np.ndarray, y_mm: np.ndarray, seed: int) -> np.ndarray:
    """Unit-rms wrinkle pattern of a slack membrane (sum of seeded random plane waves).

    Args:
        x_mm, y_mm: world coordinates (mm), broadcastable.
        seed: pattern seed.

    Returns:
        float64 heights of rms ≈ 1 (multiply by the amplitude in mm).
    """
    rng = np.random.default_rng(seed)
    k = 2 * np.pi / rng.uniform(*WRINKLE_PERIOD_MM, WRINKLE_WAVES)
    ang = rng.uniform(0.0, np.pi, WRINKLE_WAVES)
    phase = rng.uniform(0.0, 2 * np.pi, WRINKLE_WAVES)
    z = np.zeros(np.broadcast_shapes(np.shape(x_mm), np.shape(y_mm)))
    for kk, aa, pp in zip(k, ang, phase, strict=True):
        z = z + np.cos(kk * (np.cos(aa) * x_mm + np.sin(aa) * y_mm) + pp)
    return z * np.sqrt(2.0 / WRINKLE_WAVES)


def polygon_area_mm2(points: np.ndarray) -> float:
    """Shoelace area (mm²) of a closed (n, 2) polygon given without repeated first vertex."""
    x, y = points[:, 0], points[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))

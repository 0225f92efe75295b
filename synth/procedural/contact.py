"""The contact patch: its area-vs-pressure law and its shape (a wavy ellipse).

Own simple law, not the renderer's mechanics: no contact up to the onset ``p0``, then
``A(p) = A20 · ((p − p0) / (20 − p0))^γ`` (concave: fast growth after the onset, saturating
towards 20 kPa; with p0 = 3 kPa, γ = 0.3, A20 = 190 mm² it gives ~100 / 145 / 190 mm² at
5 / 10 / 20 kPa, the reference fingertip figures). The patch is an ellipse (aspect 1.2-1.5,
long axis along the finger) whose edge radius carries a small 3- and 4-fold waviness; it drifts
slightly off-centre as the pressure grows. It lies flat on the window plane, so its true area on
the membrane is its projected area.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contactcal.synth.procedural.session import Finger

#: Pressure at which ``area20_mm2`` is reached, kPa.
P_REF_KPA = 20.0
#: Largest contact long semi-axis, × the window ring radius (the membrane's free part).
MAX_SEMI_AXIS = 0.8
#: Centre drift per kPa above the onset, mm (along the contact's long axis).
DRIFT_MM_PER_KPA = 0.03


@dataclass(frozen=True)
class Patch:
    """The contact patch of one frame, mm (origin at the rig axis, ``y`` down)."""

    cx: float  # centre x, mm
    cy: float  # centre y, mm
    a: float  # long semi-axis of the underlying ellipse, mm
    b: float  # short semi-axis, mm
    angle: float  # long axis direction, rad
    lobes: float  # waviness amplitude, × radius
    phases: tuple[float, float]  # phases of the 3- and 4-fold waviness, rad

    def edge_radius(self, phi: np.ndarray) -> np.ndarray:
        """Edge distance from the centre in direction ``phi`` (rad, any shape), mm."""
        return self._edge(np.cos(phi - self.angle), np.sin(phi - self.angle))

    def _edge(self, c: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Edge distance at direction cosine/sine ``c``, ``s`` relative to the long axis, mm
        (multiple angles by Chebyshev identities: no trigonometric calls on images)."""
        ellipse = self.a * self.b / np.sqrt((self.b * c) ** 2 + (self.a * s) ** 2)
        c3, s3 = c * (4 * c * c - 3), s * (3 - 4 * s * s)
        c4, s4 = 8 * c**4 - 8 * c * c + 1, 4 * s * c * (2 * c * c - 1)
        p3, p4 = self.phases
        wave = (c3 * math.cos(p3) - s3 * math.sin(p3)) + 0.7 * (
            c4 * math.cos(p4) - s4 * math.sin(p4)
        )
        return ellipse * (1.0 + self.lobes * wave)

    def area_mm2(self) -> float:
        """Exact area ``½∮ r(φ)² dφ`` (trapezoid rule on 4096 directions, periodic: exact to
        rounding for this band-limited radius), mm²."""
        phi = np.linspace(0.0, 2 * math.pi, 4096, endpoint=False)
        return float(0.5 * np.mean(self.edge_radius(phi) ** 2) * 2 * math.pi)

    def polar(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(distance from the centre, edge radius in that direction)`` at points ``(x, y)``,
        mm; ``distance < edge`` inside the patch."""
        dx, dy = x - self.cx, y - self.cy
        dist = np.hypot(dx, dy)
        safe = np.maximum(dist, 1e-12)
        ca, sa = math.cos(self.angle), math.sin(self.angle)
        c = np.where(dist > 0, (dx * ca + dy * sa) / safe, 1.0)
        s = np.where(dist > 0, (dy * ca - dx * sa) / safe, 0.0)
        return dist, self._edge(c, s)


def area_law_mm2(finger: Finger, p_kpa: float) -> float:
    """Contact area at ``p_kpa`` (0 at or below the onset), mm², before the size cap."""
    v = finger.values
    p0 = v["onset_kpa"]
    if p_kpa <= p0:
        return 0.0
    return v["area20_mm2"] * ((p_kpa - p0) / (P_REF_KPA - p0)) ** v["area_exponent"]


def contact_patch(finger: Finger, p_kpa: float) -> Patch | None:
    """The patch at ``p_kpa``, or None below the onset.

    The long semi-axis is capped at ``MAX_SEMI_AXIS`` × the window radius minus the offset, so
    the patch stays on the membrane (hard, off-centre sessions reach the cap).
    """
    area = area_law_mm2(finger, p_kpa)
    if area <= 0.0:
        return None
    v = finger.values
    aspect = v["aspect"]
    a = math.sqrt(area * aspect / math.pi)
    cap = MAX_SEMI_AXIS * v["window_radius_mm"] - v["offset_mm"]
    a = min(a, cap)
    cx, cy = finger.centre_mm()
    drift = DRIFT_MM_PER_KPA * (p_kpa - v["onset_kpa"])
    return Patch(
        cx=cx + drift * math.cos(finger.contact_angle),
        cy=cy + drift * math.sin(finger.contact_angle),
        a=a,
        b=a / aspect,
        angle=finger.contact_angle,
        lobes=v["lobes"],
        phases=finger.lobe_phases,
    )

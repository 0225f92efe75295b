"""The rig's luminous structures: the window ring, the coating glow and the inner ring.

Own ring model (not the renderer's optics), after the paper's description of its photographs:
the window (outer) ring is the light guide's reflection on the window, lit by two LED sectors,
and saturates: at 0 kPa it is the brightest structure. The inner ring is the light guide's
reflection on the curved membrane: absent while the membrane is flat (0 kPa), shrinking while
the membrane inflates free of the finger, then hugging the contact edge, its inner edge
sharpening as the pressure grows. Everything is linear intensity, 1.0 = white.
"""

from __future__ import annotations

import math

import numpy as np

from contactcal.synth.procedural.contact import Patch
from contactcal.synth.procedural.grid import Grid
from contactcal.synth.procedural.session import Finger

#: Below this pressure the membrane is flat: no inner ring, kPa.
FLAT_KPA = 0.25
#: Angular half-width of one LED's sector, rad.
LED_SECTOR_RAD = 0.7
#: Inner ring radius while free of the finger: from START × window radius down to END at onset.
FREE_START, FREE_END = 0.72, 0.4
#: Pressure over which the inner ring closes in on the contact edge after onset, kPa.
CLOSE_IN_KPA = 1.5
#: Inner ring gap to the contact edge at high pressure, mm.
GAP_MM = 0.25


def led_profile(finger: Finger, phi: np.ndarray) -> np.ndarray:
    """Angular brightness of the two LED sectors at directions ``phi`` (rad): in ``[1−d, 1]``.

    Each sector is a von Mises bump ``exp((cos(φ − φ_i) − 1) / σ²)``, σ = ``LED_SECTOR_RAD``.
    """
    d = finger.values["led_depth"]
    c, s = np.cos(phi), np.sin(phi)
    best = np.zeros_like(phi)
    for centre in (finger.led_angle, finger.led_angle + finger.led_spread):
        cos_delta = c * math.cos(centre) + s * math.sin(centre)
        best = np.maximum(best, np.exp((cos_delta - 1.0) / LED_SECTOR_RAD**2))
    return (1.0 - d) + d * best


def window_and_glow(grid: Grid, finger: Finger) -> np.ndarray:
    """(H·ss, W·ss) float32: the saturating window ring, the glow inside it, dark walls outside."""
    v = finger.values
    r, led = grid.r, led_profile(finger, grid.theta)  # about the rig axis
    radius, width = v["window_radius_mm"], v["window_width_mm"]
    ring = v["window_peak"] * led * np.exp(-(((r - radius) / width) ** 2))
    inside = 1.0 / (1.0 + np.exp((r - radius + 2 * width) / (0.5 * width)))  # soft rim
    # The LED sectors light the glow from the rim: no angular structure at the centre.
    shade = 1.0 - (1.0 - led) * np.clip(r / radius, 0.0, 1.0)
    glow = v["glow_level"] * shade * (1.0 + 0.3 * (r / radius) ** 2) * inside
    return (ring + glow + 0.01).astype(np.float32)


def _ring(dist: np.ndarray, peak: np.ndarray, width: float) -> np.ndarray:
    """Asymmetric ring profile across signed distance ``dist`` (mm, < 0 inside): sharp inner
    flank (half the width), soft outer one."""
    w = np.where(dist < 0, 0.5 * width, width)
    return peak * np.exp(-((dist / w) ** 2))


def inner_ring(
    grid: Grid,
    finger: Finger,
    p_kpa: float,
    led: np.ndarray,
    patch: Patch | None,
    polar: tuple[np.ndarray, np.ndarray] | None,
) -> np.ndarray:
    """(H·ss, W·ss) float32: the inner (membrane) ring at ``p_kpa``; zeros at 0 kPa.

    Args:
        grid: the drawing grid.
        finger: the session.
        p_kpa: pressure, kPa.
        led: (H·ss, W·ss) :func:`led_profile` about the rig axis.
        patch: the contact patch, None below the onset.
        polar: ``patch.polar`` on the grid (distance, edge radius), None without a patch.
    """
    v = finger.values
    if p_kpa < FLAT_KPA:
        return np.zeros(grid.x.shape, np.float32)
    p0, radius, width = v["onset_kpa"], v["window_radius_mm"], v["inner_width_mm"]
    if patch is None or polar is None:  # inflating, free of the finger: a shrinking circle
        t = min(p_kpa / p0, 1.0)
        cx, cy = finger.centre_mm()
        dist = np.hypot(grid.x - cx, grid.y - cy)
        dist -= radius * (FREE_START + (FREE_END - FREE_START) * t)
        peak = v["inner_peak"] * (0.5 + 0.5 * t) * led
        return _ring(dist, peak, width * (1.8 - 0.6 * t)).astype(np.float32)
    above = p_kpa - p0
    gap = max((FREE_END * radius - patch.b) * math.exp(-above / CLOSE_IN_KPA), 0.0) + GAP_MM
    dist = polar[0] - (polar[1] + gap)
    peak = v["inner_peak"] * (0.8 + 0.2 * min(above / 5.0, 1.0)) * led
    return _ring(dist, peak, width * (1.0 + math.exp(-above / 3.0))).astype(np.float32)

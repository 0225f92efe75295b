"""Fingerprint ridge texture: a warped loop pattern with breaks, either polarity.

Own model (independent of the renderer's fingerprint): the ridge phase is the distance from a
core point, squeezed across the finger (a loop), plus a slow random warp of a few periods, so
ridges curve and their period varies locally; ridge width varies through a random duty bias, and
a sparse smooth field breaks ridges (minutiae-like ends and pores). Fixed to the finger: the
contact grows over the same texture frame after frame.
"""

from __future__ import annotations

import math

import numpy as np

from contactcal.synth.procedural.grid import Grid, smooth_field
from contactcal.synth.procedural.session import Finger

#: Scale of the slow warp of the ridge phase, mm; larger = straighter ridges.
WARP_CELL_MM = 2.5
#: Warp amplitude, ridge periods.
WARP_PERIODS = 1.2
#: Scale of the ridge breaks, mm.
BREAK_CELL_MM = 0.5
#: Break threshold on the unit-sd break field; higher = fewer breaks.
BREAK_LEVEL = 1.5


def ridge_texture(grid: Grid, finger: Finger) -> np.ndarray:
    """(H·ss, W·ss) float32 texture in ``[-1, 1]``: +1 on ridges when the polarity is +1.

    The texture is drawn from the finger's own ``texture_seed`` (same texture at every pressure).
    """
    rng = np.random.default_rng([finger.texture_seed, 1])
    v = finger.values
    period = v["ridge_period_mm"]
    cx, cy = finger.centre_mm()
    along = finger.contact_angle
    core_shift = rng.uniform(-2.0, 2.0)  # core point along the finger axis, mm
    qx = grid.x - (cx + core_shift * math.cos(along))
    qy = grid.y - (cy + core_shift * math.sin(along))
    u = qx * math.cos(along) + qy * math.sin(along)  # along the finger
    w = -qx * math.sin(along) + qy * math.cos(along)  # across it
    squeeze = rng.uniform(0.55, 0.85)  # < 1: loop elongated along the finger
    phase = np.hypot(u * squeeze, w) / period
    cell = WARP_CELL_MM / grid.mm_per_sample
    phase += WARP_PERIODS * smooth_field(rng, grid.x.shape, cell)
    phase += 0.15 * u / period * rng.uniform(-1.0, 1.0)  # slight arch/tilt component
    duty = rng.uniform(-0.3, 0.3)  # > 0: wide ridges, narrow valleys
    sharp = rng.uniform(1.5, 3.0)
    profile = np.tanh(sharp * (np.cos(2 * math.pi * phase) + duty)) / math.tanh(sharp)
    breaks = smooth_field(rng, grid.x.shape, BREAK_CELL_MM / grid.mm_per_sample) > BREAK_LEVEL
    profile = np.where(breaks, -0.6 * np.abs(profile), profile)
    return (finger.ridge_polarity * np.clip(profile, -1.0, 1.0)).astype(np.float32)

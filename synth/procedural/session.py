"""One session's (finger's) parameters, drawn from the configured ranges."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from contactcal.synth.procedural.config import GeneratorConfig, Ranges


@dataclass(frozen=True)
class Finger:
    """Everything fixed for one session (units as in :class:`Ranges`)."""

    hard: bool  # drawn from the hard ranges
    values: dict[str, float]  # one value per :class:`Ranges` field
    led_angle: float  # direction of the first LED sector, rad (the second is roughly opposite)
    led_spread: float  # angle between the two LEDs, rad (π = opposite)
    contact_angle: float  # long axis direction of the contact ellipse, rad
    offset_angle: float  # direction of the contact centre offset, rad
    lobe_phases: tuple[float, float]  # phases of the 3- and 4-fold edge waviness, rad
    ridge_polarity: int  # +1: ridges brighter than valleys; -1: darker
    texture_seed: int  # seed of the fingerprint texture and the coating particles

    def mm_per_px(self, width: int) -> float:
        """Pixel size at the contact plane for frames ``width`` px wide, mm/px."""
        return self.values["fov_width_mm"] / width

    def centre_mm(self) -> tuple[float, float]:
        """Contact centre ``(x, y)`` relative to the rig axis (image centre), mm."""
        r = self.values["offset_mm"]
        return r * math.cos(self.offset_angle), r * math.sin(self.offset_angle)


def draw_finger(rng: np.random.Generator, ranges: Ranges, hard: bool) -> Finger:
    """Draw one session from ``ranges`` (uniformly, field by field, in declaration order)."""
    values = {f.name: float(rng.uniform(*getattr(ranges, f.name))) for f in fields(ranges)}
    return Finger(
        hard=hard,
        values=values,
        led_angle=float(rng.uniform(0.0, 2 * math.pi)),
        led_spread=float(rng.uniform(0.75, 1.0) * math.pi),
        contact_angle=float(rng.uniform(-0.6, 0.6) + math.pi / 2),  # finger roughly along y
        offset_angle=float(rng.uniform(0.0, 2 * math.pi)),
        lobe_phases=(float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi))),
        ridge_polarity=1 if rng.random() < 0.5 else -1,
        texture_seed=int(rng.integers(0, 2**31 - 1)),
    )


def finger_params(config: GeneratorConfig, finger: int) -> Finger:
    """The deterministic session of finger ``finger``: Generator seeded by ``(seed, finger)``."""
    rng = np.random.default_rng([config.seed, finger])
    hard = bool(rng.random() < config.hard_fraction)
    return draw_finger(rng, config.hard if hard else config.normal, hard)

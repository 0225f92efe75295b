"""How steady the pressure must be for a video frame to be kept (``calibrate --video``)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class StepConfig:
    """How steady pressure must be for a frame to be kept."""

    # kPa, half-width of the band a step's samples stay in. A tenth of the usual 1 kPa spacing
    # of calibration steps (neighbouring steps never mix) and twice a regulator's typical
    # ±0.05 kPa sensor noise (a held step is not split); raise it for a noisier controller.
    tolerance_kpa: float = 0.1
    # s the pressure must have been steady before a frame is kept: the membrane's response to a
    # step (~0.1-0.3 s for the silicone membrane) has died out; longer keeps fewer frames.
    settle_s: float = 0.5

    def __post_init__(self) -> None:
        for option, value in (
            ("--tolerance-kpa", self.tolerance_kpa),
            ("--settle-s", self.settle_s),
        ):
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{option}: expected a number >= 0, got {value}")

"""Ranges of the procedural generator's session parameters, and what a run generates.

A session (one finger) draws every parameter uniformly from a :class:`Ranges`: the normal
ranges (:data:`NORMAL`) or, for a share of the sessions, the hard ones (:data:`HARD`: exposure
extremes, off-centre fingers, faint ridges, a dim LED, heavy noise, strong JPEG). Intensities are
linear, 1.0 = the sensor's white at exposure 1 (above 1 clips).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from contactcal.synth.layout import check_frame_size, check_sweep

Range = tuple[float, float]


@dataclass(frozen=True)
class Ranges:
    """Uniform ``(lo, hi)`` ranges of one session's parameters."""

    fov_width_mm: Range = (40.0, 46.0)  # field across the frame width, mm; sets mm/px
    window_radius_mm: Range = (11.0, 12.5)  # window (outer) ring radius; must fit the frame
    window_width_mm: Range = (0.3, 0.55)  # its Gaussian half-width; wider = blurrier ring
    window_peak: Range = (1.8, 3.0)  # its peak, × white: > 1 saturates (the brightest thing)
    led_depth: Range = (0.25, 0.6)  # two-LED sector modulation of both rings and the glow
    glow_level: Range = (0.08, 0.18)  # membrane coating glow inside the window
    inner_peak: Range = (0.35, 0.7)  # inner (membrane) ring peak; stays below the window ring
    inner_width_mm: Range = (0.2, 0.45)  # inner ring half-width at contact; sharpens with p
    onset_kpa: Range = (2.0, 4.0)  # contact onset; no contact at or below it
    area20_mm2: Range = (150.0, 230.0)  # contact area at 20 kPa (reference: ~190 mm²)
    area_exponent: Range = (0.28, 0.4)  # A ∝ (p − onset)^γ: ~100/140/190 mm² at 5/10/20 kPa
    aspect: Range = (1.2, 1.5)  # contact ellipse long/short axis
    offset_mm: Range = (0.0, 1.5)  # contact centre distance from the rig axis
    lobes: Range = (0.0, 0.04)  # 3- and 4-fold edge waviness, × radius; 0 = ellipse
    ridge_period_mm: Range = (0.35, 0.55)  # fingerprint ridge period (both polarities drawn)
    ridge_contrast: Range = (0.3, 0.6)  # ridge modulation, × the skin level
    skin_level: Range = (0.6, 1.6)  # skin in contact / glow level; < 1 darker, > 1 brighter
    halo_mm: Range = (0.15, 0.5)  # faint ridges just outside the contact (near contact)
    sparkle_per_mm2: Range = (0.1, 0.5)  # bright coating particles
    grain: Range = (0.04, 0.1)  # fine multiplicative coating grain, relative
    vignetting: Range = (0.1, 0.35)  # brightness lost at the frame corner, relative
    exposure: Range = (0.8, 1.25)  # gain on the linear image
    blur_px: Range = (0.3, 0.8)  # defocus Gaussian sigma at 400 px width, scaled with width
    read_noise: Range = (1.0, 2.5)  # Gaussian read noise, DN (of 255)
    shot_noise: Range = (0.15, 0.35)  # shot noise sd = k·sqrt(DN)
    jpeg_quality: Range = (75.0, 95.0)  # JPEG round trip quality (frames are saved as PNG)

    def __post_init__(self) -> None:
        for f in fields(self):
            lo, hi = getattr(self, f.name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ValueError(f"Ranges.{f.name}: expected finite lo <= hi, got ({lo}, {hi})")


#: Ranges of normal sessions.
NORMAL = Ranges()

#: Ranges of hard sessions: extremes the normal ranges avoid.
HARD = replace(
    NORMAL,
    onset_kpa=(1.5, 5.0),
    offset_mm=(1.5, 3.0),
    led_depth=(0.6, 0.95),
    ridge_contrast=(0.08, 0.25),
    halo_mm=(0.4, 1.0),
    lobes=(0.03, 0.07),
    sparkle_per_mm2=(0.5, 1.5),
    exposure=(0.45, 1.9),
    blur_px=(0.7, 1.4),
    read_noise=(2.5, 5.0),
    jpeg_quality=(50.0, 70.0),
)


@dataclass(frozen=True)
class GeneratorConfig:
    """What ``contactcal procedural`` generates (written to ``config.json``)."""

    fingers: int  # sessions in the set
    pressures_kpa: tuple[float, ...]  # pressure steps of every session, kPa
    seed: int  # dataset seed; finger f draws from numpy Generator([seed, f])
    width: int = 400  # frame width, px (the rig's is 2592: far too slow for a cross-check)
    height: int = 300  # frame height, px
    supersample: int = 2  # drawn at this × size then area-averaged; 1 is faster, aliases ridges
    hard_fraction: float = 0.25  # share of sessions drawn from HARD
    normal: Ranges = NORMAL  # ranges of normal sessions
    hard: Ranges = HARD  # ranges of hard sessions

    def __post_init__(self) -> None:
        check_sweep(self.fingers, self.pressures_kpa)
        if self.seed < 0:  # numpy seeds are >= 0
            raise ValueError(f"--seed must be >= 0, got {self.seed}")
        check_frame_size(self.width, self.height)
        if self.supersample < 1:
            raise ValueError(f"supersample must be >= 1, got {self.supersample}")
        if not 0.0 <= self.hard_fraction <= 1.0:
            raise ValueError(f"--hard-fraction must be in [0, 1], got {self.hard_fraction}")

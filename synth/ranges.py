"""The ranges of the domain randomisation, as data (``randomize.sample_session`` draws them).

Each table lists one :class:`Draw` per generator call, in draw order; ``nominal`` is the
paper's regime (docs/fidelity.md), ``hard`` the wider ranges (docs/synth.md). Reordering or
inserting a row changes every session of a seed: append new draws in a new table drawn last.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

LED_COUNT = 16  # LEDs feeding the light guide plate (sets the azimuthal non-uniformity's scale)


@dataclass(frozen=True)
class Draw:
    """One scalar (or ``size``-vector) random draw of a session.

    ``kind`` and the meaning of ``nominal`` / ``hard`` (the latter used when ``hard=True``;
    None = same as nominal): ``"uniform"`` (lo, hi); ``"normal"`` (mean, sd); ``"lognormal"``
    (0, sd) -> ``exp(N(0, sd))``; ``"loguniform"`` (lo, hi) -> ``exp(U(log lo, log hi))``;
    ``"seed"`` -> an int in [0, 2³¹) (no parameters); ``"loguniform_z"`` (lo, hi): loguniform
    mapped from one N(0, 1) draw (uses the generator as ``"lognormal"`` does, so switching
    between them moves no later draw). ``hard_kind``: another kind for ``hard``.
    """

    name: str
    kind: str
    nominal: tuple[float, float] = (0.0, 0.0)
    hard: tuple[float, float] | None = None
    size: int | None = None
    hard_kind: str | None = None

    def sample(self, rng: np.random.Generator, hard: bool) -> Any:
        """Draw the value (exactly one generator call)."""
        lo, hi = self.hard if hard and self.hard is not None else self.nominal
        kind = self.hard_kind if hard and self.hard_kind else self.kind
        if kind == "uniform":
            return rng.uniform(lo, hi, self.size)
        if kind == "normal":
            return rng.normal(lo, hi, self.size)
        if kind == "lognormal":
            return float(math.exp(rng.normal(lo, hi)))
        if kind == "loguniform":
            return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
        if kind == "loguniform_z":
            u = 0.5 * (1.0 + math.erf(rng.normal(0.0, 1.0) / math.sqrt(2.0)))
            return float(lo * (hi / lo) ** u)
        if kind == "seed":
            return int(rng.integers(2**31))
        raise ValueError(f"synth/randomize.py: unknown Draw kind {kind!r}")


def _uniform(name: str, lo: float, hi: float, hard: tuple[float, float] | None = None) -> Draw:
    return Draw(name, "uniform", (lo, hi), hard)


def _normal(name: str, mean: float, sd: float, hard_sd: float | None = None) -> Draw:
    return Draw(name, "normal", (mean, sd), None if hard_sd is None else (mean, hard_sd))


# The draws in generator order (changing the order changes every session of a seed). Ranges
# follow ``shared/reference``: pad width 13-18 mm, aspect 1.2-1.5, onset 2-4 kPa, finger
# stiffness of the three measured users and around them.
BODY_DRAWS = (  # finger, membrane, rig, LED profile
    _uniform("width_mm", 13.0, 18.0),
    *(
        d
        for n in (2, 3, 4)  # shape harmonics n = 2, 3, 4: (eps_n, phase_n)
        for d in (_uniform(f"eps_{n}", 0.0, 0.025), _uniform(f"phase_{n}", 0.0, 2 * math.pi))
    ),
    _uniform("length_per_width", 1.35, 1.6),
    _uniform("radius_mm", 7.0, 10.0),
    _uniform("e0_mpa", 0.011, 0.022),
    _uniform("beta_per_n", 0.4, 1.0),
    _uniform("aspect", 1.2, 1.5),
    # Nominal: the display is worn centred on the pulp (the paper's patches fit its 55 % ROI);
    # hard: off-centre up to the ROI's edge.
    _normal("offset_x_mm", 0.0, 0.4, hard_sd=2.5),
    _normal("offset_y_mm", 0.0, 0.4, hard_sd=2.5),
    _normal("yaw_rad", math.pi / 2, 0.35),  # finger enters along the image's y axis
    _normal("tilt_rad", 0.0, 0.06, hard_sd=0.15),  # pitch; shifts the patch by R sin(tilt)
    _uniform("clamp_radius_mm", 11.5, 13.5),
    # Several mm: the inner ring (LGP seen in the concave membrane) only comes back and shrinks
    # for inflations of ~4-7 mm (docs/fidelity.md), and the paper shows it shrinking at 1-2 kPa,
    # before contact. A 70 µm silicone membrane's low tension makes such gaps consistent with
    # onset; with the Hencky law (mechanics.py) 1 kPa already inflates ~70 % of the gap.
    _uniform("gap_mm", 5.0, 7.0, hard=(3.5, 7.5)),
    _uniform("onset_kpa", 2.0, 4.0),
    _uniform("onset_ramp_kpa", 0.5, 1.0),
    # Window-to-membrane depth and LGP depth set the rings' sizes (docs/fidelity.md): the
    # paper's 55 % ROI holds its patches only if the window ring looks large next to the
    # membrane (deep chamber, LGP near the window); a deeper LGP shrinks the inner ring sooner.
    _uniform("chamber_depth_mm", 7.0, 9.0, hard=(5.0, 10.0)),
    _uniform("lgp_gap_mm", 4.0, 6.0, hard=(2.0, 12.0)),
    _uniform("fov_y_deg", 28.0, 30.5),
    _normal("camera_offset_x_mm", 0.0, 0.3),
    _normal("camera_offset_y_mm", 0.0, 0.3),
    Draw("led_deviation", "normal", (0.0, 0.08), (0.0, 0.25), size=LED_COUNT),
)
# (hard only: a dim LED sector is drawn here, see _dim_sector)
EXPOSURE_DRAWS = (
    # nominal: a set-up camera; hard: ±2 stops, clipped window rings included
    Draw("exposure_gain", "lognormal", (0.0, 0.1), (0.25, 4.0), hard_kind="loguniform_z"),
    _uniform("defocus_sigma_px", 0.0, 1.0, hard=(0.0, 2.2)),
    Draw("full_well", "loguniform", (300.0, 5000.0)),
    _uniform("read_noise", 0.002, 0.012),
    _uniform("gamma", 1.8, 2.4),
)
# (the JPEG quality is drawn here: lossless or 50-98, half and half)
LOOK_DRAWS = (  # camera pose, skin, coating, seeds, LGP brightness
    _normal("camera_tilt_x_deg", 0.0, 0.6),
    _normal("camera_tilt_y_deg", 0.0, 0.6),
    _normal("shift_x_px", 0.0, 1.5),
    _normal("shift_y_px", 0.0, 1.5),
    Draw("skin_gain", "uniform", (0.6, 1.3), size=3),
    # Sparse mica flakes on clear silicone: effective specular reflectance of the same order as
    # the window's (2R/(1+R) ≈ 8 %), so the window ring stays the brightest structure (paper).
    _uniform("coating_reflectance", 0.03, 0.06, hard=(0.02, 0.3)),
    _uniform("particle_density_per_mm2", 250.0, 1200.0),
    # Flake tilts blur the inner ring into a halo; the paper's ring hugs the contact with a sharp
    # inner edge, so nominal flakes lie flat (hard: the old, blurrier range).
    _uniform("particle_tilt_deg", 0.5, 1.5, hard=(1.0, 4.0)),
    _uniform("sparkle_fraction", 0.02, 0.08, hard=(0.03, 0.2)),
    _uniform("sparkle_tilt_deg", 10.0, 30.0),
    _uniform("roughness_alpha", 0.02, 0.06, hard=(0.03, 0.15)),  # GGX: wide = dim halo
    _uniform("blue_per_red_reflectance", 0.9, 1.05),
    _uniform("coating_diffuse", 0.0, 0.03, hard=(0.0, 0.1)),  # binder glow; > ~4 % lifts the
    #   dark membrane above half the ring's brightness and the routine's blob swells (fidelity.md)
    Draw("fingerprint_seed", "seed"),
    _uniform("ridge_contrast", 0.35, 1.0, hard=(0.05, 1.0)),  # hard: barely visible to crisp
    Draw("particle_seed", "seed"),
    _uniform("lgp_radiance", 0.9, 1.2, hard=(0.5, 1.6)),
    # Slack membrane at 0 kPa (mechanics.py): wrinkles of tens of µm tilt the surface by a few
    # degrees, enough to scatter the flat membrane's LGP reflex (docs/fidelity.md).
    _uniform("slack_mm", 0.02, 0.06, hard=(0.0, 0.08)),
    Draw("slack_seed", "seed"),
)
SKIN_DRAWS = (  # synth/skin.py; nominal skin is clean, hard skin far beyond (docs/synth.md)
    _uniform("dryness", 0.0, 0.1, hard=(0.0, 0.6)),
    _uniform("wetness", 0.0, 0.15, hard=(0.0, 0.8)),
    _uniform("inverted", 0.0, 0.0, hard=(0.0, 1.0)),  # < 0.5 → ridges darker (hard only)
    Draw("scar_count", "uniform", (0.0, 1.3), (0.0, 3.99)),  # floor → 0-1 (hard: 0-3) scars
    Draw("skin_seed", "seed"),
)
# Appearance v2 (synth/look.py, docs/synth.md), drawn last so the draws above keep their values.
CAMERA2_DRAWS = (
    _uniform("lgp_inner_radius_mm", 11.5, 11.5, hard=(10.5, 12.5)),  # hard: ring width
    _uniform("tone_strength", 0.0, 0.1, hard=(0.0, 0.5)),  # S-curve blend
    Draw("wb_gains", "uniform", (0.97, 1.03), (0.75, 1.25), size=3),  # white balance / cast
    _uniform("vignetting", 0.0, 0.1, hard=(0.0, 0.4)),
    Draw("vignette_centre", "normal", (0.0, 0.03), size=2),  # × image width
    _uniform("motion_blur_px", 0.0, 0.0, hard=(0.0, 3.0)),
    _uniform("motion_blur_deg", 0.0, 180.0),
    Draw("dust_count", "uniform", (0.0, 3.99), (0.0, 15.99)),  # floor → 0-3 (hard: 0-15)
    _uniform("stray_draw", 1.0, 1.0, hard=(0.0, 1.0)),  # < STRAY_PROBABILITY → glare
    _uniform("stray_amplitude", 0.0, 0.0, hard=(0.0, 0.15)),  # fraction of white
    Draw("look_seed", "seed"),
)
# Smooth coating (hard sessions, opt-in: ``DatasetConfig.smooth_fraction``; drawn after every
# other table): flat flakes and a near-mirror GGX lobe turn the inner ring before contact into a
# thin sharp ring (the paper's "internal luminous ring") instead of a halo (docs/synth.md).
SMOOTH_DRAWS = (
    _uniform("smooth_draw", 1.0, 1.0, hard=(0.0, 1.0)),  # < smooth_fraction → smooth coating
    _uniform("smooth_tilt_deg", 0.1, 0.5),  # rms flake tilt (nominal 0.5-1.5°); less = sharper
    Draw("smooth_alpha", "loguniform", (0.005, 0.02)),  # GGX α (nominal 0.02-0.06)
)
# Centre speck (opt-in: ``DatasetConfig.speck_fraction``; drawn after every other table): one
# bright dust speck on the window near the image centre, as ``add_dust``'s bright ones (10-40 %
# of white, radius 1-4 px at 400 wide), placed uniformly over a disc of 0.12 × the image height
# (~0.3 window-ring radii: where the first contact appears), in normal and hard sessions alike.
SPECK_DRAWS = (
    _uniform("speck_draw", 0.0, 1.0),  # < speck_fraction → a centre speck
    _uniform("speck_strength", 0.1, 0.4),
    _uniform("speck_radius_px", 1.0, 4.0),
    _uniform("speck_place_r", 0.0, 1.0),  # → 0.12 · √r × the image height from the centre
    _uniform("speck_place_deg", 0.0, 360.0),
)
SPECK_DISC_HEIGHTS = 0.12
# Membrane departure (opt-in: ``DatasetConfig.departure_fraction``; drawn after the speck, so every
# earlier draw keeps its value): the slope at which the free membrane leaves the contact edge
# (``MembraneParams.departure_slope``). 0 puts the inner ring ~0.6 mm outside the edge (our v2
# optics); ~0.3 closes it on the edge, as the rig paper sees it ("the growing fingerprint region
# was delimited by an inner ring"); ~0.5 leaves no ring near the edge at all (measured on
# validation sessions re-rendered, docs/synth.md "Membrane departure").
DEPARTURE_DRAWS = (
    _uniform("departure_draw", 0.0, 1.0),  # < departure_fraction → the slope below, else 0
    _uniform("departure_slope", 0.0, 0.5),
)
STRAY_PROBABILITY = 0.3  # hard only: share of sessions with a stray reflection
DIM_SECTOR_PROBABILITY = 0.3  # hard only: share of sessions with a dim LED sector
JPEG_PROBABILITY = 0.5  # share of sessions saved as JPEG (else lossless)

"""Domain randomisation: every random choice of a synthetic session, drawn from one generator.

A *session* is one finger on the rig, stepped through the pressures: its finger, membrane,
fingerprint, coating, light and camera are drawn once (``sample_session``); each frame then
adds a small per-frame jitter of exposure and noise (``frame_camera``). The ``hard`` flag raises
the odds of off-centre fingers, low/high exposure, faint ridges, defocus and a weak LED sector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from contactcal.synth.camera import CameraEffects
from contactcal.synth.coating import MembraneOptics
from contactcal.synth.mechanics import FingerParams, MembraneParams, tension_for_onset
from contactcal.synth.rig import RigGeometry

LED_COUNT = 16  # LEDs feeding the light guide plate (sets the azimuthal non-uniformity's scale)
BASE_EXPOSURE = 2.0  # × render radiance: puts the window ring near 200-250 grey, like the rig's
#   photographs (the published routine finds the ring at threshold 150)


@dataclass(frozen=True)
class SessionParams:
    """All sampled parameters of one session (one finger, one seed)."""

    finger: FingerParams
    membrane: MembraneParams
    rig: RigGeometry  # rig build tolerances: chamber depth, LGP depth, field of view, camera offset
    onset_kpa: float  # kPa, the onset the membrane parameters were solved for
    fingerprint_seed: int  # seed of the ridge texture (one finger = one texture)
    ridge_contrast: float  # 0-1, how strongly ridges couple to the membrane (faint ↔ crisp)
    particle_seed: int  # seed of the mica flake normal map
    optics: MembraneOptics  # coating (flake density, tilt, sparkle, roughness) and skin colour
    lgp_radiance: float  # emitted radiance of the light guide plate (relative)
    lgp_profile: tuple[float, ...]  # (LED_COUNT,) relative brightness around the ring
    camera: CameraEffects  # session's base camera (exposure, blur, noise, JPEG, tilt)
    hard: bool  # drawn from the hard-case distribution


def _lognormal(rng: np.random.Generator, sd: float) -> float:
    return float(math.exp(rng.normal(0.0, sd)))


def sample_session(rng: np.random.Generator, hard: bool = False) -> SessionParams:
    """Draw one session's parameters.

    Args:
        rng: the session's generator (e.g. ``default_rng([seed, finger_index])``).
        hard: draw from the hard-case distribution.

    Returns:
        The session parameters; ranges follow ``shared/reference`` (pad width 13-18 mm, aspect
        1.2-1.5, onset 2-4 kPa, finger stiffness of the three measured users and around them).
    """
    width = rng.uniform(13.0, 18.0)
    offset_sd = 2.5 if hard else 1.0
    harmonics = tuple(
        (float(rng.uniform(0.0, 0.025)), float(rng.uniform(0, 2 * math.pi))) for _ in range(3)
    )
    finger = FingerParams(
        width_mm=width,
        length_mm=width * rng.uniform(1.35, 1.6),
        radius_mm=rng.uniform(7.0, 10.0),
        e0_mpa=rng.uniform(0.011, 0.022),
        beta_per_n=rng.uniform(0.4, 1.0),
        aspect=rng.uniform(1.2, 1.5),
        offset_mm=(float(rng.normal(0, offset_sd)), float(rng.normal(0, offset_sd))),
        yaw_rad=float(rng.normal(math.pi / 2, 0.35)),  # finger enters along the image's y axis
        tilt_rad=float(rng.normal(0.0, 0.15)),
        harmonics=harmonics,
    )
    a = rng.uniform(11.5, 13.5)
    # Several mm: the inner ring (LGP seen in the concave membrane) only comes back and shrinks
    # for inflations of ~4.5-7 mm (docs/renderer.md), and the paper shows it shrinking before
    # contact. A 70 µm silicone membrane's low tension makes such gaps consistent with onset.
    gap = rng.uniform(3.5, 6.0)
    onset = rng.uniform(2.0, 4.0)
    membrane = MembraneParams(
        clamp_radius_mm=a,
        tension_n_per_mm=tension_for_onset(onset, gap, a),
        gap_mm=gap,
        onset_ramp_kpa=rng.uniform(0.5, 1.0),
    )
    rig = RigGeometry(
        chamber_depth_mm=float(rng.uniform(2.5, 4.0)),
        clamp_radius_mm=float(a),
        lgp_gap_mm=float(rng.uniform(7.0, 12.0)),
        fov_y_deg=float(rng.uniform(28.0, 30.5)),
        camera_offset_mm=(float(rng.normal(0, 0.3)), float(rng.normal(0, 0.3))),
    )
    profile = 1.0 + rng.normal(0.0, 0.25 if hard else 0.08, LED_COUNT)
    if hard and rng.random() < 0.3:  # a dim sector: "ring partly missing"
        start = rng.integers(LED_COUNT)
        for k in range(int(rng.integers(2, 5))):
            profile[(start + k) % LED_COUNT] *= 0.15
    exposure_sd = 0.6 if hard else 0.25
    camera = CameraEffects(
        exposure=BASE_EXPOSURE * _lognormal(rng, exposure_sd),
        defocus_sigma_px=float(rng.uniform(0.0, 2.2 if hard else 1.0)),
        full_well=float(math.exp(rng.uniform(math.log(300), math.log(5000)))),
        read_noise=float(rng.uniform(0.002, 0.012)),
        gamma=float(rng.uniform(1.8, 2.4)),
        jpeg_quality=0 if rng.random() < 0.5 else int(rng.integers(60, 96)),
        tilt_deg=(float(rng.normal(0, 0.6)), float(rng.normal(0, 0.6))),
        shift_px=(float(rng.normal(0, 1.5)), float(rng.normal(0, 1.5))),
    )
    skin = np.clip(np.array([0.62, 0.42, 0.36]) * rng.uniform(0.6, 1.3, 3) ** 0.3, 0.0, 1.0)
    refl = float(rng.uniform(0.35, 0.75))
    optics = MembraneOptics(
        particle_density_per_mm2=float(rng.uniform(250.0, 1200.0)),
        particle_tilt_deg=float(rng.uniform(1.0, 4.0)),
        sparkle_fraction=float(rng.uniform(0.03, 0.2)),
        sparkle_tilt_deg=float(rng.uniform(10.0, 30.0)),
        roughness_alpha=float(rng.uniform(0.03, 0.12)),
        coating_reflectance=(refl, refl, refl * float(rng.uniform(0.9, 1.05))),
        coating_diffuse=float(rng.uniform(0.0, 0.08)),
        skin_rgb=(float(skin[0]), float(skin[1]), float(skin[2])),
    )
    return SessionParams(
        finger=finger,
        membrane=membrane,
        rig=rig,
        onset_kpa=float(onset),
        fingerprint_seed=int(rng.integers(2**31)),
        ridge_contrast=float(rng.uniform(0.12, 0.4) if hard else rng.uniform(0.35, 1.0)),
        particle_seed=int(rng.integers(2**31)),
        optics=optics,
        lgp_radiance=float(rng.uniform(0.7, 1.4)),
        lgp_profile=tuple(float(v) for v in np.clip(profile, 0.05, None)),
        camera=camera,
        hard=hard,
    )


def frame_camera(session: SessionParams, rng: np.random.Generator) -> CameraEffects:
    """The session camera with a small per-frame exposure jitter (auto-exposure, LED flicker)."""
    return replace(session.camera, exposure=session.camera.exposure * _lognormal(rng, 0.04))

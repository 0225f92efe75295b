"""Domain randomisation: every random choice of a synthetic session, drawn from one generator.

A *session* is one finger on the rig, stepped through the pressures: its finger, membrane,
fingerprint, coating, light and camera are drawn once (``sample_session``); each frame then
adds a small per-frame jitter of exposure and noise (``frame_camera``). The ``hard`` flag raises
the odds of off-centre fingers, low/high exposure, faint ridges, defocus and a weak LED sector,
and widens the v2 look (``CAMERA2_DRAWS``: colour cast, tone curve, vignetting, dust, glare).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from contactcal.synth.camera import CameraEffects
from contactcal.synth.coating import MembraneOptics
from contactcal.synth.look import LookEffects
from contactcal.synth.mechanics import tension_for_onset
from contactcal.synth.mechanics_params import FingerParams, MembraneParams
from contactcal.synth.ranges import (
    BODY_DRAWS,
    CAMERA2_DRAWS,
    DEPARTURE_DRAWS,
    DIM_SECTOR_PROBABILITY,
    EXPOSURE_DRAWS,
    JPEG_PROBABILITY,
    LED_COUNT,
    LOOK_DRAWS,
    SKIN_DRAWS,
    SMOOTH_DRAWS,
    SPECK_DISC_HEIGHTS,
    SPECK_DRAWS,
    STRAY_PROBABILITY,
    Draw,
)
from contactcal.synth.rig import RigGeometry
from contactcal.synth.skin import SkinCondition

BASE_EXPOSURE = 11.0  # × render radiance: puts the window ring near 230 grey and its outer fringe
#   (front-face reflex alone, half as bright) near 180, so the published routine's threshold of
#   150 keeps the whole ring, as on the rig's photographs (docs/fidelity.md)


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
    skin: SkinCondition  # ridge polarity, dry/wet skin, scars
    hard: bool  # drawn from the hard-case distribution


def _draw(rng: np.random.Generator, table: tuple[Draw, ...], hard: bool) -> dict[str, Any]:
    return {d.name: d.sample(rng, hard) for d in table}


def _dim_sector(rng: np.random.Generator, profile: np.ndarray) -> None:
    """Dim 2-4 consecutive LEDs to 15 % in place ("ring partly missing")."""
    start = rng.integers(LED_COUNT)
    for k in range(int(rng.integers(2, 5))):
        profile[(start + k) % LED_COUNT] *= 0.15


def _finger(v: dict[str, Any]) -> FingerParams:
    return FingerParams(
        width_mm=v["width_mm"],
        length_mm=v["width_mm"] * v["length_per_width"],
        radius_mm=v["radius_mm"],
        e0_mpa=v["e0_mpa"],
        beta_per_n=v["beta_per_n"],
        aspect=v["aspect"],
        offset_mm=(float(v["offset_x_mm"]), float(v["offset_y_mm"])),
        yaw_rad=float(v["yaw_rad"]),
        tilt_rad=float(v["tilt_rad"]),
        harmonics=tuple((float(v[f"eps_{n}"]), float(v[f"phase_{n}"])) for n in (2, 3, 4)),
    )


def _membrane_and_rig(
    v: dict[str, Any], departure_fraction: float
) -> tuple[MembraneParams, RigGeometry]:
    a, gap = v["clamp_radius_mm"], v["gap_mm"]
    departs = v["departure_draw"] < departure_fraction
    membrane = MembraneParams(
        clamp_radius_mm=a,
        tension_n_per_mm=tension_for_onset(v["onset_kpa"], gap, a),
        gap_mm=gap,
        onset_ramp_kpa=v["onset_ramp_kpa"],
        slack_mm=float(v["slack_mm"]),
        slack_seed=int(v["slack_seed"]),
        departure_slope=float(v["departure_slope"]) if departs else 0.0,
    )
    rig = RigGeometry(
        chamber_depth_mm=float(v["chamber_depth_mm"]),
        clamp_radius_mm=float(a),
        lgp_gap_mm=float(v["lgp_gap_mm"]),
        fov_y_deg=float(v["fov_y_deg"]),
        camera_offset_mm=(float(v["camera_offset_x_mm"]), float(v["camera_offset_y_mm"])),
        lgp_inner_radius_mm=float(v["lgp_inner_radius_mm"]),
    )
    return membrane, rig


def _centre_speck(v: dict[str, Any], speck_fraction: float) -> tuple[float, float, float, float]:
    """``LookEffects.centre_speck`` from the ``SPECK_DRAWS`` (none unless drawn)."""
    if not v["speck_draw"] < speck_fraction:
        return (0.0, 0.0, 0.0, 0.0)
    r = SPECK_DISC_HEIGHTS * math.sqrt(float(v["speck_place_r"]))
    a = math.radians(float(v["speck_place_deg"]))
    strength, radius = float(v["speck_strength"]), float(v["speck_radius_px"])
    return (strength, radius, r * math.cos(a), r * math.sin(a))


def _camera(v: dict[str, Any], jpeg_quality: int, speck_fraction: float) -> CameraEffects:
    return CameraEffects(
        exposure=BASE_EXPOSURE * v["exposure_gain"],
        defocus_sigma_px=float(v["defocus_sigma_px"]),
        full_well=v["full_well"],
        read_noise=float(v["read_noise"]),
        gamma=float(v["gamma"]),
        jpeg_quality=jpeg_quality,
        tilt_deg=(float(v["camera_tilt_x_deg"]), float(v["camera_tilt_y_deg"])),
        shift_px=(float(v["shift_x_px"]), float(v["shift_y_px"])),
        look=LookEffects(
            vignetting=float(v["vignetting"]),
            vignette_centre=tuple(float(c) for c in np.clip(v["vignette_centre"], -0.5, 0.5)),
            wb_gains=tuple(float(g) for g in v["wb_gains"]),
            tone_strength=float(v["tone_strength"]),
            motion_blur_px=float(v["motion_blur_px"]),
            motion_blur_deg=float(v["motion_blur_deg"]),
            dust_count=int(v["dust_count"]),
            stray_amplitude=float(v["stray_amplitude"]) * (v["stray_draw"] < STRAY_PROBABILITY),
            centre_speck=_centre_speck(v, speck_fraction),
            seed=int(v["look_seed"]),
        ),
    )


def _optics(v: dict[str, Any], smooth_fraction: float) -> MembraneOptics:
    skin = np.clip(np.array([0.62, 0.42, 0.36]) * v["skin_gain"] ** 0.3, 0.0, 1.0)
    refl = float(v["coating_reflectance"])
    smooth = v["smooth_draw"] < smooth_fraction
    return MembraneOptics(
        particle_density_per_mm2=float(v["particle_density_per_mm2"]),
        particle_tilt_deg=float(v["smooth_tilt_deg" if smooth else "particle_tilt_deg"]),
        sparkle_fraction=float(v["sparkle_fraction"]),
        sparkle_tilt_deg=float(v["sparkle_tilt_deg"]),
        roughness_alpha=float(v["smooth_alpha" if smooth else "roughness_alpha"]),
        coating_reflectance=(refl, refl, refl * float(v["blue_per_red_reflectance"])),
        coating_diffuse=float(v["coating_diffuse"]),
        skin_rgb=(float(skin[0]), float(skin[1]), float(skin[2])),
    )


def sample_session(
    rng: np.random.Generator,
    hard: bool = False,
    smooth_fraction: float = 0.0,
    speck_fraction: float = 0.0,
    departure_fraction: float = 0.0,
) -> SessionParams:
    """Draw one session's parameters (``ranges``' tables, in order, plus conditional draws).

    Args:
        rng: the session's generator (e.g. ``default_rng([seed, finger_index])``).
        hard: draw from the hard-case distribution.
        smooth_fraction: share of hard sessions with a smooth coating (``SMOOTH_DRAWS``: a thin
            sharp inner ring before contact); 0 = none, as in the shipped model's data.
        speck_fraction: share of all sessions with a bright dust speck near the image centre
            (``SPECK_DRAWS``, ``LookEffects.centre_speck``); 0 = none, as in the shipped
            model's data.
        departure_fraction: share of all sessions whose membrane leaves the contact edge at a
            drawn slope (``DEPARTURE_DRAWS``, ``MembraneParams.departure_slope``); 0 = none
            (the clamped annulus's zero slope), as in the shipped model's data.

    Returns:
        The session parameters.
    """
    v = _draw(rng, BODY_DRAWS, hard)
    profile = 1.0 + v["led_deviation"]
    if hard and rng.random() < DIM_SECTOR_PROBABILITY:
        _dim_sector(rng, profile)
    v |= _draw(rng, EXPOSURE_DRAWS, hard)
    jpeg_quality = 0 if rng.random() < JPEG_PROBABILITY else int(rng.integers(50, 99))
    v |= _draw(rng, LOOK_DRAWS, hard)
    v |= _draw(rng, SKIN_DRAWS, hard)
    v |= _draw(rng, CAMERA2_DRAWS, hard)  # v2 appearance, last: earlier draws keep their values
    v |= _draw(rng, SMOOTH_DRAWS, hard)  # smooth coating, after v2: earlier draws keep theirs
    v |= _draw(rng, SPECK_DRAWS, hard)  # centre speck: every earlier draw keeps its value
    v |= _draw(rng, DEPARTURE_DRAWS, hard)  # membrane departure, last: the same
    membrane, rig = _membrane_and_rig(v, departure_fraction)
    return SessionParams(
        finger=_finger(v),
        membrane=membrane,
        rig=rig,
        onset_kpa=float(v["onset_kpa"]),
        fingerprint_seed=v["fingerprint_seed"],
        ridge_contrast=float(v["ridge_contrast"]),
        particle_seed=v["particle_seed"],
        optics=_optics(v, smooth_fraction),
        lgp_radiance=float(v["lgp_radiance"]),
        lgp_profile=tuple(float(x) for x in np.clip(profile, 0.05, None)),
        camera=_camera(v, jpeg_quality, speck_fraction),
        skin=SkinCondition(
            polarity=-1 if hard and v["inverted"] < 0.5 else 1,
            dryness=float(v["dryness"]),
            wetness=float(v["wetness"]),
            scars=int(v["scar_count"]),
            seed=int(v["skin_seed"]),
        ),
        hard=hard,
    )


def frame_camera(session: SessionParams, rng: np.random.Generator) -> CameraEffects:
    """The session camera with a small per-frame exposure jitter (auto-exposure, LED flicker)."""
    jitter = float(math.exp(rng.normal(0.0, 0.04)))
    return replace(session.camera, exposure=session.camera.exposure * jitter)

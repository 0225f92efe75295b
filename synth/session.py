"""One synthetic session: a finger stepped through pressures, rendered with exact masks.

Per frame: contact mechanics → membrane surface and contact region; fingerprint ridges (in the
finger's frame, so they move with it) → contact-weight texture; Mitsuba render of the rig; the
exact mask from the same camera's pixel-centre rays hitting the membrane; then the camera model
(exposure, tilt, blur, noise, JPEG), applied to frame and mask alike.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from contactcal.synth.camera import apply_camera
from contactcal.synth.fingerprint import Fingerprint, make_fingerprint
from contactcal.synth.layout import check_frame_size
from contactcal.synth.mechanics import solve_contact
from contactcal.synth.membrane_shape import ContactState
from contactcal.synth.randomize import SessionParams, frame_camera
from contactcal.synth.rig import RigGeometry, focal_px, mm_per_px_at
from contactcal.synth.skin import apply_skin

if TYPE_CHECKING:
    from contactcal.synth.render import RigRenderer


@dataclass(frozen=True)
class RenderConfig:
    """Image size and render quality of a dataset."""

    width: int = 320  # px; 4:3. Ridges (0.4-0.5 mm) span ~4.5 px at 320 — near the limit
    height: int = 240  # px
    spp: int = 8  # samples per pixel; time ∝ spp; at 8 the network's areas differ from 64 spp
    #   as little as at 16 (docs/synth.md, "Samples per pixel"); the camera adds noise anyway
    n_rings: int = 96  # membrane mesh rings; fewer facets the inner ring
    n_sectors: int = 256  # membrane mesh sectors
    weight_size: int = 1024  # contact texture texels over the membrane (~40/mm: ~18 per ridge)
    normal_map_size: int = 1024  # mica flake normal map texels
    variant: str = "auto"  # Mitsuba variant: auto (llvm when a good LLVM exists), scalar_rgb

    def __post_init__(self) -> None:
        check_frame_size(self.width, self.height)
        if self.spp < 1:
            raise ValueError(f"spp must be >= 1, got {self.spp}")


@dataclass(frozen=True)
class FrameOutput:
    """One rendered frame and its truth."""

    pressure_kpa: float
    frame: np.ndarray  # (H, W, 3) uint8 RGB
    mask: np.ndarray  # (H, W) bool, exact contact region (pixel centres)
    state: ContactState  # mechanics truth (area_mm2 on the membrane, onset, ...)
    mm_per_px: float  # pixel size at the contact plateau's height (image centre), mm


def contact_weight(
    state: ContactState, fp: Fingerprint, session: SessionParams, size: int
) -> np.ndarray:
    """``(size, size) float32`` texture in membrane uv: ridge coupling inside the contact region.

    Texel ``(i, j)`` is centred at ``x = -a + (j + 0.5)·2a/size``, ``y = -a + (i + 0.5)·2a/size``
    (``a`` = clamp radius). The ridge pattern is expressed in the finger's frame (origin at the
    finger's lowest point, ``v`` along the finger), so it moves with the finger, not the patch.
    """
    a = state.clamp_radius_mm
    c = -a + (np.arange(size) + 0.5) * (2 * a / size)
    x, y = np.meshgrid(c, c)
    if not state.in_contact:
        return np.zeros((size, size), np.float32)
    f = session.finger
    dx, dy = x - f.offset_mm[0], y - f.offset_mm[1]
    cy, sy = math.cos(f.yaw_rad), math.sin(f.yaw_rad)
    along, across = dx * cy + dy * sy, -dx * sy + dy * cy
    ridges = fp.sample(across, along)
    texel = 2 * a / size
    centre = ((f.offset_mm[0] + a) / texel - 0.5, (f.offset_mm[1] + a) / texel - 0.5)
    ridges = apply_skin(ridges, texel, centre, session.skin)
    w = session.ridge_contrast * ridges * state.inside(x, y)
    return w.astype(np.float32)


def _open_renderer(rig: RigGeometry, config: RenderConfig) -> RigRenderer:
    """Load the rig's scene once for a session (Mitsuba is imported only here)."""
    from contactcal.synth.render import RigRenderer

    return RigRenderer(
        rig,
        config.width,
        config.height,
        spp=config.spp,
        n_rings=config.n_rings,
        n_sectors=config.n_sectors,
        weight_size=config.weight_size,
        normal_map_size=config.normal_map_size,
        variant=config.variant,
    )


def render_session(
    session: SessionParams,
    pressures: Sequence[float],
    config: RenderConfig,
    seed: Sequence[int],
    rig: RigGeometry | None = None,
    skip: Sequence[bool] | None = None,
) -> Iterator[FrameOutput | None]:
    """Render a session frame by frame (one scene load, in-place updates).

    Args:
        session: sampled parameters (:func:`contactcal.synth.randomize.sample_session`).
        pressures: kPa, in rendering order.
        config: size and quality.
        seed: entropy of this session (e.g. ``(dataset_seed, finger)``); frame ``k`` uses
            ``(*seed, k)`` so any frame can be re-rendered alone (resume) bit-identically.
        rig: geometry override (None → the session's sampled rig).
        skip: per frame, True → yield None without rendering (already on disk).

    Yields:
        :class:`FrameOutput` per pressure (None for skipped frames).
    """
    rig = rig or session.rig
    if rig.clamp_radius_mm != session.membrane.clamp_radius_mm:
        rig = replace(rig, clamp_radius_mm=session.membrane.clamp_radius_mm)
    fp = make_fingerprint(np.random.default_rng(session.fingerprint_seed))
    skip = skip or [False] * len(pressures)
    focal = focal_px(rig, config.height)
    with _open_renderer(rig, config) as renderer:
        for k, (p, done) in enumerate(zip(pressures, skip, strict=True)):
            if done:
                yield None
                continue
            rng = np.random.default_rng([*seed, k])
            state = solve_contact(float(p), session.finger, session.membrane)
            weight = contact_weight(state, fp, session, config.weight_size)
            linear = renderer.render(
                state.membrane_z,
                weight,
                session.lgp_radiance,
                np.asarray(session.lgp_profile),
                particle_seed=session.particle_seed,
                optics=session.optics,
                seed=int(rng.integers(2**31)),
            )
            hits = renderer.hit_points(state.membrane_z)
            ok = np.isfinite(hits[..., 0])
            mask = np.zeros(ok.shape, bool)
            mask[ok] = state.inside(hits[..., 0][ok], hits[..., 1][ok])
            frame, mask = apply_camera(linear, mask, frame_camera(session, rng), rng, focal)
            scale = mm_per_px_at(rig, state.plateau_z_mm, config.width, config.height)
            yield FrameOutput(float(p), frame, mask, state, scale)

"""One procedural frame: rings, glow, the contact patch with its ridges, then the camera."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from contactcal.synth.procedural.camera import Optics, expose, session_optics
from contactcal.synth.procedural.config import GeneratorConfig
from contactcal.synth.procedural.contact import contact_patch
from contactcal.synth.procedural.grid import Grid, make_grid
from contactcal.synth.procedural.ridges import ridge_texture
from contactcal.synth.procedural.rings import inner_ring, led_profile, window_and_glow
from contactcal.synth.procedural.session import Finger

#: Edge softness of the contact patch in the image (logistic scale), mm.
EDGE_MM = 0.04
#: Ridge contrast at the onset, × the full contrast reached 5 kPa above it.
ONSET_CONTRAST = 0.6


@dataclass(frozen=True)
class Frame:
    """A frame and its truth."""

    pressure_kpa: float  # kPa
    rgb: np.ndarray  # (H, W, 3) uint8
    mask: np.ndarray  # (H, W) bool, pixel centres inside the contact
    area_mm2: float  # true contact area, mm² (0 without contact)


@dataclass(frozen=True)
class _Layers:
    """A session's pressure-independent layers on the supersampled grid."""

    grid: Grid
    pixels: Grid  # the saved frame's pixel centres (for the mask)
    background: np.ndarray  # window ring, glow, walls
    texture: np.ndarray  # ridge texture in [-1, 1]
    led: np.ndarray  # LED sector brightness about the rig axis
    optics: Optics


def _skin(
    layers: _Layers, finger: Finger, p_kpa: float, polar: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(inside weight, halo weight, skin intensity) on the supersampled grid."""
    v = finger.values
    depth = polar[1] - polar[0]  # mm inside the edge (< 0 outside)
    inside = 1.0 / (1.0 + np.exp(-np.clip(depth / EDGE_MM, -50, 50)))
    halo = np.exp(np.minimum(depth, 0.0) / v["halo_mm"]) * (depth < 0)
    grow = min((p_kpa - v["onset_kpa"]) / 5.0, 1.0)
    contrast = v["ridge_contrast"] * (ONSET_CONTRAST + (1 - ONSET_CONTRAST) * grow)
    skin = v["glow_level"] * v["skin_level"] * (1.0 + contrast * layers.texture)
    return inside, halo, skin


def _draw(layers: _Layers, finger: Finger, p_kpa: float, rng: np.random.Generator) -> Frame:
    patch = contact_patch(finger, p_kpa)
    polar = None if patch is None else patch.polar(layers.grid.x, layers.grid.y)
    scene = layers.background + inner_ring(layers.grid, finger, p_kpa, layers.led, patch, polar)
    mask = np.zeros(layers.pixels.x.shape, bool)
    area = 0.0
    if patch is not None and polar is not None:
        inside, halo, skin = _skin(layers, finger, p_kpa, polar)
        faint = 0.4 * finger.values["ridge_contrast"] * halo * layers.texture
        scene = scene * (1.0 - inside) * (1.0 + faint) + skin * inside
        dist, edge = patch.polar(layers.pixels.x, layers.pixels.y)
        mask = dist < edge
        # A patch smaller than the pixel grid resolves counts as no contact (contact = mask).
        area = patch.area_mm2() if mask.any() else 0.0
    rgb = expose(scene.astype(np.float32), layers.optics, finger, layers.grid.ss, rng)
    return Frame(pressure_kpa=p_kpa, rgb=rgb, mask=mask, area_mm2=area)


def session_frames(
    config: GeneratorConfig, finger_no: int, finger: Finger, pressures: Sequence[float]
) -> Iterator[Frame]:
    """The frames of one session at ``pressures`` (kPa), in the order given.

    Frame ``k`` draws its noise from numpy Generator ``[seed, finger_no, k]``; the session's
    texture, sparkle and rings are fixed, so frames differ only where the pressure acts.
    """
    mm = finger.mm_per_px(config.width)
    grid = make_grid(config.width, config.height, mm, config.supersample)
    layers = _Layers(
        grid=grid,
        pixels=make_grid(config.width, config.height, mm, 1),
        background=window_and_glow(grid, finger),
        texture=ridge_texture(grid, finger),
        led=led_profile(finger, grid.theta),
        optics=session_optics(grid, finger),
    )
    for k, p in enumerate(pressures):
        rng = np.random.default_rng([config.seed, finger_no, k])
        yield _draw(layers, finger, float(p), rng)

"""Membrane underside appearance: mica-flake coating blended with skin where it touches.

The coating is a ``normalmap`` of per-flake random normals over a GGX ``roughconductor``
(sparkly rough specular), mixed with a little diffuse binder; ``blendbsdf`` with the caller's
``contact_weight`` bitmap (membrane uv space) switches to diffuse skin where ridges touch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MembraneOptics", "check_weight", "membrane_bsdf_dict", "particle_normal_map"]


@dataclass(frozen=True)
class MembraneOptics:
    """Appearance of the membrane's mica-coated underside and of the skin seen through it."""

    particle_density_per_mm2: float = 600.0  # mica flakes per mm² (~40 µm flakes); more = finer
    particle_tilt_deg: float = 2.0  # rms tilt of most flakes; larger = blurrier rings
    sparkle_fraction: float = 0.1  # share of strongly tilted flakes; more = more glitter
    sparkle_tilt_deg: float = 20.0  # rms tilt of those; they light up away from the rings
    roughness_alpha: float = 0.06  # GGX alpha of each flake; larger = softer, dimmer rings
    coating_reflectance: tuple[float, float, float] = (0.55, 0.55, 0.55)  # silvery mica
    coating_diffuse: float = 0.03  # fraction of diffuse binder; >0 = membrane faintly grey
    coating_diffuse_rgb: tuple[float, float, float] = (0.5, 0.5, 0.5)  # binder albedo
    skin_rgb: tuple[float, float, float] = (0.62, 0.42, 0.36)  # skin albedo in contact

    def __post_init__(self) -> None:
        """Reject out-of-range values (``ValueError`` naming ``synth/scene.py``)."""
        if not self.particle_density_per_mm2 > 0:
            raise ValueError("synth/scene.py: particle_density_per_mm2 must be > 0")
        for name in ("particle_tilt_deg", "sparkle_tilt_deg"):
            if not 0 <= getattr(self, name) < 60:
                raise ValueError(f"synth/scene.py: {name} must be in [0, 60)")
        if not 0 <= self.sparkle_fraction <= 1:
            raise ValueError("synth/scene.py: sparkle_fraction must be in [0, 1]")
        if not 0.001 <= self.roughness_alpha <= 1:
            raise ValueError("synth/scene.py: roughness_alpha must be in [0.001, 1]")
        if not 0 <= self.coating_diffuse <= 1:
            raise ValueError("synth/scene.py: coating_diffuse must be in [0, 1]")
        for name in ("coating_reflectance", "coating_diffuse_rgb", "skin_rgb"):
            v = getattr(self, name)
            if len(v) != 3 or not all(0 <= c <= 1 for c in v):
                raise ValueError(f"synth/scene.py: {name} must be 3 values in [0, 1], got {v}")


def particle_normal_map(
    rng: np.random.Generator, size: int, clamp_radius_mm: float, optics: MembraneOptics
) -> np.ndarray:
    """Tangent-space normal map of the mica flakes over ``[-a, a]²`` (``(size, size, 3)``).

    Flakes are cells of a grid of pitch ``1/sqrt(density)`` whose borders are dithered by a
    per-texel jitter (irregular, Voronoi-like outlines); each flake gets a random tilt with
    rms ``particle_tilt_deg`` (or ``sparkle_tilt_deg`` for a ``sparkle_fraction`` of them)
    and uniform azimuth. Encoded as ``(n + 1) / 2`` float32.
    """
    pitch = 1.0 / math.sqrt(optics.particle_density_per_mm2)
    texel = 2 * clamp_radius_mm / size
    g = max(1, math.ceil(2 * clamp_radius_mm / pitch))
    sig = math.tan(math.radians(optics.particle_tilt_deg)) / math.sqrt(2.0)
    sig_s = math.tan(math.radians(optics.sparkle_tilt_deg)) / math.sqrt(2.0)
    sparkle = rng.random((g + 1, g + 1, 1)) < optics.sparkle_fraction
    slopes = rng.normal(0.0, 1.0, size=(g + 1, g + 1, 2)) * np.where(sparkle, sig_s, sig)
    c = (np.arange(size) + 0.5) * texel / pitch
    jit = rng.uniform(-0.35, 0.35, size=(2, size, size))
    iy = np.clip(np.floor(c[:, None] + jit[0]), 0, g).astype(np.int64)
    ix = np.clip(np.floor(c[None, :] + jit[1]), 0, g).astype(np.int64)
    s = slopes[iy, ix]
    n = np.concatenate([-s, np.ones((*s.shape[:2], 1))], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return ((n + 1.0) * 0.5).astype(np.float32)


def membrane_bsdf_dict(
    contact_weight: np.ndarray, normal_map: np.ndarray, optics: MembraneOptics
) -> dict:
    """BSDF of the membrane's underside: ``blend(contact_weight; coating, skin)``.

    coating = ``blend(coating_diffuse; normalmap(flakes) over roughconductor, diffuse binder)``.
    ``contact_weight`` ``(M, M)`` in [0, 1] covers ``[-a, a]²``: row i at
    ``y = -a + (i + 0.5) 2a/M``, column j at ``x = -a + (j + 0.5) 2a/M`` (a top view with row
    0 at the smallest y); 1 = skin touching (diffuse skin), 0 = bare coating.
    """
    import mitsuba as mi

    w = check_weight(contact_weight)
    return {
        "type": "blendbsdf",
        "weight": _bitmap(mi, w[..., None], "bilinear"),
        "coating": {
            "type": "blendbsdf",
            "weight": {"type": "rgb", "value": float(optics.coating_diffuse)},
            "flakes": {
                "type": "normalmap",
                "normalmap": _bitmap(mi, normal_map, "nearest"),
                "bsdf": {
                    "type": "roughconductor",
                    "distribution": "ggx",
                    "alpha": float(optics.roughness_alpha),
                    "material": "none",
                    "specular_reflectance": {
                        "type": "rgb",
                        "value": list(optics.coating_reflectance),
                    },
                },
            },
            "binder": {
                "type": "diffuse",
                "reflectance": {"type": "rgb", "value": list(optics.coating_diffuse_rgb)},
            },
        },
        "skin": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(optics.skin_rgb)}},
    }


def _bitmap(mi, data: np.ndarray, filt: str) -> dict:
    # Mitsuba looks up row 0 at v = 0 for our uv (verified in tests): no flip needed.
    return {
        "type": "bitmap",
        "data": mi.TensorXf(np.ascontiguousarray(data, dtype=np.float32)),
        "raw": True,
        "filter_type": filt,
        "wrap_mode": "clamp",
    }


def check_weight(w: np.ndarray) -> np.ndarray:
    w = np.asarray(w, dtype=np.float32)
    if w.ndim != 2 or w.shape[0] != w.shape[1] or w.shape[0] < 2:
        raise ValueError(f"synth/scene.py: contact_weight must be (M, M), M>=2, got {w.shape}")
    if not np.all(np.isfinite(w)) or w.min() < 0 or w.max() > 1:
        raise ValueError("synth/scene.py: contact_weight must be finite and in [0, 1]")
    return w

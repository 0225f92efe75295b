"""Render many calibration frames from one loaded Mitsuba scene, updating it in place.

``RigRenderer`` loads the scene once for a (rig, size, spp, mesh resolution, texture sizes)
and then, per frame, writes the membrane vertices/normals, the contact-weight bitmap, the LGP
radiance texture and (when the particle seed or optics change) the flake normal map through
``mi.traverse`` + ``params.update()``: reloading scenes in a loop leaks memory. The window is
composited in closed form: ``frame = T(θ)² * mitsuba + WindowReflection`` (``window.py``).

Determinism: the same inputs and ``seed`` give a bit-identical frame (Mitsuba's independent
sampler is seeded per call; the window and normal map are deterministic numpy).
"""

from __future__ import annotations

import gc
from types import TracebackType

import numpy as np

from contactcal.synth.coating import MembraneOptics, particle_normal_map
from contactcal.synth.rig import RigGeometry, mm_per_px_at, pixel_rays, project_to_pixels
from contactcal.synth.scene import (
    ZFn,
    lgp_profile_texture,
    membrane_vertices,
    polar_disk_topology,
    scene_dict,
    set_buffer,
)
from contactcal.synth.variant import set_variant
from contactcal.synth.window import WindowReflection, sample_profile, window_transmission

__all__ = ["RigRenderer", "mm_per_px_at", "pixel_rays", "project_to_pixels"]

_K_LGP = 256  # azimuthal texels of the LGP texture; caller profiles are resampled to this


def _resample_profile(profile: np.ndarray) -> np.ndarray:
    """Periodic linear resampling of a ``(K,)`` profile (φ_k = 2πk/K) to ``_K_LGP`` samples."""
    p = np.asarray(profile, np.float64).ravel()
    if p.size < 1 or not np.all(np.isfinite(p)) or np.any(p < 0):
        raise ValueError(
            f"synth/render.py: azimuthal_profile must be a non-empty (K,) array >= 0, got "
            f"shape {np.shape(profile)}"
        )
    return sample_profile(p, 2 * np.pi * np.arange(_K_LGP) / _K_LGP)


def _flat(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.zeros_like(x)


class RigRenderer:
    """One loaded scene, many frames.

    Args:
        rig: geometry.
        width: image width (px); ``width / height`` must match ``rig.sensor_aspect``.
        height: image height (px).
        spp: samples per pixel.
        n_rings: radial rings of the membrane mesh (fixed topology).
        n_sectors: azimuthal sectors of the membrane mesh.
        weight_size: M of the ``(M, M)`` contact-weight texture over ``[-a, a]²``.
        normal_map_size: texels per side of the flake normal map (24 µm at 1024, a = 12.5 mm).
        variant: ``"auto"``, ``"llvm_ad_rgb"`` or ``"scalar_rgb"`` (``variant.choose_variant``).
        with_cylinder: include the 2 %-black housing wall (+1-3 % diffuse fill, see docs).
    """

    def __init__(
        self,
        rig: RigGeometry,
        width: int,
        height: int,
        spp: int = 16,
        n_rings: int = 96,
        n_sectors: int = 256,
        weight_size: int = 1024,
        normal_map_size: int = 1024,
        variant: str = "auto",
        with_cylinder: bool = True,
    ) -> None:
        if spp < 1 or weight_size < 2 or normal_map_size < 2:
            raise ValueError("synth/render.py: need spp>=1, weight_size>=2, normal_map_size>=2")
        self.variant = set_variant(variant)
        import mitsuba as mi

        self._mi = mi
        self.rig, self.width, self.height, self.spp = rig, int(width), int(height), int(spp)
        self.weight_size = int(weight_size)
        self.normal_map_size = int(normal_map_size)
        xy, _ = polar_disk_topology(n_rings, n_sectors)
        self._xy_mm = xy * rig.clamp_radius_mm
        self._optics = MembraneOptics()
        self._particle_seed: int | None = 0
        nm = particle_normal_map(
            np.random.default_rng(0), normal_map_size, rig.clamp_radius_mm, self._optics
        )
        d = scene_dict(
            rig,
            width,
            height,
            spp,
            z_fn=_flat,
            contact_weight=np.zeros((weight_size, weight_size), np.float32),
            lgp_radiance=1.0,
            azimuthal_profile=np.ones(_K_LGP),
            normal_map=nm,
            optics=self._optics,
            seed=0,
            n_rings=n_rings,
            n_sectors=n_sectors,
            with_cylinder=with_cylinder,
        )
        self.scene = mi.load_dict(d)
        self.params = mi.traverse(self.scene)
        self._transmission = window_transmission(rig, width, height)
        self._window = WindowReflection(rig, width, height, _K_LGP)

    # ----------------------------------------------------------------- updates
    def _set_geometry(self, z_fn: ZFn) -> None:
        pos, nrm = membrane_vertices(z_fn, self._xy_mm)
        set_buffer(self.params, "membrane.vertex_positions", pos.astype(np.float32))
        set_buffer(self.params, "membrane.vertex_normals", nrm.astype(np.float32))

    def _set_optics(self, optics: MembraneOptics, particle_seed: int) -> None:
        mi, p = self._mi, self.params
        key = "membrane.bsdf.bsdf_0."
        flakes = key + "bsdf_0.nested_bsdf."
        p[key + "weight.value"] = float(optics.coating_diffuse)
        p[flakes + "alpha.value"] = float(optics.roughness_alpha)
        p[flakes + "specular_reflectance.value"] = mi.Color3f(*optics.coating_reflectance)
        p[key + "bsdf_1.reflectance.value"] = mi.Color3f(*optics.coating_diffuse_rgb)
        p["membrane.bsdf.bsdf_1.reflectance.value"] = mi.Color3f(*optics.skin_rgb)
        if particle_seed != self._particle_seed or _flakes_changed(optics, self._optics):
            rng = np.random.default_rng(particle_seed)
            nm = particle_normal_map(rng, self.normal_map_size, self.rig.clamp_radius_mm, optics)
            p[key + "bsdf_0.normalmap.data"] = mi.TensorXf(nm)
            self._particle_seed = particle_seed
        self._optics = optics

    def _set_weight(self, contact_weight: np.ndarray) -> None:
        w = np.asarray(contact_weight, np.float32)
        m = self.weight_size
        if w.shape != (m, m) or not np.all(np.isfinite(w)) or w.min() < 0 or w.max() > 1:
            raise ValueError(
                f"synth/render.py: contact_weight must be ({m}, {m}) float in [0, 1] (the "
                f"renderer's weight_size), got shape {w.shape}"
            )
        self.params["membrane.bsdf.weight.data"] = self._mi.TensorXf(w[..., None])

    # ----------------------------------------------------------------- public
    def render_layers(
        self,
        z_fn: ZFn,
        contact_weight: np.ndarray,
        lgp_radiance: np.ndarray | float,
        azimuthal_profile: np.ndarray,
        particle_seed: int = 0,
        optics: MembraneOptics | None = None,
        seed: int = 0,
    ) -> dict[str, np.ndarray]:
        """Render the separate layers of one frame (arguments as in ``render``).

        Returns:
            ``{"scene": (H, W, 3) Mitsuba radiance without window, "transmission": (H, W)
            T(θ)², "reflection": (H, W, 3) window reflex}``, all float32.
        """
        prof = _resample_profile(azimuthal_profile)
        self._set_geometry(z_fn)
        self._set_weight(contact_weight)
        self._set_optics(optics or self._optics, int(particle_seed))
        self.params["lgp.emitter.radiance.data"] = self._mi.TensorXf(
            lgp_profile_texture(lgp_radiance, prof)
        )
        self.params.update()
        img = np.array(self._mi.render(self.scene, spp=self.spp, seed=int(seed)), np.float32)
        return {
            "scene": img[..., :3],
            "transmission": self._transmission,
            "reflection": self._window(lgp_radiance, prof),
        }

    def render(
        self,
        z_fn: ZFn,
        contact_weight: np.ndarray,
        lgp_radiance: np.ndarray | float,
        azimuthal_profile: np.ndarray,
        particle_seed: int = 0,
        optics: MembraneOptics | None = None,
        seed: int = 0,
    ) -> np.ndarray:
        """Render one frame.

        Args:
            z_fn: membrane height ``z_fn(x_mm, y_mm) -> z_mm`` (vectorised, z(r = a) ≈ 0).
            contact_weight: ``(M, M)`` float32 in [0, 1] over ``[-a, a]²`` (row i at
                ``y = -a + (i + 0.5) 2a/M``, column j at ``x = -a + (j + 0.5) 2a/M``);
                1 = skin touching the membrane.
            lgp_radiance: LGP radiance, scalar or ``(3,)`` RGB.
            azimuthal_profile: ``(K,)`` relative LGP radiance at φ_k = 2πk/K.
            particle_seed: seed of the flake normal map (regenerated only when it changes).
            optics: coating/skin appearance; ``None`` keeps the current one.
            seed: Monte-Carlo seed.

        Returns:
            ``(H, W, 3)`` float32 linear radiance, window composited:
            ``transmission * scene + reflection``.
        """
        lay = self.render_layers(
            z_fn, contact_weight, lgp_radiance, azimuthal_profile, particle_seed, optics, seed
        )
        out = lay["transmission"][..., None] * lay["scene"] + lay["reflection"]
        return out.astype(np.float32)

    def hit_points(self, z_fn: ZFn) -> np.ndarray:
        """World point (mm) where each pixel-centre ray first meets the membrane.

        Uses ``pixel_rays`` (identical to the Mitsuba camera's pixel-centre rays) and
        ``scene.ray_intersect`` on the same triangulated membrane the frame is rendered with.

        Returns:
            ``(H, W, 3)`` float64; NaN where the ray misses the membrane.
        """
        mi = self._mi
        self._set_geometry(z_fn)
        self.params.update()
        o, d = pixel_rays(self.rig, self.width, self.height)
        o, d = o.reshape(-1, 3), d.reshape(-1, 3)
        if self.variant.startswith("scalar"):
            pts = np.full(o.shape, np.nan)
            ok = np.zeros(len(o), bool)
            for k in range(len(o)):
                si = self.scene.ray_intersect(mi.Ray3f(o[k], d[k]))
                if si.is_valid():
                    pts[k], ok[k] = np.array(si.p, np.float64), True
        else:
            si = self.scene.ray_intersect(mi.Ray3f(mi.Point3f(*o.T), mi.Vector3f(*d.T)))
            ok = np.array(si.is_valid(), bool)
            pts = np.array(si.p, np.float64).reshape(3, -1).T.copy()
        rho = np.hypot(pts[:, 0], pts[:, 1])
        member = (
            ok
            & (rho <= self.rig.clamp_radius_mm * (1 + 1e-5))
            & (pts[:, 2] > self.rig.z_window_top)
        )
        pts[~member] = np.nan
        return pts.reshape(self.height, self.width, 3)

    def close(self) -> None:
        """Drop the scene and free Dr.Jit's cached memory (the renderer is unusable after)."""
        self.scene = None
        self.params = None
        gc.collect()
        try:
            import drjit as dr

            dr.flush_malloc_cache()
        except (ImportError, AttributeError):
            pass

    def __enter__(self) -> RigRenderer:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def _flakes_changed(a: MembraneOptics, b: MembraneOptics) -> bool:
    return (
        a.particle_density_per_mm2 != b.particle_density_per_mm2
        or a.particle_tilt_deg != b.particle_tilt_deg
        or a.sparkle_fraction != b.sparkle_fraction
        or a.sparkle_tilt_deg != b.sparkle_tilt_deg
    )

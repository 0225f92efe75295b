"""Closed-form PMMA window: the LGP's reflection on it and its transmission.

Why outside Mitsuba: a thin flat slab in the scene reflects only a few % of the paths that
reach it, so its reflex converges slowly (very noisy rings at affordable spp), while it is a
fixed image that a closed form reproduces within 0.5 % (prototype measurement). Here:

- each camera ray meets the window's bottom face at incidence θ; unpolarised Fresnel
  reflectance ``R(θ)`` at the air/PMMA interface (the same at both faces);
- reflection: ``R`` off the bottom face plus, after refraction, reflection off the top face
  and refraction back, ``(1-R)² R Σ R^{2k} = (1-R) R / (1+R)``; total ``2R / (1+R)`` (thin slab,
  incoherent). The second reflex is **laterally shifted** by ``2 t tan θ_t`` (0.4-0.6 mm at the
  ring's angles): modelled, it widens the ring's inner edge by a faint second copy;
- each reflected ray is followed down to the LGP plane; inside the annulus it picks up the
  LGP's radiance times the azimuthal profile (same periodic linear interpolation as the
  Mitsuba texture);
- anti-aliased with ``ss x ss`` stratified sub-pixel rays (deterministic);
- transmission per pass ``T = 1 - 2R/(1+R) = (1-R)/(1+R)``; light seen through the window has
  crossed it twice (LGP -> membrane upwards, membrane -> camera downwards), so the factor is
  ``T(θ)²`` with θ the camera ray's angle. For the specular rings of a near-flat membrane the
  upward angle equals θ; for the diffuse skin it differs (up to ~45°, T 0.92 -> 0.90), an
  error below the LGP radiance randomisation, stated rather than modelled;
- not modelled: the slab's refraction shift of the transmitted image (it moves the membrane
  apparent position ~0.7 mm closer, a 1 % scale change; frames and labels share the same
  un-refracted camera, so labels stay consistent), absorption in 2 mm PMMA (< 1 %).
"""

from __future__ import annotations

import numpy as np

from contactcal.synth.rig import RigGeometry, pixel_rays

__all__ = [
    "WindowReflection",
    "fresnel_unpolarized",
    "sample_profile",
    "window_transmission",
]


def fresnel_unpolarized(cos_i: np.ndarray, n: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of an air -> dielectric (index ``n``) interface.

    Args:
        cos_i: cosine of the incidence angle, in (0, 1].
        n: refractive index of the slab.
    """
    c = np.clip(np.asarray(cos_i, np.float64), 1e-9, 1.0)
    s2 = 1.0 - c * c
    ct = np.sqrt(np.maximum(0.0, 1.0 - s2 / (n * n)))
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def sample_profile(profile: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Periodic linear interpolation of ``profile[k]`` given at φ_k = 2πk/K (radians)."""
    p = np.asarray(profile, np.float64).ravel()
    return np.interp(phi, 2 * np.pi * np.arange(p.size) / p.size, p, period=2 * np.pi)


def _slab(rig: RigGeometry, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hit point on the window's bottom face, aperture mask and Fresnel R for rays ``d``."""
    c = np.asarray(rig.camera_position)
    t = (rig.z_window_bottom - c[2]) / d[..., 2]
    p = c + t[..., None] * d
    inside = np.hypot(p[..., 0], p[..., 1]) <= rig.cylinder_radius_mm
    r = fresnel_unpolarized(d[..., 2], rig.window_ior)
    return p, inside, r


class WindowReflection:
    """Precomputed linear map from the LGP's azimuthal profile to the window reflex image.

    The geometry (which sub-pixel rays land on the LGP, where and with which Fresnel weight)
    is fixed for a rig and image size; per frame only the profile changes, so the reflex is a
    weighted gather: ``refl[pix] = Σ w (1-f) p[i0] + w f p[i1]``.

    Args:
        rig: geometry.
        width: image width (px).
        height: image height (px).
        n_profile: K, the number of azimuthal profile samples (φ_k = 2πk/K).
        ss: sub-pixel rays per axis (``ss²`` per pixel) for anti-aliasing.
    """

    def __init__(self, rig: RigGeometry, width: int, height: int, n_profile: int, ss: int = 4):
        if ss < 1 or n_profile < 1:
            raise ValueError(f"synth/window.py: need ss>=1, n_profile>=1, got {ss}, {n_profile}")
        self.shape = (height, width)
        self.n_profile = n_profile
        n = rig.window_ior
        r_in, r_out = rig.lgp_inner_radius_mm, rig.lgp_outer_radius_mm
        drop = rig.z_window_bottom - rig.z_lgp  # vertical path from window bottom to LGP face
        pix_all = np.arange(width * height).reshape(height, width)
        pix, i0, i1, w0, w1 = [], [], [], [], []
        for sy in range(ss):
            for sx in range(ss):
                _, d = pixel_rays(rig, width, height, ((sx + 0.5) / ss, (sy + 0.5) / ss))
                p, inside, r = _slab(rig, d)
                cos_i = d[..., 2]
                sin_i = np.sqrt(np.maximum(0.0, 1 - cos_i * cos_i))
                sin_t = sin_i / n
                tan_t = sin_t / np.sqrt(1 - sin_t * sin_t)
                horiz = d[..., :2] / np.maximum(sin_i, 1e-12)[..., None]  # unit horizontal
                lat = (drop / cos_i * sin_i)[..., None] * horiz  # reflected ray's travel
                shift = (2 * rig.window_thickness_mm * tan_t)[..., None] * horiz
                second = (1 - r) * r / (1 + r)
                for land, w in ((p[..., :2] + lat, r), (p[..., :2] + lat + shift, second)):
                    rho = np.hypot(land[..., 0], land[..., 1])
                    on = inside & (rho >= r_in) & (rho <= r_out)
                    phi = np.arctan2(land[..., 1], land[..., 0])[on]
                    t = np.mod(phi, 2 * np.pi) / (2 * np.pi) * n_profile
                    k0 = np.floor(t).astype(np.int64) % n_profile
                    f = t - np.floor(t)
                    ww = w[on] / (ss * ss)
                    pix.append(pix_all[on])
                    i0.append(k0)
                    i1.append((k0 + 1) % n_profile)
                    w0.append(ww * (1 - f))
                    w1.append(ww * f)
        self._pix = np.concatenate(pix)
        self._i0, self._i1 = np.concatenate(i0), np.concatenate(i1)
        self._w0, self._w1 = np.concatenate(w0), np.concatenate(w1)

    def __call__(
        self, lgp_radiance: np.ndarray | float, azimuthal_profile: np.ndarray
    ) -> np.ndarray:
        """``(H, W, 3)`` float32 reflected radiance for this LGP radiance and ``(K,)`` profile."""
        rad = np.broadcast_to(np.asarray(lgp_radiance, np.float64), (3,))
        prof = np.asarray(azimuthal_profile, np.float64).ravel()
        if prof.size != self.n_profile or np.any(prof < 0) or np.any(rad < 0):
            raise ValueError(
                f"synth/window.py: need a ({self.n_profile},) profile >= 0 and radiance >= 0, "
                f"got profile shape {prof.shape}"
            )
        vals = self._w0 * prof[self._i0] + self._w1 * prof[self._i1]
        h, w = self.shape
        acc = np.bincount(self._pix, weights=vals, minlength=h * w).reshape(h, w)
        return (acc[..., None] * rad[None, None, :]).astype(np.float32)


def window_transmission(rig: RigGeometry, width: int, height: int) -> np.ndarray:
    """Two-pass slab transmission ``T(θ)²`` per pixel centre (1 outside the window aperture).

    Returns:
        ``(H, W)`` float32 in (0, 1].
    """
    _, d = pixel_rays(rig, width, height)
    _, inside, r = _slab(rig, d)
    t = (1 - r) / (1 + r)
    return np.where(inside, t * t, 1.0).astype(np.float32)

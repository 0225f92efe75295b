"""The rig's Mitsuba scene as data: small builders returning dicts (or in-memory meshes).

What is in the Mitsuba scene (docs/renderer.md has the ablations):
- camera: ideal pinhole, box pixel filter (no cross-pixel blur, so labels stay pixel-exact);
- LGP: annular Lambertian emitter facing up, per-LED non-uniformity as an azimuthal texture;
- membrane: height-field mesh over the clamp disk, mica-coated underside blended with skin;
- integrator: ``path``, ``max_depth=3`` (camera -> membrane -> LGP, plus one inter-reflection
  of the concave membrane). ``volpath`` is not needed: no thin occluder lies between the
  membrane and the LGP, because the window is composited analytically (``window.py``).
- housing: the 2 %-black cylinder wall (optional; it adds a +1-3 % diffuse fill and a faint
  band beyond the clamp edge, below the Monte-Carlo noise but systematic).
Not in it: the window (closed form) and the finger above the membrane (the coated membrane is
opaque in this model, so the finger changes no pixel: measured max difference 2e-5).

Mitsuba has no dict form for in-memory meshes, so ``lgp_dict`` and ``membrane_dict`` return
``mitsuba.Mesh`` objects, which are valid values in a scene dict. A Mitsuba variant must be set.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from contactcal.synth.coating import MembraneOptics, membrane_bsdf_dict, particle_normal_map
from contactcal.synth.rig import RigGeometry

__all__ = [
    "MembraneOptics",
    "ZFn",
    "camera_dict",
    "cylinder_dict",
    "lgp_dict",
    "membrane_bsdf_dict",
    "membrane_dict",
    "membrane_vertices",
    "particle_normal_map",
    "polar_disk_topology",
    "scene_dict",
]

ZFn = Callable[[np.ndarray, np.ndarray], np.ndarray]
_FD_EPS_MM = 1e-3  # finite-difference step for vertex normals


def _mi():
    import mitsuba as mi

    if mi.variant() is None:
        raise RuntimeError("synth/scene.py: set a Mitsuba variant first (variant.set_variant)")
    return mi


def camera_dict(rig: RigGeometry, width: int, height: int, spp: int, seed: int = 0) -> dict:
    """Pinhole sensor at the cylinder's bottom looking up ``+z`` (image up = world ``+y``)."""
    mi = _mi()
    c = rig.camera_position
    return {
        "type": "perspective",
        "fov": rig.fov_y_deg,
        "fov_axis": "y",
        "near_clip": 0.01,
        "far_clip": 1000.0,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=list(c), target=[c[0], c[1], c[2] + 1.0], up=[0.0, 1.0, 0.0]
        ),
        "sampler": {"type": "independent", "sample_count": int(spp), "seed": int(seed)},
        "film": {
            "type": "hdrfilm",
            "width": int(width),
            "height": int(height),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
    }


def _mesh(name: str, pos: np.ndarray, faces: np.ndarray, uv: np.ndarray, normals, props):
    """Build an in-memory ``mi.Mesh`` from numpy buffers."""
    mi = _mi()
    mesh = mi.Mesh(name, len(pos), len(faces), props, True, True)
    p = mi.traverse(mesh)
    set_buffer(p, "vertex_positions", np.asarray(pos, np.float32))
    set_buffer(p, "faces", np.asarray(faces, np.uint32))
    set_buffer(p, "vertex_normals", np.asarray(normals, np.float32))
    set_buffer(p, "vertex_texcoords", np.asarray(uv, np.float32))
    p.update()
    return mesh


def set_buffer(params, key: str, values: np.ndarray) -> None:
    """Write a flat numpy buffer into a traversed mesh parameter (any variant, same dtype)."""
    params[key] = type(params[key])(np.ascontiguousarray(values).ravel())


def lgp_profile_texture(radiance: np.ndarray | float, profile: np.ndarray) -> np.ndarray:
    """``(2, K, 3)`` float32 emitted radiance per LGP azimuth sample (texel k at φ = 2πk/K).

    Two identical rows: Mitsuba rejects bitmap updates smaller than 2x2.
    """
    rad = np.broadcast_to(np.asarray(radiance, np.float64), (3,))
    prof = np.asarray(profile, np.float64).ravel()
    if prof.size < 1 or np.any(~np.isfinite(prof)) or np.any(prof < 0) or np.any(rad < 0):
        raise ValueError("synth/scene.py: LGP radiance/profile must be finite and >= 0")
    tex = (prof[None, :, None] * rad[None, None, :]).astype(np.float32)
    return np.repeat(tex, 2, axis=0)


def lgp_dict(
    rig: RigGeometry,
    radiance: np.ndarray | float,
    azimuthal_profile: np.ndarray,
    n_sectors: int = 256,
):
    """Annular LGP emitter in the plane ``z = rig.z_lgp``, emitting up (``+z`` only).

    Args:
        rig: geometry.
        radiance: emitted radiance, scalar or ``(3,)`` RGB (arbitrary linear units).
        azimuthal_profile: ``(K,)`` float >= 0, relative radiance at azimuth φ_k = 2πk/K
            (φ from world +x towards +y), linearly interpolated and periodic.
        n_sectors: tessellation of the annulus.

    Returns:
        ``mi.Mesh`` with an ``area`` emitter textured by the profile and a black back side.
    """
    mi = _mi()
    tex = lgp_profile_texture(radiance, azimuthal_profile)
    k = tex.shape[1]
    phi = 2 * np.pi * np.arange(n_sectors + 1) / n_sectors
    r = np.array([rig.lgp_inner_radius_mm, rig.lgp_outer_radius_mm])
    pp, rr = np.meshgrid(phi, r)  # (2, S+1): row 0 inner, row 1 outer
    pos = np.stack([rr * np.cos(pp), rr * np.sin(pp), np.full_like(rr, rig.z_lgp)], -1)
    uv = np.stack([pp / (2 * np.pi) + 0.5 / k, (rr - r[0]) / (r[1] - r[0])], -1)
    i0 = np.arange(n_sectors)
    o0 = i0 + n_sectors + 1
    faces = np.concatenate([np.stack([i0, o0, o0 + 1], 1), np.stack([i0, o0 + 1, i0 + 1], 1)])
    normals = np.broadcast_to([0.0, 0.0, 1.0], (pos.size // 3, 3))
    props = mi.Properties()
    props["emitter"] = mi.load_dict(
        {
            "type": "area",
            "radiance": {
                "type": "bitmap",
                "data": mi.TensorXf(tex),
                "raw": True,
                "wrap_mode": "repeat",
                "filter_type": "bilinear",
            },
        }
    )
    props["bsdf"] = mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}})
    return _mesh("lgp", pos.reshape(-1, 3), faces, uv.reshape(-1, 2), normals, props)


def cylinder_dict(rig: RigGeometry, reflectance: float = 0.02) -> dict:
    """Black inner wall of the housing (diffuse, inward normals), camera to clamp plane.

    Its contribution (docs/renderer.md): +1-3 % diffuse fill on the membrane (wall lit by the
    LGP) and a faint band beyond the clamp edge; below the per-frame Monte-Carlo noise but
    systematic, and cheap, so ``scene_dict`` includes it by default.
    """
    z0 = rig.camera_position[2]
    h = -z0
    r = rig.cylinder_radius_mm
    return {
        "type": "cylinder",
        "radius": r,
        "p0": [0.0, 0.0, z0],
        "p1": [0.0, 0.0, z0 + h],
        "flip_normals": True,
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": float(reflectance)}},
    }


def polar_disk_topology(n_rings: int, n_sectors: int) -> tuple[np.ndarray, np.ndarray]:
    """Fixed triangulation of the unit disk (centre + rings), facing down (normal ``-z``).

    Returns:
        ``xy`` ``(V, 2)`` float64 on the unit disk (V = 1 + n_rings * n_sectors; the last ring
        lies on the circle), ``faces`` ``(F, 3)`` uint32 (F = n_sectors * (2 n_rings - 1)).
    """
    if n_rings < 1 or n_sectors < 3:
        raise ValueError(
            f"synth/scene.py: need n_rings>=1, n_sectors>=3, got {n_rings}, {n_sectors}"
        )
    k = np.arange(1, n_rings + 1)[:, None]
    s = np.arange(n_sectors)[None, :]
    rad = k / n_rings
    phi = 2 * np.pi * (s + 0.5 * (k % 2)) / n_sectors  # staggered rings: better triangles
    xy = np.concatenate(
        [[[0.0, 0.0]], np.stack([rad * np.cos(phi), rad * np.sin(phi)], -1).reshape(-1, 2)]
    )
    idx = lambda kk, ss: 1 + (kk - 1) * n_sectors + (ss % n_sectors)  # noqa: E731
    ss = np.arange(n_sectors)
    faces = [np.stack([np.zeros_like(ss), idx(1, ss + 1), idx(1, ss)], 1)]
    for kk in range(1, n_rings):
        i0, i1 = idx(kk, ss), idx(kk, ss + 1)
        sh = kk % 2  # outer ring's staggering relative to the inner one
        o0, o1 = idx(kk + 1, ss + 1 - sh), idx(kk + 1, ss + 2 - sh)
        # winding clockwise seen from above, so that the geometric normal is -z
        faces.append(np.stack([i0, o1, o0], 1))
        faces.append(np.stack([i0, i1, o1], 1))
    return xy, np.concatenate(faces).astype(np.uint32)


def membrane_vertices(z_fn: ZFn, xy_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Evaluate the membrane height field on the mesh vertices.

    Args:
        z_fn: ``z_fn(x_mm, y_mm) -> z_mm``, vectorised over float64 arrays of equal shape.
        xy_mm: ``(V, 2)`` vertex positions in mm.

    Returns:
        ``positions`` ``(V, 3)`` and unit ``normals`` ``(V, 3)`` pointing down (towards the
        camera), from central finite differences of ``z_fn``.
    """
    x, y = xy_mm[:, 0], xy_mm[:, 1]
    e = _FD_EPS_MM

    def ev(xx: np.ndarray, yy: np.ndarray) -> np.ndarray:
        z = np.asarray(z_fn(xx, yy), dtype=np.float64)
        if z.shape != xx.shape or not np.all(np.isfinite(z)):
            raise ValueError(
                f"synth/scene.py: z_fn must return finite z of shape {xx.shape}, got "
                f"shape {z.shape}"
            )
        return z

    z = ev(x, y)
    zx = (ev(x + e, y) - ev(x - e, y)) / (2 * e)
    zy = (ev(x, y + e) - ev(x, y - e)) / (2 * e)
    n = np.stack([zx, zy, -np.ones_like(zx)], 1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return np.stack([x, y, z], 1), n


def membrane_dict(
    rig: RigGeometry,
    z_fn: ZFn,
    contact_weight: np.ndarray,
    normal_map: np.ndarray,
    optics: MembraneOptics,
    n_rings: int = 96,
    n_sectors: int = 256,
):
    """Membrane mesh over the clamp disk (radius ``rig.clamp_radius_mm``), facing down.

    The topology depends only on ``(n_rings, n_sectors)``, so vertices can be updated in place
    (``RigRenderer``). uv = ``((x + a) / 2a, (y + a) / 2a)``.

    Returns:
        ``mi.Mesh`` named ``membrane`` with ``membrane_bsdf_dict`` as BSDF.
    """
    mi = _mi()
    a = rig.clamp_radius_mm
    xy, faces = polar_disk_topology(n_rings, n_sectors)
    pos, nrm = membrane_vertices(z_fn, xy * a)
    uv = (xy + 1.0) * 0.5
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(membrane_bsdf_dict(contact_weight, normal_map, optics))
    return _mesh("membrane", pos, faces, uv, nrm, props)


def scene_dict(
    rig: RigGeometry,
    width: int,
    height: int,
    spp: int,
    z_fn: ZFn,
    contact_weight: np.ndarray,
    lgp_radiance: np.ndarray | float,
    azimuthal_profile: np.ndarray,
    normal_map: np.ndarray,
    optics: MembraneOptics = MembraneOptics(),  # noqa: B008 (frozen dataclass)
    seed: int = 0,
    n_rings: int = 96,
    n_sectors: int = 256,
    with_cylinder: bool = True,
    max_depth: int = 3,
) -> dict:
    """Assemble the scene (see module docstring); the window is *not* in it (``window.py``)."""
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth)},
        "sensor": camera_dict(rig, width, height, spp, seed),
        "lgp": lgp_dict(rig, lgp_radiance, azimuthal_profile),
        "membrane": membrane_dict(
            rig, z_fn, contact_weight, normal_map, optics, n_rings, n_sectors
        ),
    }
    if with_cylinder:
        d["cylinder"] = cylinder_dict(rig)
    return d

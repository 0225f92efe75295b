"""Where the rig's two rings fall in the image, from geometry alone (no renderer, no noise).

The fidelity checks (``docs/fidelity.md``, ``tests/test_fidelity.py``) compare rendered frames
with the paper's observations about its rings. They need the rings' true positions, which follow
from the mirror geometry of the rig (docs/CONVENTIONS.md frame, mm):

* the **window ring**: camera rays reflected by the window's bottom face that land on the LGP
  annulus; its outer edge is a circle (closed form below);
* the **inner ring**: camera rays reflected by the *mean* membrane surface (the flakes' tilts
  scatter it in the render, which is why a render is brighter around this skeleton, not on it)
  that land on the LGP annulus.

Both ignore the window's refraction (a lateral shift of ~0.5 mm, as ``window.py``) and the
camera model's tilt and shift (``camera.py`` applies those to frame and mask alike; map points
with ``camera.tilt_homography`` when needed).
"""

from __future__ import annotations

import numpy as np

from contactcal.synth.rig import RigGeometry, focal_px, pixel_rays
from contactcal.synth.scene import ZFn

__all__ = ["membrane_hits", "membrane_reflex_mask", "window_ring_circle"]

_FIXED_POINT_ITERATIONS = 30  # ray / height-field intersection; slopes x tan(view) << 1
_FD_EPS_MM = 1e-3  # finite-difference step for the surface normal, mm


def window_ring_circle(rig: RigGeometry, width: int, height: int) -> tuple[float, float, float]:
    """Outer edge of the window ring (the LGP's reflection on the window's bottom face).

    A ray at angle θ off the axis meets the window bottom at ``r_w = H tan θ`` (``H`` the camera
    height below it) and, reflected, lands on the LGP plane at ``(H + gap) tan θ``. It is lit
    while that radius is inside the LGP annulus and ``r_w`` inside the window aperture, so the
    outer edge is at ``tan θ = min(R_out / (H + gap), R_cyl / H)``. A camera offset moves the
    circle by the same offset seen on the window.

    Returns:
        ``(cx, cy, radius)`` in pixels (OpenCV convention; no tilt or shift applied).
    """
    h = rig.z_window_bottom - rig.camera_position[2]
    gap = rig.lgp_gap_mm
    off_x, off_y = rig.camera_offset_mm
    # the LGP and the aperture are centred on the axis; in the camera's frame they sit at -offset
    tan_edge = min(rig.lgp_outer_radius_mm / (h + gap), rig.cylinder_radius_mm / h)
    f = focal_px(rig, height)
    cx = 0.5 * width - 0.5 - f * (-off_x) / (h + gap)  # world +x appears on the left
    cy = 0.5 * height - 0.5 - f * (-off_y) / (h + gap)
    return float(cx), float(cy), float(f * tan_edge)


def membrane_hits(rig: RigGeometry, z_fn: ZFn, width: int, height: int) -> np.ndarray:
    """First point where each pixel-centre ray meets the membrane height field.

    Args:
        rig: geometry.
        z_fn: membrane height ``z_fn(x_mm, y_mm) -> z_mm``, vectorised, 0 at and beyond the clamp.
        width, height: image size (px).

    Returns:
        ``(H, W, 3)`` float64 points (mm); NaN where the ray misses the membrane disc or is
        blocked by the window aperture.
    """
    o, d = pixel_rays(rig, width, height)
    t = (0.0 - o[..., 2]) / d[..., 2]
    for _ in range(_FIXED_POINT_ITERATIONS):
        p = o + t[..., None] * d
        t = (z_fn(p[..., 0], p[..., 1]) - o[..., 2]) / d[..., 2]
    p = o + t[..., None] * d
    t_win = (rig.z_window_bottom - o[..., 2]) / d[..., 2]
    w = o + t_win[..., None] * d
    ok = (np.hypot(p[..., 0], p[..., 1]) <= rig.clamp_radius_mm) & (
        np.hypot(w[..., 0], w[..., 1]) <= rig.cylinder_radius_mm
    )
    p[~ok] = np.nan
    return p


def membrane_reflex_mask(rig: RigGeometry, z_fn: ZFn, width: int, height: int) -> np.ndarray:
    """Pixels whose mirror reflection in the mean membrane surface lands on the LGP annulus.

    Returns:
        ``(H, W) bool``, the skeleton of the inner ring (no flake scatter, no window ring).
    """
    _, d = pixel_rays(rig, width, height)
    p = membrane_hits(rig, z_fn, width, height)
    ok = np.isfinite(p[..., 0])
    x, y = np.where(ok, p[..., 0], 0.0), np.where(ok, p[..., 1], 0.0)
    e = _FD_EPS_MM
    zx = (z_fn(x + e, y) - z_fn(x - e, y)) / (2 * e)
    zy = (z_fn(x, y + e) - z_fn(x, y - e)) / (2 * e)
    n = np.stack([-zx, -zy, np.ones_like(zx)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    r = d - 2.0 * np.sum(d * n, -1, keepdims=True) * n
    down = r[..., 2] < -1e-9
    z0 = np.where(ok, p[..., 2], 0.0)
    t_lgp = (rig.z_lgp - z0) / np.where(down, r[..., 2], -1.0)
    t_win = (rig.z_window_bottom - z0) / np.where(down, r[..., 2], -1.0)
    land = np.hypot(x + t_lgp * r[..., 0], y + t_lgp * r[..., 1])
    through = np.hypot(x + t_win * r[..., 0], y + t_win * r[..., 1]) <= rig.cylinder_radius_mm
    on = (land >= rig.lgp_inner_radius_mm) & (land <= rig.lgp_outer_radius_mm)
    return ok & down & through & on

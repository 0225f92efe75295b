"""Geometry of the optical calibration rig and the pinhole camera model shared by all renderers.

World frame (docs/CONVENTIONS.md): millimetres, origin at the centre of the membrane's clamp
plane, ``z`` up towards the finger. Everything optical lies below ``z = 0``:

    z = 0                       membrane clamp plane (flat membrane), clamp circle radius a
    z = -chamber_depth          window top face
    z = -chamber - thickness    window bottom face
    z = window bottom - gap     LGP emitting (top) face, annulus [r_in, r_out], facing +z
    z = window bottom - 55      camera pupil, on the axis, looking +z

The camera is an ideal pinhole (no distortion, no defocus), with the image's ``up`` = world
``+y``; looking up, world ``+x`` appears on the image's left (mirrored relative to a top view).
Pixel coordinates follow OpenCV: ``(u, v) = (column, row)``, the centre of pixel ``[i, j]`` is
at ``(u, v) = (j, i)``. This file is the single place that maps world points to pixels
(``render.py`` re-exports ``project_to_pixels``); the Mitsuba camera built by
``scene.camera_dict`` is verified against it in ``tests/test_render.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["RigGeometry", "mm_per_px_at", "pixel_rays", "project_to_pixels"]


@dataclass(frozen=True)
class RigGeometry:
    """Calibration rig (Sensors 2024 paper) plus the choices this renderer had to make.

    Lengths in mm, angles in degrees. Numbers marked *paper* are from the publication;
    the others are chosen so that the images show the paper's features (docs/renderer.md).
    """

    # --- housing (paper) ---
    cylinder_radius_mm: float = 13.75  # paper: inner diameter 27.5; bounds LGP and window aperture
    cylinder_height_mm: float = 55.0  # paper: camera pupil to window bottom; larger = smaller image
    # --- window (paper) ---
    window_thickness_mm: float = 2.0  # paper: 2 mm PMMA; sets the ~0.5 mm offset of its 2nd reflex
    window_ior: float = 1.49  # PMMA at 550 nm; higher = brighter outer ring, darker scene
    # --- display ---
    chamber_depth_mm: float = 8.0  # window top to clamp plane; deeper = patch smaller next to
    #   the window ring (the paper's 55 % ROI holds it), inner ring further inside
    clamp_radius_mm: float = 12.5  # membrane radius a (11.5-13.5); must be < cylinder radius
    # --- light guide plate (LGP): opaque annulus, edge-lit by LEDs, emitting up (Lambertian) ---
    lgp_inner_radius_mm: float = 11.5  # larger = thinner rings; must stay out of the camera's view
    lgp_outer_radius_mm: float = 13.75  # at the wall; the outer ring's outer edge
    lgp_gap_mm: float = 5.0  # LGP top face below window bottom: 0 = rings at the very edge but
    #   the inner ring re-appears only at ~7 mm inflation; 15 = it shrinks from ~3 mm on but the
    #   window ring looks smaller (ROI too small for the patch); 5 = both (docs/fidelity.md)
    # --- camera ---
    camera_offset_mm: tuple[float, float] = (0.0, 0.0)  # pupil (x, y) misalignment off the axis
    fov_y_deg: float = 29.0  # vertical field of view; 28.1 frames the window aperture exactly
    sensor_aspect: float = 4.0 / 3.0  # width / height of the 2592x1944 sensor; images must match

    def __post_init__(self) -> None:
        """Reject inconsistent geometry (raises ``ValueError`` naming ``synth/rig.py``)."""
        positive = (
            "cylinder_radius_mm",
            "cylinder_height_mm",
            "window_thickness_mm",
            "chamber_depth_mm",
            "clamp_radius_mm",
            "lgp_inner_radius_mm",
            "lgp_outer_radius_mm",
            "fov_y_deg",
            "sensor_aspect",
        )
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"synth/rig.py: RigGeometry.{name} must be > 0, got {v!r}")
        checks = [
            (self.window_ior > 1.0, "window_ior must be > 1"),
            (self.lgp_gap_mm >= 0.0, "lgp_gap_mm must be >= 0"),
            (self.lgp_inner_radius_mm < self.lgp_outer_radius_mm, "lgp inner < outer radius"),
            (self.lgp_outer_radius_mm <= self.cylinder_radius_mm, "lgp outer <= cylinder radius"),
            (self.clamp_radius_mm <= self.cylinder_radius_mm, "clamp radius <= cylinder radius"),
            (self.fov_y_deg < 170.0, "fov_y_deg must be < 170"),
            (len(self.camera_offset_mm) == 2, "camera_offset_mm must be (x, y)"),
        ]
        for ok, what in checks:
            if not ok:
                raise ValueError(f"synth/rig.py: inconsistent RigGeometry: {what} ({self})")

    @property
    def z_window_top(self) -> float:
        """z of the window's top face (mm)."""
        return -self.chamber_depth_mm

    @property
    def z_window_bottom(self) -> float:
        """z of the window's bottom face (mm)."""
        return -self.chamber_depth_mm - self.window_thickness_mm

    @property
    def z_lgp(self) -> float:
        """z of the LGP's emitting top face (mm)."""
        return self.z_window_bottom - self.lgp_gap_mm

    @property
    def camera_position(self) -> tuple[float, float, float]:
        """Camera pupil (x, y, z) in mm."""
        return (
            float(self.camera_offset_mm[0]),
            float(self.camera_offset_mm[1]),
            self.z_window_bottom - self.cylinder_height_mm,
        )


def _check_size(width: int, height: int, rig: RigGeometry) -> None:
    if int(width) != width or int(height) != height or width < 1 or height < 1:
        raise ValueError(f"synth/rig.py: image size must be positive ints, got {width}x{height}")
    if abs(width / height - rig.sensor_aspect) > 0.02 * rig.sensor_aspect:
        raise ValueError(
            f"synth/rig.py: image {width}x{height} does not have the sensor aspect "
            f"{rig.sensor_aspect:.4f} (RigGeometry.sensor_aspect)"
        )


def focal_px(rig: RigGeometry, height: int) -> float:
    """Focal length in pixels for an image of ``height`` rows (square pixels)."""
    return 0.5 * height / math.tan(math.radians(0.5 * rig.fov_y_deg))


def project_to_pixels(rig: RigGeometry, xyz_mm: np.ndarray, width: int, height: int) -> np.ndarray:
    """Project world points to pixel coordinates.

    Args:
        rig: geometry.
        xyz_mm: ``(N, 3)`` float world points in mm, in front of the camera (z above it).
        width: image width in pixels.
        height: image height in pixels.

    Returns:
        ``(N, 2)`` float64 ``(u, v)`` = (column, row); the centre of pixel ``[i, j]`` is ``(j, i)``.
    """
    _check_size(width, height, rig)
    p = np.asarray(xyz_mm, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"synth/rig.py: xyz_mm must have shape (N, 3), got {p.shape}")
    c = np.asarray(rig.camera_position)
    d = p - c
    if np.any(d[:, 2] <= 0):
        raise ValueError("synth/rig.py: project_to_pixels got points at or below the camera")
    f = focal_px(rig, height)
    u = 0.5 * width - 0.5 - f * d[:, 0] / d[:, 2]  # world +x appears on the left
    v = 0.5 * height - 0.5 - f * d[:, 1] / d[:, 2]  # world +y appears at the top
    return np.stack([u, v], axis=1)


def pixel_rays(
    rig: RigGeometry, width: int, height: int, subpixel: tuple[float, float] = (0.5, 0.5)
) -> tuple[np.ndarray, np.ndarray]:
    """Camera rays through pixel centres (or another sub-pixel position).

    Args:
        rig: geometry.
        width: image width in pixels.
        height: image height in pixels.
        subpixel: position inside each pixel as fractions ``(sx, sy)`` in [0, 1); (0.5, 0.5)
            is the centre, consistent with ``project_to_pixels``.

    Returns:
        ``origins`` ``(H, W, 3)`` float64 mm (all the camera pupil) and unit ``directions``
        ``(H, W, 3)`` float64.
    """
    _check_size(width, height, rig)
    f = focal_px(rig, height)
    u = np.arange(width, dtype=np.float64) + subpixel[0] - 0.5
    v = np.arange(height, dtype=np.float64) + subpixel[1] - 0.5
    uu, vv = np.meshgrid(u, v)
    dx = -(uu - (0.5 * width - 0.5)) / f
    dy = -(vv - (0.5 * height - 0.5)) / f
    d = np.stack([dx, dy, np.ones_like(dx)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.broadcast_to(np.asarray(rig.camera_position), d.shape).copy()
    return o, d


def mm_per_px_at(rig: RigGeometry, z_mm: float, width: int, height: int) -> float:
    """Size of one pixel (mm) on the plane ``z = z_mm``, at the image centre."""
    _check_size(width, height, rig)
    dz = z_mm - rig.camera_position[2]
    if dz <= 0:
        raise ValueError(f"synth/rig.py: plane z={z_mm} mm is not above the camera")
    return dz / focal_px(rig, height)

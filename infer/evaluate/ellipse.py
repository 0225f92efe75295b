"""A hand-drawn contact ellipse in ImageJ's convention, converted to OpenCV's and rasterised.

ImageJ (Analyze › Measure with "Centroid" and "Fit ellipse") reports an ellipse as ``X, Y``
(centre), ``Major, Minor`` (FULL axis lengths) and ``Angle``: degrees from the image's +x axis to
the major axis, counter-clockwise AS SEEN ON SCREEN (y points down in the image, so a positive
angle tilts the major axis towards the top of the image). ImageJ's pixel ``(i, j)`` covers
``[i, i + 1) × [j, j + 1)``, so the centre of the top-left pixel is ``(0.5, 0.5)``.

OpenCV (``cv2.ellipse``, ``cv2.fitEllipse``: a ``RotatedRect`` ``((cx, cy), (w, h), angle)``)
puts pixel centres on integer coordinates, gives full side lengths, and rotates the first side
``w`` by ``angle`` degrees from +x towards +y, i.e. CLOCKWISE on screen. Hence
:meth:`ImageJEllipse.to_opencv`: centre − 0.5 px, ``w = major``, ``h = minor``, angle negated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: An OpenCV ``RotatedRect``: ``((cx, cy), (width, height), angle_deg)``, px and degrees.
RotatedRect = tuple[tuple[float, float], tuple[float, float], float]


@dataclass(frozen=True)
class ImageJEllipse:
    """One ellipse as ImageJ reports it (see the module docstring)."""

    cx: float  # px, ImageJ "X": centre, pixel (0, 0) spans [0, 1)
    cy: float  # px, ImageJ "Y": centre, y pointing down (not "Invert Y coordinates")
    major: float  # px, FULL length of the major axis (> 0)
    minor: float  # px, FULL length of the minor axis (> 0)
    angle_deg: float  # degrees, +x to the major axis, counter-clockwise on screen

    @property
    def analytic_area_px(self) -> float:
        """``π · major · minor / 4``, px² (the axes are full lengths)."""
        return math.pi * self.major * self.minor / 4.0

    def to_opencv(self) -> RotatedRect:
        """The same ellipse as an OpenCV ``RotatedRect`` (for ``cv2.ellipse``)."""
        return (self.cx - 0.5, self.cy - 0.5), (self.major, self.minor), -self.angle_deg


def rasterise(box: RotatedRect, shape: tuple[int, int]) -> np.ndarray:
    """The pixels whose CENTRE lies inside the ellipse ``box`` (OpenCV convention).

    The pixel-centre rule is the rule of the exact masks of rendered sessions; its pixel count
    matches ``π·w·h/4`` to within the boundary's quantisation. (``cv2.ellipse(..., -1)`` fills
    every pixel its outline touches: about half a pixel more all around, +4 % for a 40 px
    ellipse, which would count as an area error of the method.)

    Args:
        box: ``((cx, cy), (w, h), angle_deg)``; full side lengths, angle clockwise on screen.
        shape: ``(H, W)`` of the frame, px.

    Returns:
        ``(H, W)`` bool mask.
    """
    (cx, cy), (w, h), angle = box
    a, b, t = w / 2.0, h / 2.0, math.radians(angle)
    c, s = math.cos(t), math.sin(t)
    ex, ey = math.hypot(a * c, b * s), math.hypot(a * s, b * c)  # half extents along x, y
    x0, x1 = max(0, math.floor(cx - ex)), min(shape[1], math.ceil(cx + ex) + 1)
    y0, y1 = max(0, math.floor(cy - ey)), min(shape[0], math.ceil(cy + ey) + 1)
    mask = np.zeros(shape, dtype=bool)
    if x0 >= x1 or y0 >= y1:
        return mask  # entirely outside the frame
    ys, xs = np.mgrid[y0:y1, x0:x1]
    dx, dy = xs - cx, ys - cy
    u = dx * c + dy * s  # along the first side
    v = -dx * s + dy * c
    mask[y0:y1, x0:x1] = (u / a) ** 2 + (v / b) ** 2 <= 1.0
    return mask

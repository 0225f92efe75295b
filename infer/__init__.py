"""contactcal.infer: the deployable core (numpy, OpenCV, onnxruntime; never torch or mitsuba)."""

from __future__ import annotations

__version__ = "0.1.0"

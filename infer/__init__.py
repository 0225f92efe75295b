"""contactcal.infer: the deployable core (numpy, OpenCV, onnxruntime; never torch or mitsuba).

``__version__`` is the installed distribution's version (single source: ``pyproject.toml``).
``contactcal`` itself is a namespace over the role folders, so it has no ``__version__``; use
this one or ``contactcal --version``.
"""

from __future__ import annotations

from importlib.metadata import version

__version__ = version("contactcal")

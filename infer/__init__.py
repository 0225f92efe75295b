"""contactcal.infer: the deployable core (numpy, OpenCV, onnxruntime; never torch or mitsuba).

``__version__`` is the installed distribution's version (single source: ``pyproject.toml``),
looked up on first use (``importlib.metadata`` costs ~10-15 ms of every command's start-up).
``contactcal`` itself is a namespace over the role folders, so it has no ``__version__``; use
this one or ``contactcal --version``.
"""

from __future__ import annotations


def __getattr__(name: str) -> str:
    """``__version__`` from the installed distribution's metadata, on first use (PEP 562).

    Raises:
        AttributeError: any other name, or ``__version__`` of a source tree that was never
            installed (no distribution metadata to read it from).
    """
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("contactcal")
        except PackageNotFoundError as exc:
            raise AttributeError(
                "contactcal is not installed, so it has no version: `pip install -e .` in the "
                "checkout"
            ) from exc
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

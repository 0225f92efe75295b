"""Where the bundled example session lives."""

from __future__ import annotations

from pathlib import Path

from contactcal.infer.errors import RunError

#: The example session folder (in the source tree; present in editable installs).
EXAMPLE_SESSION = Path(__file__).resolve().parents[2] / "examples" / "session"


def example_manifest() -> Path:
    """Path of the example session's ``manifest.csv``.

    Raises:
        RunError: the example session is not present (e.g. a wheel install without the source
            tree); run ``contactcal calibrate`` on your own manifest instead.
    """
    path = EXAMPLE_SESSION / "manifest.csv"
    if not path.is_file():
        raise RunError(
            f"example session not found at {path}; it ships with the source tree "
            "(install with `pip install -e .` from a clone) or calibrate your own manifest",
            code=2,
        )
    return path

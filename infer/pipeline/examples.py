"""Where the bundled example session lives."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from contactcal.infer.errors import RunError

#: The example session folder: package data of ``contactcal.examples`` (the repository's
#: ``examples/``), in wheels and editable installs alike (installed packages are folders on disk).
EXAMPLE_SESSION = Path(str(resources.files("contactcal.examples").joinpath("session")))


def example_manifest() -> Path:
    """Path of the example session's ``manifest.csv``.

    Raises:
        RunError: the example session is missing from the installation (a damaged install);
            reinstall contactcal, or run ``contactcal calibrate`` on your own manifest.
    """
    path = EXAMPLE_SESSION / "manifest.csv"
    if not path.is_file():
        raise RunError(
            f"example session not found at {path}; reinstall contactcal "
            "(`pip install --force-reinstall contactcal`) or calibrate your own manifest",
            code=2,
        )
    return path

"""Errors shared by the command-line tools, and the check that names a missing extra."""

from __future__ import annotations

import importlib.util


class RunError(Exception):
    """A run that cannot produce a result although its input was valid; ``code`` = exit status."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


def require_extra(command: str, extra: str, modules: tuple[str, ...]) -> None:
    """Check that an optional extra is installed, without importing it.

    Args:
        command: the subcommand, for the message (e.g. ``"synth"``).
        extra: the extra of ``pyproject.toml`` that provides ``modules`` (e.g. ``"synth"``).
        modules: top-level modules the command needs (e.g. ``("mitsuba", "drjit")``).

    Raises:
        ValueError: one line naming the missing modules and the ``pip install`` that adds them
            (exit 2 through the CLI).
    """
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise ValueError(
            f"`contactcal {command}` needs the {extra!r} extra (missing module(s): "
            f"{', '.join(missing)}); install it with: pip install 'contactcal[{extra}]'"
        )

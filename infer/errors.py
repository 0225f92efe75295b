"""Errors shared by the command-line tools, the check that names a missing extra, an error that
names its option, and the listing of a few names in a message."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Sequence


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


def option_error(option: str, value: object, exc: Exception) -> ValueError:
    """``exc`` as an error that names the option it is about: ``OPTION VALUE: message``; a
    message that starts with the value itself (a path check's ``PATH: ...``), or with a path
    value made absolute (as :meth:`~contactcal.infer.files.atomic.OutputSet.stage` names it),
    does not repeat it.

    Example: ``raise option_error("--out", out, exc) from None``.
    """
    message = str(exc)
    shown = [str(value)]
    if isinstance(value, str | os.PathLike):
        shown.append(os.path.abspath(value))
    for prefix in (f"{s}: " for s in shown):
        if message.startswith(prefix):
            message = message.removeprefix(prefix)
            break
    return ValueError(f"{option} {value}: {message}")


def few(names: Sequence[str], limit: int = 3, sep: str = ", ") -> str:
    """Up to ``limit`` names joined by ``sep``, then how many more (``"none"`` for none).

    With ``", "`` it reads ``a, b, c and 2 more``; with ``"; "`` (names that hold commas)
    ``a; b; c; and 2 more``.
    """
    if not names:
        return "none"
    rest = len(names) - limit
    more = f"{sep.rstrip().rstrip(',')} and {rest} more" if rest > 0 else ""
    return sep.join(names[:limit]) + more

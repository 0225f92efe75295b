"""Errors shared by the command-line tools, the check that names a missing extra, an error that
names its option, and the listing of a few names (or changed config keys) in a message."""

from __future__ import annotations

import importlib.util
import json
import os
from collections.abc import Mapping, Sequence
from typing import Any


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


def _flat(record: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"render": {"spp": 1}}`` → ``{"render.spp": 1}``."""
    out: dict[str, Any] = {}
    for key, value in record.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


_NONE = object()  # a key one of two configs lacks


def _shown(value: Any) -> str:
    """A config value in a message: JSON, at most 40 characters."""
    text = "(none)" if value is _NONE else json.dumps(value)
    return text if len(text) <= 40 else text[:39] + "…"


def config_changes(old: Mapping[str, Any], new: Mapping[str, Any], limit: int | None = 4) -> str:
    """The keys of two (nested) configs that differ, old → new, for a refused resume.

    Args:
        old: the recorded config (nested dicts).
        new: this run's.
        limit: keys named before the rest are counted (None: every key named).

    Returns:
        e.g. ``render.spp: 1 → 4; seed: 0 → 9`` (values as JSON, at most 40 characters).
    """
    was, now = _flat(old), _flat(new)
    keys = sorted(k for k in was.keys() | now.keys() if was.get(k, _NONE) != now.get(k, _NONE))
    shown = [f"{k}: {_shown(was.get(k, _NONE))} → {_shown(now.get(k, _NONE))}" for k in keys]
    return few(shown, len(shown) if limit is None else limit, "; ")

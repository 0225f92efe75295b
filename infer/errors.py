"""Errors shared by the command-line tools."""

from __future__ import annotations


class RunError(Exception):
    """A run that cannot produce a result although its input was valid; ``code`` = exit status."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code

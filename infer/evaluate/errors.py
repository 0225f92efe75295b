"""The error of unusable hand labels (``contactcal evaluate``)."""

from __future__ import annotations


class LabelError(ValueError):
    """Unusable labels; the message names the file and says what was expected."""

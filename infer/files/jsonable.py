"""Plain-JSON conversion of result values (numpy scalars and arrays, paths; NaN/inf → None) and
the one JSON text form of outputs."""

from __future__ import annotations

import json
import math
import os
from typing import Any

import numpy as np


def finite_or_none(x: Any) -> float | None:
    """``float(x)``, or None for None, NaN and inf."""
    if x is None:
        return None
    v = float(x)
    return v if math.isfinite(v) else None


def jsonable(obj: Any) -> Any:
    """Plain JSON types; NaN/inf become None, numpy and Path values are converted."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return finite_or_none(obj)
    if obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    return str(obj)


def json_text(obj: Any, ensure_ascii: bool = True) -> str:
    """``obj`` as indented JSON text with a final newline; NaN/inf are rejected (ValueError)."""
    return json.dumps(obj, indent=2, ensure_ascii=ensure_ascii, allow_nan=False) + "\n"

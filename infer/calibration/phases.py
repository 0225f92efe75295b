"""Loading and unloading passes of a session: the ``phase`` of each frame.

A rig records a session as a loading pass (pressure rising) and, optionally, an unloading pass
(pressure falling). The phase of a frame is given by the manifest's ``phase`` column or, without
it, read from the row order (:func:`phases_from_order`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

LOADING = "loading"
UNLOADING = "unloading"
PHASES = (LOADING, UNLOADING)
#: How the phases were determined (recorded in ``calibration.json`` as ``phase_source``).
FROM_COLUMN = "phase column"
FROM_ORDER = "row order (rising then falling)"
SINGLE_PASS = "single pass (no phase column; rows not rising then falling)"


def parse_phase(cell: str) -> str | None:
    """``"loading"`` / ``"unloading"`` from a cell (case-insensitive, spaces ignored), or None."""
    value = cell.strip().lower()
    return value if value in PHASES else None


def phases_from_order(pressures_kpa: Sequence[float]) -> tuple[list[str], str]:
    """Each row's phase from the row order, and how it was determined.

    Rule: when the pressures rise (non-decreasing, >= 2 distinct values up to the maximum) and
    then fall (non-increasing after the last row at the maximum, at least one row), the rows
    after the last row at the maximum are the unloading pass and the others the loading pass.
    Any other order (e.g. rows in no particular order, or only falling) is one loading pass.

    Args:
        pressures_kpa: ``(N,)`` pressures in row order, kPa.

    Returns:
        ``(phases, source)``: one phase per row, and :data:`FROM_ORDER` or :data:`SINGLE_PASS`.
    """
    p = list(pressures_kpa)
    single = [LOADING] * len(p)
    if not p:
        return single, SINGLE_PASS
    top = max(p)
    last = max(i for i, v in enumerate(p) if v == top)
    rise, fall = p[: last + 1], p[last + 1 :]
    rising = all(a <= b for a, b in itertools.pairwise(rise)) and len(set(rise)) >= 2
    falling = all(a >= b for a, b in itertools.pairwise(fall))
    if not (fall and rising and falling):
        return single, SINGLE_PASS
    return [LOADING] * len(rise) + [UNLOADING] * len(fall), FROM_ORDER

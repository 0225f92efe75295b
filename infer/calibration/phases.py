"""Loading and unloading passes of a session: the ``phase`` of each frame.

A rig records a session as a loading pass (pressure rising) and, optionally, an unloading pass
(pressure falling). The phase of a frame is given by the manifest's ``phase`` column or, without
it, read from the row order (:func:`phases_from_order`).
"""

from __future__ import annotations

import bisect
import itertools
import statistics
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


def phases_from_order(
    pressures_kpa: Sequence[float], slack_kpa: float = 0.0
) -> tuple[list[str], str]:
    """Each row's phase from the row order, and how it was determined.

    Rule: when the pressures rise (non-decreasing, >= 2 distinct values up to the maximum) and
    then fall (non-increasing after the last row at the maximum, at least one row), the rows
    after the last row at the maximum are the unloading pass and the others the loading pass.
    Any other order (e.g. rows in no particular order, or only falling) is one loading pass.
    With ``slack_kpa`` > 0, "non-decreasing" allows a row up to it below the highest row so
    far, "non-increasing" up to it above the lowest one, and "at the maximum" up to it below
    (gauge readings of one held step that straddle a step boundary).

    Args:
        pressures_kpa: ``(N,)`` pressures in row order, kPa.
        slack_kpa: kPa, >= 0 (see above; :func:`order_slack`).

    Returns:
        ``(phases, source)``: one phase per row, and :data:`FROM_ORDER` or :data:`SINGLE_PASS`.
    """
    p = list(pressures_kpa)
    single = [LOADING] * len(p)
    if not p:
        return single, SINGLE_PASS
    top = max(p)
    last = max(i for i, v in enumerate(p) if v >= top - slack_kpa)
    rise, fall = p[: last + 1], p[last + 1 :]
    peaks = list(itertools.accumulate(rise, max))[:-1]  # the highest row before each row
    rising = all(b >= a - slack_kpa for a, b in zip(peaks, rise[1:], strict=True))
    rising = rising and len(set(rise)) >= 2
    lows = list(itertools.accumulate(fall, min))[:-1]
    falling = all(b <= a + slack_kpa for a, b in zip(lows, fall[1:], strict=True))
    if not (fall and rising and falling):
        return single, SINGLE_PASS
    return [LOADING] * len(rise) + [UNLOADING] * len(fall), FROM_ORDER


def order_slack(levels_kpa: Sequence[float]) -> float:
    """The slack for :func:`phases_from_order` (kPa): half the median gap between the
    session's consecutive distinct step pressures, so that one step's frames straddling a step
    boundary (a few hundredths of a kPa) never read as a reversal, and a step back by half a
    step still does. 0 with fewer than three distinct pressures."""
    distinct = sorted(set(levels_kpa))
    if len(distinct) < 3:
        return 0.0
    gaps = [b - a for a, b in itertools.pairwise(distinct)]
    return 0.5 * statistics.median(gaps)


def misplaced_rows(levels_kpa: Sequence[float]) -> list[int]:
    """The fewest rows (indices) without which the rows rise, then fall (either part may be
    empty): in a manifest read as one pass because its order is neither, these are the rows
    that broke it, e.g. a typo (16 for 6 kPa among 5 and 7).

    Args:
        levels_kpa: ``(N,)`` each row's step pressure in row order, kPa (the steps' pooled
            readings, so that one step's jitter is no reversal).

    Returns:
        Sorted row indices, empty when the rows already rise then fall.
    """
    p = list(levels_kpa)
    n = len(p)
    rise = _longest_rising(p)[1]  # rise[k]: longest rise within rows < k
    fall = _longest_rising(p[::-1])[1][::-1]  # fall[k]: longest fall within rows >= k
    # the split into a rise and a fall keeping most rows; ties: the longer rise
    k = max(range(n, -1, -1), key=lambda j: rise[j] + fall[j])
    kept = set(_longest_rising(p[:k])[0]) | {k + i for i in _longest_rising([-v for v in p[k:]])[0]}
    return [i for i in range(n) if i not in kept]


def _longest_rising(values: Sequence[float]) -> tuple[list[int], list[int]]:
    """A longest non-decreasing subsequence of ``values`` (patience sorting, O(N log N)).

    Returns:
        Its indices (ascending), and ``(N + 1,)`` lengths: ``[k]`` that of such a
        subsequence among the first ``k`` values.
    """
    tails: list[float] = []  # the smallest tail value of a rising run of each length
    tail_at: list[int] = []  # its index
    before = [-1] * len(values)
    lengths = [0]
    for i, v in enumerate(values):
        j = bisect.bisect_right(tails, v)
        before[i] = tail_at[j - 1] if j > 0 else -1
        if j == len(tails):
            tails.append(v)
            tail_at.append(i)
        else:
            tails[j], tail_at[j] = v, i
        lengths.append(len(tails))
    out, i = [], tail_at[-1] if tail_at else -1
    while i >= 0:
        out.append(i)
        i = before[i]
    return out[::-1], lengths

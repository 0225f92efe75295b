"""Markdown tables of ``contactcal bench``'s report."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

#: Markdown table columns: (key, header, shown as %).
Columns = Sequence[tuple[str, str, bool]]


def _fmt(v: object, pct: bool = False) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{100 * v:.1f} %" if pct else f"{v:.3g}"
    return str(v)


def md_table(rows: Sequence[Mapping[str, Any]], cols: Columns) -> str:
    """A Markdown table of ``rows`` (missing keys show as "–")."""
    head = "| " + " | ".join(c[1] for c in cols) + " |"
    sep = "|" + "---|" * len(cols)
    body = ["| " + " | ".join(_fmt(r.get(key), pct) for key, _, pct in cols) + " |" for r in rows]
    return "\n".join([head, sep, *body])

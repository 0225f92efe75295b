"""Valid JSON syntax that Python's ``json`` cannot read: each input reader must refuse it in one
line naming the input, as it refuses invalid JSON."""

from __future__ import annotations

#: By what each text exceeds: an integer over Python's digit limit (4300), nesting deeper than
#: its recursion limit.
UNREADABLE_JSON = {
    "digits": '{"a": ' + "9" * 5000 + "}",
    "nesting": "[" * 200_000 + "]" * 200_000,
}

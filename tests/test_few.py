"""The one listing of a few names in a message (``contactcal.infer.errors.few``), which the core,
``synth`` and ``train`` share: ``a, b, c and 2 more``, or with ``"; "`` ``a; b; c; and 2 more``."""

from __future__ import annotations

from contactcal.infer.calibration.provenance import identical_frames_warning
from contactcal.infer.errors import few


def test_few_names_a_few_then_counts_the_rest() -> None:
    assert few([]) == "none"
    assert few(["a", "b", "c"]) == "a, b, c"
    assert few(["a", "b", "c", "d", "e"]) == "a, b, c and 2 more"
    assert few(["a", "b", "c", "d"], 2, "; ") == "a; b; and 2 more"
    assert few(["a, x", "b"], 5, "; ") == "a, x; b"


def test_a_warning_lists_through_it() -> None:
    group = {"sha256": "0", "files": ["f0.jpg", "f1.jpg"], "pressures_kpa": [1.0, 2.0]}
    text = identical_frames_warning([group] * 5)
    assert text.count("2 frames (f0.jpg … f1.jpg) at 1, 2 kPa") == 3
    assert "at 1, 2 kPa; and 2 more (the record's extra.identical_frames)" in text

"""``contactcal bench`` reads each session's reference frame once where it reads it several ways:
the accuracy path measures it as a frame in the method's own decode, and the robustness suite's
samples of one session share its decode (and ring)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
from procedural import write_dataset
from read_counts import count_reads

from contactcal.infer.bench.accuracy import score_session
from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.bench.robustness import load_samples, sample_rows
from contactcal.infer.image import read as image_read
from contactcal.infer.methods.registry import make_method


@pytest.fixture
def reads(monkeypatch: pytest.MonkeyPatch) -> Counter[Path]:
    """Each image file's reads (of its bytes), by path."""
    return count_reads(monkeypatch, (image_read, "read_file_bytes"))


@pytest.mark.parametrize("name", ["classical", "unet"])
def test_the_accuracy_path_reads_the_reference_once(
    name: str, tmp_path: Path, reads: Counter[Path]
) -> None:
    rows = sorted(
        next(iter(sessions_of(read_index(write_dataset(tmp_path / "d", fingers=1))).values())),
        key=lambda r: r.pressure_kpa,
    )
    scored = score_session(make_method(name, None, threads=1, outline=True), name, rows)
    assert reads[Path(rows[0].frame)] == 1
    assert all(reads[Path(r.frame)] == 1 for r in rows)
    assert scored[0].reference and scored[0].frame == str(rows[0].frame)


def test_the_robustness_samples_of_a_session_share_its_reference(
    tmp_path: Path, reads: Counter[Path]
) -> None:
    data = write_dataset(tmp_path / "d", fingers=1)
    pairs = sample_rows(sessions_of(read_index(data)), 3)
    assert len(pairs) == 3 and len({ref.frame for _, ref in pairs}) == 1
    samples = load_samples(pairs)
    assert reads[Path(pairs[0][1].frame)] == 1
    assert all(s.reference is samples[0].reference for s in samples)
    assert all(s.ring is samples[0].ring for s in samples)

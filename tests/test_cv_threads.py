"""OpenCV's thread count is set for a block and restored, also when the block fails."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import cv2
import pytest

from contactcal.infer.cli import main
from contactcal.infer.image.cv_threads import opencv_threads
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION


@pytest.fixture
def three_threads() -> Iterator[None]:
    """OpenCV at 3 threads (a count no default gives, so a missed restore shows), reset after."""
    before = cv2.getNumThreads()
    cv2.setNumThreads(3)
    assert cv2.getNumThreads() == 3
    yield
    cv2.setNumThreads(before)


def test_set_for_the_block_and_restored(three_threads: None) -> None:
    with opencv_threads(1):
        assert cv2.getNumThreads() == 1
    assert cv2.getNumThreads() == 3
    with pytest.raises(RuntimeError), opencv_threads(1):
        raise RuntimeError("boom")
    assert cv2.getNumThreads() == 3


def test_bad_count_is_refused(three_threads: None) -> None:
    with pytest.raises(ValueError, match="threads must be >= 1, got 0"):
        with opencv_threads(0):
            pass
    assert cv2.getNumThreads() == 3


def test_measure_runs_opencv_on_its_threads(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, three_threads: None
) -> None:
    seen: list[int] = []
    real = cv2.setNumThreads
    monkeypatch.setattr(cv2, "setNumThreads", lambda n: (seen.append(n), real(n)))
    frame = sorted(EXAMPLE_SESSION.glob("p*.jpg"))[5]
    out = tmp_path / "r.json"
    assert main(["measure", str(frame), "--method", "classical", "--out", str(out)]) == 0
    assert seen == [1, 3]  # --threads' default for the command, then restored
    assert main(["measure", str(frame), "--threads", "2", "--out", str(tmp_path / "s.json")]) == 0
    assert seen[2:] == [2, 3] and cv2.getNumThreads() == 3

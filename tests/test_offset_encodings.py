"""``contactcal boundary-offset`` counts a session once also when its frames come in two
encodings: the same captures as JPEG and re-encoded as PNG share no file's bytes, but share their
labels (equal areas at equal pressures), and are refused with both evaluations named."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import pytest

from contactcal.infer.cli import main
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION


def _as_png(dst: Path) -> Path:
    """The example session's frames re-encoded as PNG (its rig.json beside), its manifest."""
    dst.mkdir()
    rows = (EXAMPLE_SESSION / "manifest.csv").read_text(encoding="utf-8").splitlines()
    for row in rows[1:]:
        name = row.split(",")[0]
        image = cv2.imread(str(EXAMPLE_SESSION / name), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(str(dst / Path(name).with_suffix(".png")), image)
    text = "\n".join([rows[0], *(r.replace(".jpg,", ".png,") for r in rows[1:])]) + "\n"
    (dst / "manifest.csv").write_text(text, encoding="utf-8")
    shutil.copy(EXAMPLE_SESSION / "rig.json", dst / "rig.json")
    return dst / "manifest.csv"


def test_one_session_in_two_encodings_is_refused_naming_both(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    masks = str(EXAMPLE_SESSION / "masks")
    manifests = [EXAMPLE_SESSION / "manifest.csv", _as_png(tmp_path / "png")]
    outs = [tmp_path / "jpeg_eval", tmp_path / "png_eval"]
    for manifest, out in zip(manifests, outs, strict=True):
        assert main(["evaluate", str(manifest), "--labels", masks, "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["boundary-offset", *map(str, outs)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert all(str(out / "evaluation.json") in err for out in outs)
    assert "same areas at the same pressures" in err and "counts once" in err


def test_sessions_sharing_a_few_labels_still_pool() -> None:
    """Two sessions of one display whose contact fills the ring at the top pressures can share
    those labels (the ring's interior) by right; one session twice shares all of them."""
    from contactcal.infer.evaluate.identity import check_distinct_labels

    def labels(areas: list[int]) -> set[tuple[float, int]]:
        return {(float(kpa), a) for kpa, a in enumerate(areas, start=3)}

    ring = [9000, 9000, 9000]  # the last three pressures: both fill the ring
    one = {"file": "a/evaluation.json", "labels": labels([100, 400, 900, 2500, 5000, *ring])}
    two = {"file": "b/evaluation.json", "labels": labels([120, 430, 950, 2400, 5100, *ring])}
    check_distinct_labels([one, two])  # 3 of 8 shared: two sessions
    again = {"file": "c/evaluation.json", "labels": set(one["labels"])}
    with pytest.raises(ValueError, match="a/evaluation.json and c/evaluation.json: 8 frames"):
        check_distinct_labels([one, two, again])

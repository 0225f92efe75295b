"""``contactcal evaluate`` checks every label against its frame before it measures any frame:
a mask of another size than its frame is refused up front, naming the mask and both sizes."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.cli import main
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION
from contactcal.infer.pipeline.options import MeasureOptions

MANIFEST = EXAMPLE_SESSION / "manifest.csv"


def test_mask_of_another_size_is_refused_before_any_frame_is_measured(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def measured(*_: object, **__: object) -> None:
        raise AssertionError("a frame was measured before the labels were checked")

    monkeypatch.setattr(MeasureOptions, "measure", measured)
    masks = tmp_path / "masks"
    shutil.copytree(EXAMPLE_SESSION / "masks", masks)
    bad = masks / "p10.0kpa.png"
    h, w = cv2.imread(str(bad), cv2.IMREAD_GRAYSCALE).shape
    small = np.zeros((h // 2, w // 2), np.uint8)
    small[h // 8 : h // 4, w // 8 : w // 4] = 255
    cv2.imwrite(str(bad), small)
    out = tmp_path / "out"
    args = ["evaluate", str(MANIFEST), "--labels", str(masks), "--out", str(out)]
    assert main([*args, "--method", "classical"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert str(bad) in err and f"{w // 2}×{h // 2} px" in err and f"{w}×{h} px" in err
    assert not out.exists()

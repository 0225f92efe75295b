"""One shrink decision for deployment and training: large renders reach the network as a rig
frame decoded at 1/k does."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from procedural import write_dataset, write_png

torch = pytest.importorskip("torch")

from contactcal.infer.bench.dataset import read_datasets  # noqa: E402
from contactcal.infer.image.read import load_image  # noqa: E402
from contactcal.infer.methods.unet.config import PreprocessConfig  # noqa: E402
from contactcal.infer.methods.unet.shrink import deployed_shrink, fitting_reduction  # noqa: E402
from contactcal.train.data import build_cache  # noqa: E402
from contactcal.train.sessions import session_inputs  # noqa: E402

CFG = PreprocessConfig(input_size=32, ridge_work_px=48)
K = 4


def _upscaled(src: Path, dst: Path, k: int) -> Path:
    """A copy of dataset ``src`` with every frame and mask repeated k × k (areas × k²)."""
    with (src / "index.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for key in ("frame", "mask"):
            img = load_image(src / r[key])
            (dst / r[key]).parent.mkdir(parents=True, exist_ok=True)
            write_png(str(dst / r[key]), np.kron(img, np.ones((k, k), np.uint8)))
        r["area_px"] = str(int(r["area_px"]) * k * k)
        r["width"], r["height"] = str(int(r["width"]) * k), str(int(r["height"]) * k)
    with (dst / "index.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return dst


def test_fitting_reduction_reference_values() -> None:
    assert fitting_reduction(1880.0, (1944, 2592), PreprocessConfig(input_size=192)) == 8
    assert fitting_reduction(940.0, (972, 1296), PreprocessConfig(input_size=192)) == 4
    assert fitting_reduction(280.0, (300, 400), PreprocessConfig(input_size=192)) == 1
    assert fitting_reduction(940.0, (970, 1296), PreprocessConfig(input_size=192)) == 2  # 970 % 4
    assert fitting_reduction(0.0, (972, 1296), PreprocessConfig(input_size=192)) == 1


def test_training_cache_shrinks_like_deployment(tmp_path: Path) -> None:
    small = write_dataset(tmp_path / "small", fingers=2)
    big = _upscaled(small, tmp_path / "big", K)
    rows_s, rows_b = read_datasets([small]), read_datasets([big])
    assert {s.shrink for s in session_inputs(rows_s, CFG).values()} == {1}
    first = load_image(rows_b[0].frame)
    assert deployed_shrink(first, CFG) == K
    assert {s.shrink for s in session_inputs(rows_b, CFG).values()} == {K}
    a = build_cache(rows_s, CFG, 3)
    b = build_cache(rows_b, CFG, 3)
    assert torch.equal(a.x, b.x) and torch.equal(a.y, b.y)
    assert b.shapes == a.shapes and b.boxes == a.boxes
    assert np.allclose(b.area_px.numpy(), a.area_px.numpy())  # in pixels of the shrunk frame
    assert float(a.area_px.sum()) > 0


def test_mask_of_another_size_is_named(tmp_path: Path) -> None:
    big = _upscaled(write_dataset(tmp_path / "small", fingers=1), tmp_path / "big", K)
    rows = read_datasets([big])
    write_png(str(rows[-1].mask), np.zeros((48, 64), np.uint8))
    with pytest.raises(ValueError, match=r"p14\.0kpa\.png: mask shape \(48, 64\) differs"):
        build_cache(rows, CFG, 3)

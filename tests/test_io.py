"""Image loading into the canonical (H, W) uint8 form."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.image.gray import ImageError, to_gray_u8
from contactcal.infer.image.read import load_image


def _write(path: Path, img: np.ndarray) -> Path:
    assert cv2.imwrite(str(path), img)
    return path


@pytest.mark.parametrize("suffix", [".png", ".jpg", ".tif", ".bmp"])
def test_formats_load_to_canonical(tmp_path: Path, suffix: str) -> None:
    img = np.full((30, 40), 100, np.uint8)
    out = load_image(_write(tmp_path / f"a{suffix}", img))
    assert out.shape == (30, 40) and out.dtype == np.uint8
    assert abs(int(out.mean()) - 100) <= 1


def test_16bit_rgb_rgba_and_gray_agree(tmp_path: Path) -> None:
    g8 = np.tile(np.arange(0, 250, 5, dtype=np.uint8), (10, 1))
    g16 = g8.astype(np.uint16) * 257
    bgr = np.dstack([g8, g8, g8])
    bgra = np.dstack([g8, g8, g8, np.full_like(g8, 7)])
    a = load_image(_write(tmp_path / "g8.png", g8))
    b = load_image(_write(tmp_path / "g16.png", g16))
    c = load_image(_write(tmp_path / "c.png", bgr))
    d = load_image(_write(tmp_path / "d.png", bgra))
    e = load_image(_write(tmp_path / "e.tif", np.dstack([g16, g16, g16])))
    for other in (b, c, d, e):
        np.testing.assert_array_equal(a, other)


def test_colour_uses_luma(tmp_path: Path) -> None:
    bgr = np.zeros((4, 4, 3), np.uint8)
    bgr[..., 2] = 255  # pure red in BGR order
    assert int(load_image(_write(tmp_path / "r.png", bgr))[0, 0]) == 76  # 0.299 * 255


def test_reduced_decode(tmp_path: Path) -> None:
    img = np.full((64, 96), 80, np.uint8)
    for suffix in (".jpg", ".png"):
        out = load_image(_write(tmp_path / f"r{suffix}", img), reduce=4)
        assert out.shape == (16, 24)


@pytest.mark.parametrize(
    ("content", "match"),
    [(b"", "empty file"), (b"not an image at all", "not a decodable image|truncated")],
)
def test_bad_files(tmp_path: Path, content: bytes, match: str) -> None:
    path = tmp_path / "bad.png"
    path.write_bytes(content)
    with pytest.raises(ImageError, match=match) as info:
        load_image(path)
    assert "bad.png" in str(info.value)


def test_missing_and_truncated(tmp_path: Path) -> None:
    with pytest.raises(ImageError, match="no such file"):
        load_image(tmp_path / "missing.png")
    img = np.random.default_rng(0).integers(0, 255, (50, 50), dtype=np.uint8)
    for suffix in (".png", ".jpg"):
        full = _write(tmp_path / f"t{suffix}", img).read_bytes()
        cut = tmp_path / f"cut{suffix}"
        cut.write_bytes(full[: len(full) // 2])
        with pytest.raises(ImageError, match="truncated|decodable"):
            load_image(cut)
    with pytest.raises(ImageError, match="unsupported image type"):
        load_image(tmp_path / "x.gif")
    with pytest.raises(ImageError, match="not a file"):
        load_image(_dir_png(tmp_path))


def _dir_png(tmp_path: Path) -> Path:
    d = tmp_path / "folder.png"
    d.mkdir()
    return d


def test_arrays() -> None:
    assert to_gray_u8(np.ones((3, 3), np.float32))[0, 0] == 255
    assert to_gray_u8(np.ones((3, 3), bool))[0, 0] == 255
    assert to_gray_u8(np.zeros((3, 3, 1), np.uint8)).shape == (3, 3)
    with pytest.raises(ImageError, match="NaN or inf"):
        to_gray_u8(np.array([[0.1, np.nan]], np.float32), name="frame7")
    with pytest.raises(ImageError, match=r"expected \(H, W\)"):
        to_gray_u8(np.zeros((2, 2, 2), np.uint8))
    with pytest.raises(ImageError, match="empty image"):
        to_gray_u8(np.zeros((0, 5), np.uint8))
    with pytest.raises(ImageError, match="expected uint8"):
        to_gray_u8(np.zeros((2, 2), np.int64))

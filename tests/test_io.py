"""Image loading into the canonical (H, W) uint8 form."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.image.gray import ImageError, to_gray_u8
from contactcal.infer.image.read import load_image

EXAMPLE_FRAME = Path(__file__).resolve().parents[1] / "examples" / "session" / "p12.0kpa.jpg"


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
    g8 = np.tile(np.arange(0, 250, 5, dtype=np.uint8), (20, 1))
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
    bgr = np.zeros((16, 16, 3), np.uint8)
    bgr[..., 2] = 255  # pure red in BGR order
    assert int(load_image(_write(tmp_path / "r.png", bgr))[0, 0]) == 76  # 0.299 * 255


def test_reduced_decode(tmp_path: Path) -> None:
    img = np.full((64, 96), 80, np.uint8)
    for suffix in (".jpg", ".png"):
        out = load_image(_write(tmp_path / f"r{suffix}", img), reduce=4)
        assert out.shape == (16, 24)


@pytest.mark.parametrize(
    ("content", "match"),
    [(b"", "empty file"), (b"not an image at all", r"not a PNG file \(its content is not an")],
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
    with pytest.raises(ImageError, match="is a folder; expected an image file"):
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


def _with_sbit(path: Path, bits: int) -> Path:
    """Insert a gray ``sBIT`` chunk right after the PNG's IHDR chunk (8 + 25 bytes)."""
    data = path.read_bytes()
    body = b"sBIT" + bytes([bits])
    chunk = struct.pack(">I", 1) + body + struct.pack(">I", zlib.crc32(body))
    path.write_bytes(data[:33] + chunk + data[33:])
    return path


def _ramp(levels: int) -> np.ndarray:
    """A (20, 64) uint16 ramp 0 .. levels-1 (a camera's N-bit data in the low bits)."""
    return np.tile(np.linspace(0, levels - 1, 64).round().astype(np.uint16), (20, 1))


@pytest.mark.parametrize("bits", [10, 12])
def test_16bit_png_with_fewer_bits(tmp_path: Path, bits: int) -> None:
    full = (1 << bits) - 1
    data = _ramp(full + 1)
    expected = np.rint(data * (255.0 / full)).astype(np.uint8)
    plain = _write(tmp_path / f"p{bits}.png", data)
    with pytest.raises(ImageError, match=rf"p{bits}\.png.*maximum {full}.*--bit-depth"):
        load_image(plain)
    np.testing.assert_array_equal(load_image(plain, bit_depth=bits), expected)
    marked = _with_sbit(_write(tmp_path / f"s{bits}.png", data), bits)
    np.testing.assert_array_equal(load_image(marked), expected)
    np.testing.assert_array_equal(load_image(marked, bit_depth=bits), expected)
    with pytest.raises(ImageError, match="contradicts the file's sBIT chunk"):
        load_image(marked, bit_depth=16)


def test_bit_depth_rules(tmp_path: Path) -> None:
    msb = _with_sbit(_write(tmp_path / "msb.png", _ramp(4096) << 4), 12)  # PNG's own convention
    np.testing.assert_array_equal(load_image(msb), load_image(msb, bit_depth=12))
    assert load_image(msb)[0, -1] == 255
    dark16 = _write(tmp_path / "dark16.png", _ramp(4096))
    assert load_image(dark16, bit_depth=16).max() == round(4095 * 255 / 65535)
    with pytest.raises(ImageError, match="exceeds the 10-bit range"):
        load_image(_write(tmp_path / "w.png", _ramp(4096)), bit_depth=10)
    with pytest.raises(ImageError, match="holds 8-bit samples"):
        load_image(_write(tmp_path / "e.jpg", np.full((30, 40), 9, np.uint8)), bit_depth=12)
    with pytest.raises(ValueError, match="1-16"):
        load_image(dark16, bit_depth=17)


@pytest.mark.parametrize("bits", [6, 8, 12])
def test_bit_depth_is_refused_for_8bit_files(tmp_path: Path, bits: int) -> None:
    """--bit-depth 6 brightened an 8-bit file 4-fold; 8-bit samples are full range."""
    dark = _write(tmp_path / "dark8.png", np.full((30, 40), 50, np.uint8))
    with pytest.raises(ImageError, match=rf"dark8\.png: --bit-depth {bits} .*8-bit samples"):
        load_image(dark, bit_depth=bits)
    assert load_image(dark).max() == 50


@pytest.mark.parametrize("sbit", [6, 7])
def test_an_8bit_png_is_full_range_whatever_its_sbit_chunk(tmp_path: Path, sbit: int) -> None:
    """An sBIT chunk of 6 bits brightened a dark 8-bit frame 4-fold (7 bits: 2-fold), a brighter
    one not; PNG scales the source's bits to the full 8, so the chunk changes nothing. A
    --bit-depth equal to the chunk's got past the refusal of the option for 8-bit files."""
    dark = _with_sbit(_write(tmp_path / "dark8.png", np.full((30, 40), 50, np.uint8)), sbit)
    assert load_image(dark).max() == 50
    with pytest.raises(ImageError, match=rf"dark8\.png: --bit-depth {sbit} .*8-bit samples"):
        load_image(dark, bit_depth=sbit)


def test_float_tiff_range(tmp_path: Path) -> None:
    ramp = np.tile(np.linspace(0.0, 1.0, 64, dtype=np.float32), (20, 1))
    out = load_image(_write(tmp_path / "unit.tif", ramp))
    np.testing.assert_array_equal(out, np.rint(ramp * 255).astype(np.uint8))
    with pytest.raises(
        ImageError, match=r"f255\.tif.*\[0, 255\].*expected intensities in \[0, 1\]"
    ):
        load_image(_write(tmp_path / "f255.tif", ramp * 255))
    with pytest.raises(ImageError, match=r"span \[-0\.5"):
        to_gray_u8(ramp - 0.5)


@pytest.mark.parametrize(("h", "w"), [(3, 1990), (1990, 3), (15, 40), (20, 90)])
def test_images_that_are_no_rig_frame(tmp_path: Path, h: int, w: int) -> None:
    path = _write(tmp_path / "strip.png", np.full((h, w), 120, np.uint8))
    with pytest.raises(ImageError, match=rf"strip\.png: {w}×{h} px is not a rig frame"):
        load_image(path)


def test_smallest_frames_accepted(tmp_path: Path) -> None:
    assert load_image(_write(tmp_path / "a.png", np.zeros((16, 64), np.uint8))).shape == (16, 64)
    assert load_image(_write(tmp_path / "b.png", np.zeros((29, 37), np.uint8))).shape == (29, 37)


@pytest.mark.parametrize(("src", "named"), [(".jpg", ".png"), (".png", ".jpg"), (".bmp", ".tif")])
def test_content_of_another_type_than_the_suffix(tmp_path: Path, src: str, named: str) -> None:
    """A JPEG named .png was called a truncated PNG; the message now says what the file is."""
    real = _write(tmp_path / f"frame{src}", np.full((32, 48), 90, np.uint8))
    wrong = tmp_path / f"renamed{named}"
    wrong.write_bytes(real.read_bytes())
    with pytest.raises(ImageError, match=rf"renamed\{named}: not a .* file \(its content is a"):
        load_image(wrong)
    assert load_image(real).shape == (32, 48)


def _with_thumbnail(jpeg: bytes) -> bytes:
    """``jpeg`` with an APP1 segment holding a whole small JPEG (an EXIF thumbnail's EOI)."""
    ok, thumb = cv2.imencode(".jpg", np.full((8, 8), 128, np.uint8))
    assert ok
    body = b"Exif\x00\x00" + thumb.tobytes()
    return jpeg[:2] + b"\xff\xe1" + (len(body) + 2).to_bytes(2, "big") + body + jpeg[2:]


@pytest.mark.parametrize("suffix", [".png", ".jpg", "progressive.jpg"])
def test_data_after_the_image_is_not_a_truncation(tmp_path: Path, suffix: str) -> None:
    """A Raspberry Pi camera appends its raw Bayer data after the JPEG's end marker: such a
    file was refused as truncated (the marker was looked for in the last 64 bytes only)."""
    img = np.random.default_rng(1).integers(0, 255, (48, 64), dtype=np.uint8)
    params = [cv2.IMWRITE_JPEG_PROGRESSIVE, 1] if suffix.startswith("progressive") else []
    ok, enc = cv2.imencode(suffix[-4:], img, params)
    assert ok
    full = enc.tobytes()
    if suffix.endswith(".jpg"):
        full = _with_thumbnail(full)
    trailer = b"BRCM" + np.random.default_rng(2).bytes(4096) + b"\xff\xd8\xff\xe0"
    path = tmp_path / f"raw{suffix[-4:]}"
    path.write_bytes(full + trailer)
    np.testing.assert_array_equal(load_image(path), cv2.imdecode(enc, cv2.IMREAD_GRAYSCALE))
    # cut inside the image: still refused, although the file now holds an end marker in its
    # thumbnail (JPEG) and the trailer follows a damaged body
    for cut in (full[: len(full) // 2], full[: len(full) - 2]):
        path.write_bytes(cut)
        with pytest.raises(ImageError, match="truncated"):
            load_image(path)


def test_arrays_given_to_a_method_are_checked_as_files_are() -> None:
    """Through the Python API a 16-bit array of 12-bit data was read 16 times too dark (no
    ring, area 0), a 3×3 array gave "no contact", and the classical routine measured a frame
    of another size than its reference with the reference's ROI."""
    from contactcal.infer.methods.classical import ClassicalMethod
    from contactcal.infer.methods.unet.method import UnetMethod

    frame = load_image(EXAMPLE_FRAME)
    twelve_bit = np.rint(frame * (4095 / 255)).astype(np.uint16)
    ambiguous = r"frame: uint16 samples with maximum 40.. .<= 16383."
    for method in (ClassicalMethod(), UnetMethod()):
        with pytest.raises(ImageError, match=f"reference {ambiguous}"):
            method.set_reference(twelve_bit)
        method.set_reference(frame)
        with pytest.raises(ImageError, match=f"^{ambiguous}"):
            method.measure(twelve_bit)
        with pytest.raises(ImageError, match="frame: 3×3 px is not a rig frame"):
            method.measure(np.zeros((3, 3), np.uint8))
        full = frame.astype(np.uint16) * 257  # full-range 16-bit: the same frame
        assert method.measure(full).area_px == method.measure(frame).area_px
        with pytest.raises(ImageError, match="reference frame: 1×1 px is not a rig frame"):
            method.set_reference(np.zeros((1, 1), np.uint8))
    classical = ClassicalMethod()
    classical.set_reference(frame)
    h, w = frame.shape
    with pytest.raises(ImageError, match=f"frame: {h}×{w} px, but the reference frame is {w}×{h}"):
        classical.measure(np.ascontiguousarray(frame.T))

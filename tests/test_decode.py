"""Reduced JPEG decoding for the U-Net: chosen only when correct, and areas agree."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.image import read
from contactcal.infer.image.gray import ImageError, reduce_area
from contactcal.infer.image.jpeg import jpeg_size
from contactcal.infer.image.read import ImageFile, load_image
from contactcal.infer.methods.base import Started
from contactcal.infer.methods.classical import ClassicalMethod
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.pipeline.measure import measure_files

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def _upscaled(tmp_path: Path, kpa: int, size: tuple[int, int], ext: str = ".jpg") -> Path:
    img = cv2.imread(str(EXAMPLE / f"p{kpa:04.1f}kpa.jpg"), cv2.IMREAD_COLOR)
    path = tmp_path / f"p{kpa:02d}{ext}"
    assert cv2.imwrite(str(path), cv2.resize(img, size, interpolation=cv2.INTER_CUBIC))
    return path


def test_jpeg_size(tmp_path: Path) -> None:
    assert jpeg_size(_upscaled(tmp_path, 0, (1600, 1200))) == (1200, 1600)
    with pytest.raises(ImageError, match="expected a JPEG file, got PNG"):
        jpeg_size(_upscaled(tmp_path, 0, (64, 48), ".png"))


def test_jpeg_size_reads_other_headers(tmp_path: Path) -> None:
    """Progressive, grey, and with an EXIF segment before the frame header: the stored size."""
    img = cv2.resize(cv2.imread(str(EXAMPLE / "p05.0kpa.jpg")), (203, 117))
    prog = tmp_path / "prog.jpg"
    assert cv2.imwrite(str(prog), img, [cv2.IMWRITE_JPEG_PROGRESSIVE, 1])
    grey = tmp_path / "grey.jpg"
    assert cv2.imwrite(str(grey), img[:, :, 0])
    assert jpeg_size(prog) == jpeg_size(grey) == (117, 203)
    image = pytest.importorskip("PIL.Image")
    exif = image.Exif()
    exif[0x0112] = 6  # orientation "rotate 90": not applied to the stored size
    tagged = tmp_path / "exif.jpg"
    image.fromarray(img).save(tagged, exif=exif)
    data = tagged.read_bytes()
    assert data.index(b"\xff\xe1") < data.index(b"\xff\xc0")  # APP1 before the frame header
    assert jpeg_size(tagged) == (117, 203)


SOF = b"\xff\xc0\x00\x11\x08\x00\x75\x00\xcb"  # baseline frame header: 117 × 203 px


@pytest.mark.parametrize(
    "data",
    [
        b"\xff\xd8" + SOF,
        b"\xff\xd8\xff\xff" + SOF[1:],  # a fill byte before the marker
        b"\xff\xd8\xff\xd0\xff\x01" + SOF,  # standalone markers (RST0, TEM): no length
        b"\xff\xd8\xff\xc4\x00\x04\x00\x00" + SOF,  # a table segment first
    ],
)
def test_jpeg_size_walks_the_markers(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "header.jpg"
    path.write_bytes(data)
    assert jpeg_size(path) == (117, 203)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "no JPEG start-of-image marker"),
        (b"II*\x00rest", "got TIFF"),
        (b"\xff\xd8\xff\xe0\x00\x10JFIF", "header: truncated"),
        (b"\xff\xd8\x00\x00", "header: no marker where one was expected"),
        (b"\xff\xd8\xff\x00", "header: data bytes where a marker was expected"),
        (b"\xff\xd8\xff\xc0\x00\x05\x08\x00\x10", "header: segment FF C0 of length 5"),
        (b"\xff\xd8\xff\xda\x00\x08", "no frame header before the image data"),
        (b"\xff\xd8\xff\xc0\x00\x11\x08\x00\x00\x00\x10", "height 0 in its frame header"),
        (b"\xff\xd8\xff\xc0\x00\x11\x08\x00\x10\x00\x00", "width 0 in its frame header"),
    ],
)
def test_jpeg_size_bad_headers(tmp_path: Path, data: bytes, message: str) -> None:
    path = tmp_path / "bad.jpg"
    path.write_bytes(data)
    with pytest.raises(ImageError, match=message) as info:
        jpeg_size(path)
    assert str(info.value).startswith(f"{path}: ")


def test_jpeg_size_missing_file_or_folder(tmp_path: Path) -> None:
    with pytest.raises(ImageError, match="missing.jpg: no such file"):
        jpeg_size(tmp_path / "missing.jpg")
    (tmp_path / "d.jpg").mkdir()
    with pytest.raises(ImageError, match="d.jpg: is a folder; expected a JPEG file"):
        jpeg_size(tmp_path / "d.jpg")


def test_exif_orientation_is_ignored_at_every_reduction(tmp_path: Path) -> None:
    """A frame tagged "rotate 90" keeps its stored orientation, decoded fully or at 1/k."""
    image = pytest.importorskip("PIL.Image")
    img = np.zeros((64, 128, 3), np.uint8)
    img[:8] = 255  # a bright top band: where it ends up shows the orientation
    tagged = image.fromarray(img)
    exif = tagged.getexif()
    exif[0x0112] = 6
    path = tmp_path / "tagged.jpg"
    tagged.save(path, exif=exif, quality=95)
    assert jpeg_size(path) == (64, 128)
    for k in (1, 2, 4, 8):
        gray = load_image(path, reduce=k)
        assert gray.shape == (64 // k, 128 // k), k
        assert gray[0].mean() > 200 > gray[-1].mean() + 150, k


def test_reduced_decoding_agrees_with_full(tmp_path: Path) -> None:
    ref, frame = _upscaled(tmp_path, 0, (1600, 1200)), _upscaled(tmp_path, 12, (1600, 1200))
    unet = UnetMethod()
    started = unet.start([frame], ImageFile.read(ref))
    assert started.reduction == 4  # crop ≈ 1050 px: 1/4 keeps >= 192 px, 1/8 would not
    # the reference as decoded at 1/4, returned so that the pipeline needs no second decode
    assert np.array_equal(started.reference, load_image(ref, reduce=4))
    fast = measure_files([frame], unet, ref)[0]
    unet.set_reference(load_image(ref))
    full = unet.measure(load_image(frame))
    assert (fast.width, fast.height) == (1600, 1200)
    assert fast.result.area_px == pytest.approx(full.area_px, rel=0.03)


@pytest.mark.parametrize(
    ("method", "size", "reference_decodes"),
    [
        (UnetMethod, (2592, 1944), 1),  # k = 8: the ring search's 1/8 decode is the reference
        (UnetMethod, (1600, 1200), 2),  # k = 4: the ring search at 1/8, then the reference at 1/4
        (ClassicalMethod, (2592, 1944), 1),
    ],
)
def test_the_frame_check_and_its_measurement_decode_no_reference(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    method: type,
    size: tuple[int, int],
    reference_decodes: int,
) -> None:
    ref, frame = _upscaled(tmp_path, 0, size), _upscaled(tmp_path, 12, size)
    decoded: list[str] = []
    strict = read.decode_strict

    def counted(buf: np.ndarray, flag: int, name: str) -> np.ndarray | None:
        decoded.append(Path(name).name)
        return strict(buf, flag, name)

    monkeypatch.setattr(read, "decode_strict", counted)
    # the reference measured as a frame too: its decode for the method is the one measured
    zero, m = measure_files([ref, frame], method(), ref)
    assert m.result.contact and (m.width, m.height) == (zero.width, zero.height) == size
    assert decoded.count(frame.name) == 1, decoded
    assert decoded.count(ref.name) == reference_decodes, decoded


def test_a_start_without_the_reference_image_is_a_protocol_error(tmp_path: Path) -> None:
    ref, frame = _upscaled(tmp_path, 0, (400, 300)), _upscaled(tmp_path, 12, (400, 300))
    method = ClassicalMethod()
    method.start = lambda files, reference, bit_depth=None: Started(1, None)  # type: ignore[method-assign]
    with pytest.raises(TypeError, match=r"classical: start\(\) returned no reference image"):
        measure_files([frame], method, ref)
    assert measure_files([frame], method)[0].reference is None  # none given: none needed


def test_reduction_not_used_when_unsafe(tmp_path: Path) -> None:
    unet = UnetMethod()
    small = _upscaled(tmp_path, 12, (400, 300))
    started = unet.start([small], None)  # crop already near the input size
    assert started.reduction == 1 and started.reference is None  # (== ignores the array)
    odd = _upscaled(tmp_path, 12, (1601, 1201))
    assert unet.start([odd], None).reduction == 1  # not divisible: areas would not scale exactly
    png = _upscaled(tmp_path, 12, (1600, 1200), ".png")
    assert unet.start([png], None).reduction == 1
    ref = _upscaled(tmp_path, 0, (1600, 1200))
    started = ClassicalMethod().start([_upscaled(tmp_path, 5, (1600, 1200))], ImageFile.read(ref))
    assert started.reduction == 1 and np.array_equal(started.reference, load_image(ref))
    assert np.isfinite(measure_files([odd], unet)[0].result.area_px)


def test_reduce_area_averages_blocks() -> None:
    gray = np.arange(48, dtype=np.uint8).reshape(6, 8)
    small = reduce_area(gray, 2)
    assert small.shape == (3, 4) and small.dtype == np.uint8
    assert small[0, 0] == 5 and small[2, 3] == 43  # 2×2 block means, half rounded up
    assert reduce_area(gray, 1) is gray
    with pytest.raises(ValueError, match="k must be >= 1"):
        reduce_area(gray, 0)


def test_decoded_frames_are_shrunk_like_a_reduced_decode(tmp_path: Path) -> None:
    ref, frame = _upscaled(tmp_path, 0, (1600, 1200)), _upscaled(tmp_path, 12, (1600, 1200))
    unet = UnetMethod()
    k = unet.start([frame], ImageFile.read(ref)).reduction
    fast = measure_files([frame], unet, ref)[0].result
    unet.set_reference(load_image(ref))  # decoded at full size: the method shrinks it itself
    assert unet.shrink == k and unet.reference.gray.shape == (1200 // k, 1600 // k)
    full = unet.measure(load_image(frame))
    assert full.area_px == pytest.approx(fast.area_px, rel=0.01)
    alone = UnetMethod()
    alone.set_reference(None)
    assert alone.shrink is None  # no reference: the first frame decides
    assert alone.measure(load_image(frame)).area_px == pytest.approx(fast.area_px, rel=0.03)
    assert alone.shrink == k
    with pytest.raises(ValueError, match="differs from the reference frame size 1600×1200"):
        unet.measure(cv2.resize(load_image(frame), (800, 600)))


def test_shrink_without_a_ring_uses_the_fallback_crop() -> None:
    blank = np.full((1200, 1600), 40, np.uint8)  # no ring anywhere: the fallback crop
    unet = UnetMethod()
    unet.set_reference(blank)
    assert not unet.reference.ring.found
    assert unet.shrink == 4  # fallback crop ~1190 px: 1/4 keeps >= 192 px, 1/8 would not
    result = unet.measure(blank)
    assert not result.contact and result.area_px == 0.0


def _cut_in_half(tmp_path: Path, src: Path = EXAMPLE / "p10.0kpa.jpg") -> Path:
    """The frame cut in half with the end-of-image marker re-added (libjpeg only warns)."""
    data = src.read_bytes()
    path = tmp_path / "cut.jpg"
    path.write_bytes(data[: len(data) // 2] + b"\xff\xd9")
    return path


@pytest.mark.parametrize("reduce", [1, 2, 4, 8])
def test_corrupt_jpeg_is_an_error(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], reduce: int
) -> None:
    cut = _cut_in_half(tmp_path)
    with pytest.raises(ImageError, match=r"cut\.jpg: corrupt image data .*premature end"):
        load_image(cut, reduce=reduce)
    assert load_image(EXAMPLE / "p10.0kpa.jpg", reduce=reduce).size > 0  # clean: no error
    os.write(2, b"still here\n")  # standard error is restored after the capture
    assert capfd.readouterr().err == "still here\n"


def test_corrupt_jpeg_in_a_reduced_session(tmp_path: Path) -> None:
    ref, frame = _upscaled(tmp_path, 0, (1600, 1200)), _upscaled(tmp_path, 12, (1600, 1200))
    cut = _cut_in_half(tmp_path, frame)
    unet = UnetMethod()
    # the U-Net decodes this session at 1/4
    assert unet.start([cut], ImageFile.read(ref)).reduction == 4
    with pytest.raises(ImageError, match="Corrupt JPEG data"):
        measure_files([frame, cut], unet, ref)


def test_header_too_large_for_the_decoder_is_an_error(tmp_path: Path) -> None:
    """A BMP whose header declares 10⁷ px of width: OpenCV's assertion becomes an ImageError
    naming the file (found by tests/test_cli_fuzz.py), not a traceback."""
    import struct

    info = struct.pack("<IiiHHIIiiII", 40, 10**7, 10, 1, 24, 0, 0, 0, 0, 0, 0)
    path = tmp_path / "huge.bmp"
    path.write_bytes(b"BM" + struct.pack("<IHHI", 1358, 0, 0, 54) + info + bytes(1300))
    with pytest.raises(ImageError, match=r"huge\.bmp: the decoder refused the file"):
        load_image(path)

"""Inputs a lab can trust: frames match their reference, and every bad input exits 2 in one line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from unreadable_json import UNREADABLE_JSON

from contactcal.infer.cli import main
from contactcal.infer.image.gray import ImageError
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.classical import ClassicalMethod
from contactcal.infer.methods.registry import METHODS, make_method
from contactcal.infer.pipeline.measure import measure_files
from contactcal.infer.pipeline.scale import PixelScale, RigConfigError, load_rig_config

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
REF, FRAME = EXAMPLE / "p00.0kpa.jpg", EXAMPLE / "p10.0kpa.jpg"


def _gray(kpa: float) -> np.ndarray:
    return load_image(EXAMPLE / f"p{kpa:04.1f}kpa.jpg")


def _png(path: Path, img: np.ndarray) -> Path:
    assert cv2.imwrite(str(path), img)
    return path


def _warped(tmp_path: Path, name: str, shift_px: float = 0.0, zoom: float = 1.0) -> Path:
    """The 10 kPa frame, same size, content shifted right by ``shift_px`` and zoomed by ``zoom``."""
    g = _gray(10)
    h, w = g.shape
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), 0.0, zoom)
    m[0, 2] += shift_px
    return _png(tmp_path / name, cv2.warpAffine(g, m, (w, h), flags=cv2.INTER_LINEAR))


def _exit_2(capsys: pytest.CaptureFixture[str], argv: list[str], *needles: str) -> str:
    """Run the CLI; it must exit 2 with exactly one line on stderr containing ``needles``."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("contactcal: error: ") and err.count("\n") == 1, err
    for needle in needles:
        assert needle in err, err
    return err


@pytest.mark.parametrize("name", METHODS)
def test_frame_of_another_size_than_the_reference(tmp_path: Path, name: str) -> None:
    big = _png(tmp_path / "big_ref.png", cv2.resize(_gray(0), (800, 600)))
    with pytest.raises(ImageError) as info:
        measure_files([FRAME], make_method(name), big)
    msg = str(info.value)
    assert str(FRAME) in msg and str(big) in msg and "400×300 px, the reference 800×600" in msg


@pytest.mark.parametrize(
    ("shift_px", "zoom", "what"),
    [(20.0, 1.0, "ring centre is 15%"), (0.0, 1.15, "ring radius differs")],
)
def test_frame_framed_otherwise_than_the_reference(
    tmp_path: Path, shift_px: float, zoom: float, what: str
) -> None:
    moved = _warped(tmp_path, "moved.png", shift_px, zoom)
    with pytest.raises(ImageError, match=rf"moved\.png: does not match the reference .*{what}"):
        measure_files([FRAME, moved], ClassicalMethod(), REF)


def test_small_moves_within_tolerance_are_accepted(tmp_path: Path) -> None:
    nudged = _warped(tmp_path, "nudged.png", shift_px=2.0)  # ~2 % of the ring radius
    out = measure_files([nudged], ClassicalMethod(), REF)
    assert out[0].result.contact and out[0].result.note == ""


def test_the_example_session_matches_its_reference() -> None:
    frames = sorted(EXAMPLE.glob("p*.jpg"))
    for name in METHODS:
        for m in measure_files(frames, make_method(name), REF):
            assert "ring" not in m.result.note, (name, m.file, m.result.note)


def test_unchecked_ring_position_is_said(tmp_path: Path) -> None:
    dark = _png(tmp_path / "dark.png", np.full((300, 400), 12, np.uint8))
    darker = _png(tmp_path / "darker.png", np.full((300, 400), 8, np.uint8))
    unlit_ref = measure_files([darker], ClassicalMethod(), dark)[0]  # no ring anywhere: noted
    assert "no ring found in the reference dark.png" in unlit_ref.result.note
    with pytest.raises(ImageError, match="dark.png: the reference frame shows no window ring"):
        measure_files([FRAME], ClassicalMethod(), dark)  # a lit frame, a dark reference
    with pytest.raises(ImageError, match="400×300 px, the reference 40×30"):  # size still checked
        measure_files([FRAME], ClassicalMethod(), _png(tmp_path / "s.png", np.zeros((30, 40))))
    unlit_frame = measure_files([dark], ClassicalMethod(), REF)[0]
    assert "no ring found in this frame" in unlit_frame.result.note


def test_cli_reference_mismatch(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    half = _png(tmp_path / "half.png", cv2.resize(_gray(10), (200, 150)))
    out = tmp_path / "r.json"
    for name in METHODS:
        argv = ["measure", str(half), "--reference", str(REF), "--method", name, "--out", str(out)]
        _exit_2(capsys, argv, str(half), str(REF), "200×150 px, the reference 400×300")
    moved = _warped(tmp_path, "moved.png", shift_px=20.0)
    argv = ["measure", str(moved), "--reference", str(REF), "--out", str(out)]
    _exit_2(capsys, argv, str(moved), str(REF), "ring centre")
    assert not out.exists()


def _session_copy(tmp_path: Path) -> Path:
    session = tmp_path / "session"
    shutil.copytree(EXAMPLE, session, ignore=shutil.ignore_patterns("masks", "truth.csv"))
    return session


def test_cli_calibrate_mixed_sizes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    session = _session_copy(tmp_path)
    odd = session / "p12.0kpa.jpg"
    cv2.imwrite(str(odd), cv2.resize(cv2.imread(str(odd)), (200, 150)))
    argv = ["calibrate", str(session / "manifest.csv"), "--method", "classical"]
    _exit_2(capsys, [*argv, "--out", str(tmp_path / "o")], "p12.0kpa.jpg", "p00.0kpa.jpg")
    assert not (tmp_path / "o").exists()


def test_cli_corrupt_jpeg(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = FRAME.read_bytes()
    cut = tmp_path / "cut.jpg"
    cut.write_bytes(data[: len(data) // 2] + b"\xff\xd9")
    out = str(tmp_path / "r.json")
    _exit_2(capsys, ["measure", str(cut), "--reference", str(REF), "--out", out], "cut.jpg")


def test_cli_bit_depth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    g8 = _gray(10)
    p8 = _png(tmp_path / "p8.png", g8)
    g12 = np.rint(g8 * (4095 / 255)).astype(np.uint16)  # a 12-bit camera's data in 16 bits
    p12 = _png(tmp_path / "p12.png", g12)
    out = tmp_path / "r.json"
    base = ["measure", "--method", "unet", "--out", str(out)]
    _exit_2(capsys, [*base, str(p12)], "p12.png", f"maximum {g12.max()}", "--bit-depth")
    _exit_2(capsys, [*base, "--bit-depth", "17", str(p12)], "1-16")
    areas = []
    for argv in ([*base, "--bit-depth", "12", str(p12)], [*base, str(p8)]):
        assert main(argv) == 0
        areas.append(json.loads(out.read_text())[0]["area_px"])
    assert areas[0] == areas[1] > 0
    _exit_2(capsys, [*base, "--bit-depth", "12", str(p8)], "p8.png", "holds 8-bit samples")
    f255 = tmp_path / "f.tif"
    cv2.imwrite(str(f255), g8.astype(np.float32))
    _exit_2(capsys, [*base, str(f255)], "f.tif", "expected intensities in [0, 1]")


def test_cli_manifest_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    session = _session_copy(tmp_path)
    manifest = session / "manifest.csv"
    argv = ["calibrate", str(manifest), "--method", "classical", "--out", str(tmp_path / "o")]
    manifest.write_text("file,pressure_kpa\np00.0kpa.jpg,0\np10.0kpa.jpg,5\np10.0kpa.jpg,10\n")
    _exit_2(capsys, argv, "rows 2", "and 3", "same image file")
    manifest.write_text("file,pressure_kpa\np00.0kpa.jpg,0\np10.0kpa.jpg,1e308\n")
    _exit_2(capsys, argv, "row 2", "above the plausible 100 kPa")
    rows = [f"p{k:04.1f}kpa.jpg,{k * 0.001:g}" for k in (0, 4, 8, 12, 16, 20)]  # MPa
    manifest.write_text("file,pressure_kpa\n" + "\n".join(rows) + "\n")
    _exit_2(capsys, argv, "highest pressure_kpa is 0.02, below 1 kPa", "not bar or MPa")


def test_cli_no_rig_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    strip = _png(tmp_path / "strip.png", cv2.resize(_gray(10), (1990, 3)))
    for name in METHODS:
        argv = ["measure", str(strip), "--method", name, "--out", str(tmp_path / "r.json")]
        _exit_2(capsys, argv, "strip.png: 1990×3 px is not a rig frame")


def test_pixel_scale_bounds(tmp_path: Path) -> None:
    assert PixelScale(0.0118, 2592).area_mm2(1e10, 16) < float("inf")
    for bad in (1e200, 0.0, -1.0, float("nan"), float("inf"), True):
        with pytest.raises(ValueError, match="mm_per_px must be"):
            PixelScale(bad, None)
    for width in (0, 10**9, 2592.5, True):
        with pytest.raises(ValueError, match="image_width_px must be"):
            PixelScale(0.0118, width)
    rig = tmp_path / "rig.json"
    rig.write_text('{"mm_per_px": 0.0118, "image_width_px": 2592.0}')
    assert load_rig_config(rig) == PixelScale(0.0118, 2592)
    for text in (
        '{"mm_per_px": 0.0118, "image_width_px": 1e400}',
        '{"mm_per_px": "x", "image_width_px": 64}',
    ):
        rig.write_text(text)
        with pytest.raises(RigConfigError, match="rig.json"):
            load_rig_config(rig)


@pytest.mark.parametrize("text", UNREADABLE_JSON.values(), ids=UNREADABLE_JSON.keys())
def test_rig_json_no_reader_takes_is_one_line_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    """JSON no reader takes (an integer over the digit limit, deep nesting) is refused as invalid
    JSON (was a line without the file, or a RecursionError traceback)."""
    rig = tmp_path / "rig.json"
    rig.write_text(text)
    argv = ["measure", str(FRAME), "--rig", str(rig), "--out", str(tmp_path / "r.json")]
    _exit_2(capsys, argv, f"{rig}: not a readable JSON rig config (unreadable JSON value (")


def test_cli_scale_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = str(tmp_path / "r.json")
    _exit_2(capsys, ["measure", str(FRAME), "--mm-per-px", "1e200", "--out", out], "mm_per_px")
    session = _session_copy(tmp_path)
    (session / "rig.json").write_text('{"mm_per_px": 0.05, "image_width_px": 1e400}')
    argv = ["calibrate", str(session / "manifest.csv"), "--out", str(tmp_path / "o")]
    _exit_2(capsys, argv, "rig.json", "image_width_px must be")


@pytest.mark.parametrize("name", METHODS)
def test_12bit_session_with_reference(tmp_path: Path, name: str) -> None:
    def pair(bits: int) -> list[Path]:
        scale, dtype = ((1 << bits) - 1) / 255, np.uint8 if bits == 8 else np.uint16
        return [
            _png(tmp_path / f"{kpa}_{bits}.png", np.rint(_gray(kpa) * scale).astype(dtype))
            for kpa in (0, 10)
        ]

    (ref12, f12), (ref8, f8) = pair(12), pair(8)
    with pytest.raises(ImageError, match="--bit-depth"):
        measure_files([f12], make_method(name), ref12)
    got = measure_files([f12], make_method(name), ref12, bit_depth=12)[0].result
    want = measure_files([f8], make_method(name), ref8)[0].result
    assert got.area_px == want.area_px > 0 and got.note == want.note == ""


def _with_chunk(png: bytes, kind: bytes, data: bytes) -> bytes:
    """``png`` with a chunk inserted right after IHDR (CRC computed)."""
    import struct
    import zlib

    ihdr_end = 8 + 4 + 4 + 13 + 4
    chunk = struct.pack(">I", len(data)) + kind + data
    chunk += struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    return png[:ihdr_end] + chunk + png[ihdr_end:]


def test_colour_metadata_warning_is_not_corruption(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """A bad iCCP chunk makes libpng warn, but the pixels are intact: warned, not refused."""
    img = cv2.imread(str(EXAMPLE / "p12.0kpa.jpg"), cv2.IMREAD_GRAYSCALE)
    ok, buf = cv2.imencode(".png", img)
    assert ok
    path = tmp_path / "iccp.png"
    path.write_bytes(_with_chunk(buf.tobytes(), b"iCCP", b"x"))
    capfd.readouterr()
    np.testing.assert_array_equal(load_image(path), img)
    assert "iCCP" in capfd.readouterr().err
    # while damage to the pixel data stays an error
    bad = bytearray(buf.tobytes())
    bad[len(bad) // 2 : len(bad) // 2 + 40] = b"\x00" * 40
    (tmp_path / "bad.png").write_bytes(bytes(bad))
    with pytest.raises(ImageError):
        load_image(tmp_path / "bad.png")

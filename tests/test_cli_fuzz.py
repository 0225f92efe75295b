"""Property test over the CLI itself: random files on disk never end in a traceback.

Beside the API-level fuzz (tests/test_hard_cases.py), this writes random image files (sizes,
formats, bit depths, channels, corrupt bytes) and runs ``contactcal measure`` and ``calibrate``
through ``main``: every run must end with 0, 1 or 2, an exit 2 with exactly one message line,
and never an exception escaping ``main`` (which would be a traceback for the user).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contactcal.infer.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
FORMATS = (".png", ".jpg", ".tif", ".bmp")
CORRUPTIONS = ("none", "truncate", "flip", "garbage", "empty")


@st.composite
def image_files(draw: st.DrawFn) -> dict:
    """Parameters of one random image file."""
    return {
        "h": draw(st.integers(1, 96)),
        "w": draw(st.integers(1, 96)),
        "fmt": draw(st.sampled_from(FORMATS)),
        "depth": draw(st.sampled_from(("u8", "u16", "f32"))),
        "channels": draw(st.sampled_from((1, 3, 4))),
        "corrupt": draw(st.sampled_from(CORRUPTIONS)),
        "seed": draw(st.integers(0, 2**16)),
        "example": draw(st.booleans()),  # start from a real rig frame, resized
    }


def write_file(folder: Path, name: str, p: dict) -> Path:
    """Write one random file as described by ``p`` (see :func:`image_files`)."""
    rng = np.random.default_rng(p["seed"])
    shape = (p["h"], p["w"]) if p["channels"] == 1 else (p["h"], p["w"], p["channels"])
    if p["example"]:
        img = cv2.imread(str(EXAMPLE / "p12.0kpa.jpg"), cv2.IMREAD_UNCHANGED)
        img = cv2.resize(img, (p["w"], p["h"]), interpolation=cv2.INTER_AREA)
        img = img.reshape(p["h"], p["w"], -1)[:, :, 0]
        img = np.dstack([img] * p["channels"]) if p["channels"] > 1 else img
    else:
        img = rng.integers(0, 256, shape, endpoint=False).astype(np.uint8)
    fmt, depth = p["fmt"], p["depth"]
    if depth == "u16" and fmt in (".png", ".tif"):
        img = img.astype(np.uint16) * 257
    elif depth == "f32" and fmt == ".tif":
        img = img.astype(np.float32) / 255.0
    path = folder / f"{name}{fmt}"
    ok, buf = cv2.imencode(fmt, img)
    data = buf.tobytes() if ok else b"not an image"
    if p["corrupt"] == "truncate":
        data = data[: max(1, len(data) // 2)]
    elif p["corrupt"] == "flip":
        arr = bytearray(data)
        for i in rng.integers(0, len(arr), max(1, len(arr) // 50)):
            arr[i] ^= 0xFF
        data = bytes(arr)
    elif p["corrupt"] == "garbage":
        data = rng.integers(0, 256, 200, dtype=np.uint8).tobytes()
    elif p["corrupt"] == "empty":
        data = b""
    path.write_bytes(data)
    return path


def _check_run(argv: list[str], capfd: pytest.CaptureFixture[str]) -> int:
    capfd.readouterr()
    code = main(argv)  # an exception here is a traceback for the user: the test fails
    err = capfd.readouterr().err  # the file descriptor: OpenCV and libjpeg write there too
    assert code in (0, 1, 2), f"exit {code} for {argv}"
    if code == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) == 1, f"exit 2 should say one line, got: {err!r}"
    return code


SETTINGS = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@SETTINGS
@given(
    frame=image_files(),
    ref=st.one_of(st.none(), image_files()),
    method=st.sampled_from(("unet", "classical")),
)
def test_measure_random_files(
    tmp_path_factory: pytest.TempPathFactory,
    capfd: pytest.CaptureFixture[str],
    frame: dict,
    ref: dict | None,
    method: str,
) -> None:
    folder = tmp_path_factory.mktemp("fuzz")
    path = write_file(folder, "frame", frame)
    argv = ["measure", "--method", method, "--out", str(folder / "out.json"), str(path)]
    if ref is not None:
        argv[1:1] = ["--reference", str(write_file(folder, "ref", ref))]
    if _check_run(argv, capfd) == 0:
        for r in json.loads((folder / "out.json").read_text()):
            assert math.isfinite(r["area_px"]) and 0.0 <= r["area_px"] <= r["width"] * r["height"]
            assert r["contact"] == (r["area_px"] > 0)


@SETTINGS
@given(
    files=st.lists(image_files(), min_size=2, max_size=3),
    method=st.sampled_from(("unet", "classical")),
)
def test_calibrate_random_files(
    tmp_path_factory: pytest.TempPathFactory,
    capfd: pytest.CaptureFixture[str],
    files: list[dict],
    method: str,
) -> None:
    folder = tmp_path_factory.mktemp("fuzz")
    rows = [f"{write_file(folder, f'f{i}', p).name},{4.0 * i}" for i, p in enumerate(files)]
    (folder / "m.csv").write_text("file,pressure_kpa\n" + "\n".join(rows) + "\n")
    out = folder / "cal"
    code = _check_run(
        ["calibrate", str(folder / "m.csv"), "--method", method, "--out", str(out)], capfd
    )
    assert (out / "calibration.json").is_file() == (code == 0)

"""Hard cases and numerical stability of both methods (and torch vs ONNX on each case)."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contactcal.infer.image.frame import MAX_ASPECT_RATIO, MIN_FRAME_SIDE_PX
from contactcal.infer.image.gray import ImageError, to_gray_u8
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.classical import ClassicalMethod
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"


def _frame(kpa: int) -> np.ndarray:
    return load_image(EXAMPLE / f"p{kpa:04.1f}kpa.jpg")


def _ring_sector_removed(g: np.ndarray) -> np.ndarray:
    out = g.copy()
    h, w = g.shape
    yy, xx = np.mgrid[0:h, 0:w]
    ang = np.degrees(np.arctan2(yy - h / 2, xx - w / 2))
    r = np.hypot(yy - h / 2, xx - w / 2)
    out[(ang > 20) & (ang < 110) & (r > 0.6 * h / 2)] = 0
    return out


CASES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "as rendered": lambda g: g,
    "underexposed x0.3": lambda g: np.clip(g * 0.3, 0, 255).astype(np.uint8),
    "overexposed x2.5": lambda g: np.clip(g * 2.5, 0, 255).astype(np.uint8),
    "heavy noise": lambda g: np.clip(
        g + np.random.default_rng(0).normal(0, 25, g.shape), 0, 255
    ).astype(np.uint8),
    "defocus": lambda g: cv2.GaussianBlur(g, (0, 0), 3.0),
    "ring partly missing": _ring_sector_removed,
    "odd size crop": lambda g: np.ascontiguousarray(g[3:-4, 5:-2]),
    "all black": lambda g: np.zeros_like(g),
    "all white": lambda g: np.full_like(g, 255),
    "tiny image": lambda g: cv2.resize(g, (37, 29), interpolation=cv2.INTER_AREA),
}


@pytest.fixture(scope="module")
def unet() -> UnetMethod:
    assert DEFAULT_MODEL.is_file(), f"the shipped model is missing: {DEFAULT_MODEL}"
    return UnetMethod(outline=True)


def _bound(method: object, gray: np.ndarray) -> float:
    """Largest area a method may report: the image, and for the U-Net also its crop."""
    box = method.reference.box if isinstance(method, UnetMethod) else None
    return float(gray.size if box is None else min(gray.size, box.side**2))


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("kpa", [0, 4, 12])
def test_hard_cases_are_finite_and_bounded(unet: UnetMethod, case: str, kpa: int) -> None:
    for method in (unet, ClassicalMethod()):
        gray = CASES[case](_frame(kpa))
        ref = CASES[case](_frame(0))
        method.set_reference(ref)
        res = method.measure(gray)
        assert np.isfinite(res.area_px) and 0.0 <= res.area_px <= _bound(method, gray), (
            f"{type(method).__name__} on '{case}' at {kpa} kPa: area {res.area_px}"
        )
        assert res.contact == (res.area_px > 0), f"contact flag inconsistent on '{case}'"


@pytest.mark.parametrize("case", ["as rendered", "heavy noise", "all black", "all white"])
def test_no_contact_frame_is_no_contact(unet: UnetMethod, case: str) -> None:
    unet.set_reference(CASES[case](_frame(0)))
    res = unet.measure(CASES[case](_frame(0)))
    assert not res.contact and res.area_px == 0.0, f"'{case}' 0 kPa: {res}"


def test_shipped_model_sane_on_example_session(unet: UnetMethod) -> None:
    with open(EXAMPLE / "truth.csv", newline="") as fh:
        truth = {r["file"]: r for r in csv.DictReader(fh)}
    unet.set_reference(_frame(0))
    errors = []
    for kpa in (8, 14, 20):
        t = truth[f"p{kpa:04.1f}kpa.jpg"]
        res = unet.measure(_frame(kpa))
        mask = cv2.imread(str(EXAMPLE / "masks" / f"p{kpa:04.1f}kpa.png"), cv2.IMREAD_GRAYSCALE)
        assert res.contact and res.contour is not None
        pred = np.zeros_like(mask)
        cv2.drawContours(pred, [res.contour], -1, 255, -1)
        inter = np.logical_and(pred > 0, mask > 0).sum()
        union = np.logical_or(pred > 0, mask > 0).sum()
        assert inter / union > 0.85, f"IoU {inter / union:.3f} at {kpa} kPa"
        errors.append(abs(res.area_px / float(t["area_px"]) - 1))
    assert max(errors) < 0.1, f"relative area errors {errors}"


def test_16bit_and_gray_inputs_agree(unet: UnetMethod, tmp_path: Path) -> None:
    g = _frame(12)
    cv2.imwrite(str(tmp_path / "g16.png"), g.astype(np.uint16) * 257)
    cv2.imwrite(str(tmp_path / "g8.png"), g)
    unet.set_reference(_frame(0))
    a = unet.measure(load_image(tmp_path / "g16.png")).area_px
    b = unet.measure(load_image(tmp_path / "g8.png")).area_px
    assert a == b > 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_float_arrays_rejected(bad: float) -> None:
    arr = np.full((30, 40), 0.5, np.float32)
    arr[3, 4] = bad
    with pytest.raises(ImageError, match="NaN or inf"):
        to_gray_u8(arr, name="frame.npy")


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    h=st.integers(1, 90),
    w=st.integers(1, 90),
    dtype=st.sampled_from([np.uint8, np.uint16, np.float32]),
    channels=st.sampled_from([0, 3, 4]),
    seed=st.integers(0, 2**16),
)
def test_random_images_no_undocumented_exception(
    unet: UnetMethod, h: int, w: int, dtype: type, channels: int, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    shape = (h, w) if channels == 0 else (h, w, channels)
    if dtype is np.float32:
        arr = rng.random(shape, dtype=np.float32)
    else:
        arr = rng.integers(0, np.iinfo(dtype).max, shape, endpoint=True).astype(dtype)
    gray = to_gray_u8(arr)
    short, long = min(h, w), max(h, w)
    too_small = short < MIN_FRAME_SIDE_PX or long > MAX_ASPECT_RATIO * short
    for method in (unet, ClassicalMethod()):
        method.set_reference(None)
        if too_small:  # refused as a file of that size is (it gave "no contact")
            with pytest.raises(ImageError, match="is not a rig frame"):
                method.measure(gray)
            continue
        res = method.measure(gray)
        assert np.isfinite(res.area_px) and 0.0 <= res.area_px <= max(_bound(method, gray), 1.0)

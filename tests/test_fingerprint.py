"""Tests of the procedural fingerprint texture generator (contactcal.synth.fingerprint)."""

from __future__ import annotations

import numpy as np
import pytest

from contactcal.synth.fingerprint import PATTERNS, Fingerprint, FingerprintConfig, make_fingerprint
from contactcal.synth.ridge_period import ridge_period_px

# Small textures keep the suite fast: 10 mm at 16 px/mm = 160 px.
SMALL = FingerprintConfig(size_mm=10.0, px_per_mm=16.0)


def _only(pattern: str, **kw: float) -> FingerprintConfig:
    probs = tuple(float(p == pattern) for p in PATTERNS)
    return FingerprintConfig(size_mm=10.0, px_per_mm=16.0, pattern_probs=probs, **kw)


def test_smoke_shape_dtype_range() -> None:
    fp = make_fingerprint(np.random.default_rng(0), SMALL)
    assert isinstance(fp, Fingerprint)
    assert fp.ridges.shape == (160, 160)
    assert fp.ridges.dtype == np.float32
    assert np.isfinite(fp.ridges).all()
    assert fp.ridges.min() >= 0.0 and fp.ridges.max() <= 1.0
    assert fp.ridges.max() > 0.9 and fp.ridges.min() < 0.1  # real ridges and valleys
    assert SMALL.period_mm_range[0] <= fp.period_mm <= SMALL.period_mm_range[1]
    assert fp.pattern in PATTERNS
    assert fp.size_mm == pytest.approx(10.0) and fp.px_per_mm == 16.0


def test_default_config_size() -> None:
    cfg = FingerprintConfig()
    assert cfg.size_mm >= 28.0
    assert cfg.px_per_mm * cfg.period_mm_range[0] >= 7.0  # >= 7 px per ridge period


def test_determinism() -> None:
    a = make_fingerprint(np.random.default_rng(42), SMALL)
    b = make_fingerprint(np.random.default_rng(42), SMALL)
    c = make_fingerprint(np.random.default_rng(43), SMALL)
    assert a.ridges.tobytes() == b.ridges.tobytes()
    assert (a.period_mm, a.pattern) == (b.period_mm, b.pattern)
    assert not np.array_equal(a.ridges, c.ridges)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_each_pattern(pattern: str) -> None:
    fp = make_fingerprint(np.random.default_rng(1), _only(pattern))
    assert fp.pattern == pattern
    assert np.isfinite(fp.ridges).all()
    assert 0.2 < fp.ridges.mean() < 0.8


@pytest.mark.parametrize("period_mm", [0.40, 0.50])
def test_measured_period_matches_config(period_mm: float) -> None:
    cfg = FingerprintConfig(
        size_mm=12.0, px_per_mm=16.0, period_mm_range=(period_mm, period_mm), period_variation=0.0
    )
    for seed in range(3):
        fp = make_fingerprint(np.random.default_rng(seed), cfg)
        assert fp.period_mm == period_mm
        measured = ridge_period_px(fp.ridges)
        assert measured == pytest.approx(period_mm * cfg.px_per_mm, rel=0.05)


def test_default_texture_period_with_variation() -> None:
    fp = make_fingerprint(np.random.default_rng(11))  # default: 28 mm, 20 px/mm, +-3 % warp
    assert fp.ridges.shape == (560, 560)
    expected = fp.period_mm * fp.px_per_mm
    assert ridge_period_px(fp.ridges) == pytest.approx(expected, rel=0.05)
    n = fp.ridges.shape[0]
    centre = fp.ridges[n // 2 - 80 : n // 2 + 80, n // 2 - 80 : n // 2 + 80]  # ~9 mm patch
    assert ridge_period_px(centre) == pytest.approx(expected, rel=0.08)


def test_ridge_period_px_sinusoid() -> None:
    yy, xx = np.mgrid[0:96, 0:128]
    for period, angle in [(5.0, 0.0), (7.3, 0.5), (11.0, 1.2)]:
        wave = np.sin(2 * np.pi * (xx * np.cos(angle) + yy * np.sin(angle)) / period)
        img = 100.0 + 0.3 * xx + 20.0 * wave  # offset and lighting gradient are removed
        assert ridge_period_px(img) == pytest.approx(period, rel=0.02)


def test_ridge_period_px_mask() -> None:
    yy, xx = np.mgrid[0:128, 0:128]
    img = np.where(xx < 64, np.sin(2 * np.pi * yy / 6.0), np.sin(2 * np.pi * xx / 12.0))
    assert ridge_period_px(img, mask=xx < 64) == pytest.approx(6.0, rel=0.03)


@pytest.mark.parametrize("bad", [np.zeros((5, 5)), np.zeros((32, 32)), np.full((16, 16), np.nan)])
def test_ridge_period_px_bad_input(bad: np.ndarray) -> None:
    with pytest.raises(ValueError, match="ridge_period_px"):
        ridge_period_px(bad)


def test_sample_matches_pixels_and_fill() -> None:
    fp = make_fingerprint(np.random.default_rng(3), SMALL)
    i, j = 37, 101
    x = (j + 0.5) / fp.px_per_mm - fp.size_mm / 2
    y = (i + 0.5) / fp.px_per_mm - fp.size_mm / 2
    assert fp.sample(np.array(x), np.array(y)) == pytest.approx(fp.ridges[i, j], abs=1e-6)
    out = fp.sample(np.array([0.0, 100.0]), np.array([0.0, 0.0]), fill=0.5)
    assert out.dtype == np.float32 and out.shape == (2,) and out[1] == 0.5
    mid = fp.sample(np.array(x + 0.5 / fp.px_per_mm), np.array(y))  # halfway to the next pixel
    assert mid == pytest.approx(0.5 * (fp.ridges[i, j] + fp.ridges[i, j + 1]), abs=1e-5)


def test_sample_is_edge_clamped_bilinear() -> None:
    """cv2.remap lookup == textbook bilinear with clamped coordinates (float32 map rounding)."""
    fp = make_fingerprint(np.random.default_rng(4), SMALL)
    img = fp.ridges.astype(np.float64)
    n = img.shape[0]
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-5.2, 5.2, (2, 50_001))  # > one remap row, some beyond the pixel centres
    r = np.clip((y + fp.size_mm / 2) * fp.px_per_mm - 0.5, 0, n - 1)
    c = np.clip((x + fp.size_mm / 2) * fp.px_per_mm - 0.5, 0, n - 1)
    r0, c0 = np.minimum(r.astype(int), n - 2), np.minimum(c.astype(int), n - 2)
    fr, fc = r - r0, c - c0
    top = img[r0, c0] * (1 - fc) + img[r0, c0 + 1] * fc
    bot = img[r0 + 1, c0] * (1 - fc) + img[r0 + 1, c0 + 1] * fc
    expected = np.where((np.abs(x) <= 5) & (np.abs(y) <= 5), top * (1 - fr) + bot * fr, 0.5)
    np.testing.assert_allclose(fp.sample(x, y), expected, atol=1e-4)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"period_mm_range": (0.5, 0.4)}, "period_mm_range"),
        ({"px_per_mm": 8.0}, "px_per_mm"),
        ({"pattern_probs": (0.0, 0.0, 0.0)}, "pattern_probs"),
        ({"iterations": 0}, "iterations"),
        ({"pore_depth": 1.5}, "pore_depth"),
        ({"break_density": -1.0}, "break_density"),
    ],
)
def test_bad_config_raises(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FingerprintConfig(**kwargs)  # type: ignore[arg-type]

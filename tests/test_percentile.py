"""infer/image/percentile.py: the same numbers as np.percentile, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from contactcal.infer.image.percentile import percentiles

#: Percentiles the pipeline uses (99.5, the median) and the edges of the range.
QS = (0.0, 0.1, 25.0, 50.0, 99.5, 99.9, 100.0)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
def test_equals_numpy_bit_for_bit(dtype: type) -> None:
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 7, 200, 1001, 77_760):
        if np.issubdtype(dtype, np.integer):
            top = 255 if dtype == np.uint8 else 4095
            values = rng.integers(0, top + 1, n).astype(dtype)
        else:
            values = (rng.random(n) * 3.0 - 0.5).astype(dtype)
        # Python floats (numpy's weak promotion) and numpy float64 percentiles (strong).
        for q in QS + tuple(rng.uniform(0, 100, 5)):
            got = percentiles(values, (q,))[0]
            want = float(np.percentile(values, q))
            assert got == want, (dtype, n, q, got, want)


def test_uint8_median_is_numpys_median() -> None:
    rng = np.random.default_rng(4)
    for shape in ((243, 324), (5, 4), (3, 3)):
        img = rng.integers(0, 256, shape).astype(np.uint8)
        assert percentiles(img, (50.0,))[0] == float(np.median(img))


def test_several_at_once_and_shapes() -> None:
    img = np.arange(12, dtype=np.uint8).reshape(3, 4)
    assert percentiles(img, (0.0, 50.0, 100.0)) == (0.0, 5.5, 11.0)
    assert percentiles(img.astype(np.float32), (50.0,)) == (5.5,)


def test_nan_gives_nan_as_numpy() -> None:
    values = np.array([1.0, np.nan, 3.0], np.float32)
    assert all(math.isnan(v) for v in percentiles(values, (10.0, 90.0)))


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="empty"):
        percentiles(np.zeros(0, np.uint8), (50.0,))
    with pytest.raises(ValueError, match=r"\[0, 100\]"):
        percentiles(np.zeros(3, np.uint8), (101.0,))

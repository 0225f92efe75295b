"""Skin condition (synth/skin.py): smoke, shape, bad input, reference behaviour."""

from __future__ import annotations

import numpy as np
import pytest

from contactcal.synth.skin import SCAR_LEVEL, SkinCondition, apply_skin

M = 256
TEXEL_MM = 0.05


def _ridges() -> np.ndarray:
    x = np.arange(M) * TEXEL_MM
    return (0.5 + 0.5 * np.cos(2 * np.pi * x / 0.45))[None, :].repeat(M, 0).astype(np.float32)


def test_default_changes_nothing_and_keeps_range() -> None:
    r = _ridges()
    out = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition())
    assert out.shape == (M, M) and out.dtype == np.float32
    np.testing.assert_allclose(out, r, atol=1e-6)


def test_polarity_inverts() -> None:
    r = _ridges()
    out = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition(polarity=-1))
    np.testing.assert_allclose(out, 1.0 - r, atol=1e-6)


def test_dry_wet_scars_reference_behaviour() -> None:
    r = _ridges()
    dry = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition(dryness=0.4, seed=3))
    assert np.mean(dry == 0.0) == pytest.approx(0.4, abs=0.02)  # 40 % of the area broken
    wet = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition(wetness=0.8))
    assert wet.std() < 0.5 * r.std() and wet.min() > r.min() + 0.2  # valleys filled
    scar = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition(scars=2, seed=1))
    assert 0.0 < np.mean(scar == SCAR_LEVEL) < 0.2
    again = apply_skin(r, TEXEL_MM, (M / 2, M / 2), SkinCondition(scars=2, seed=1))
    np.testing.assert_array_equal(scar, again)  # deterministic per seed


@pytest.mark.parametrize(
    "kw", [{"polarity": 0}, {"dryness": 1.5}, {"wetness": -0.1}, {"scars": -1}]
)
def test_bad_condition_is_refused(kw: dict) -> None:
    with pytest.raises(ValueError, match="synth/skin.py"):
        SkinCondition(**kw)

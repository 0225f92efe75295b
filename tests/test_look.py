"""The v2 look effects (synth/look.py) and their use in apply_camera; fast, no Mitsuba."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np
import pytest

from contactcal.synth.camera import CameraEffects, apply_camera
from contactcal.synth.look import (
    LookEffects,
    add_centre_speck,
    add_dust,
    apply_optics,
    apply_white_balance,
    motion_blur,
    motion_kernel,
    tone_curve,
    vignette_gain,
)
from contactcal.synth.randomize import SessionParams, sample_session

H, W = 60, 80
HARD = LookEffects(
    vignetting=0.4,
    vignette_centre=(0.03, -0.02),
    wb_gains=(1.25, 0.9, 0.75),
    tone_strength=0.5,
    motion_blur_px=3.0,
    motion_blur_deg=30.0,
    dust_count=15,
    stray_amplitude=0.15,
    seed=7,
)


def _frame(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    img = (0.2 + 0.6 * rng.random((H, W, 3))).astype(np.float32)
    mask = np.zeros((H, W), bool)
    mask[20:40, 30:50] = True
    return img, mask


def test_default_look_is_identity() -> None:
    img, _ = _frame()
    np.testing.assert_array_equal(apply_optics(img, LookEffects()), img)
    assert apply_white_balance(img, (1.0, 1.0, 1.0)) is img
    np.testing.assert_array_equal(vignette_gain(H, W, 0.0), np.ones((H, W, 1), np.float32))
    np.testing.assert_array_equal(motion_blur(img, 0.0, 45.0), img)


def test_default_camera_output_unchanged_by_look_field() -> None:
    img, mask = _frame()
    fx = CameraEffects(exposure=1.0, read_noise=0.01)
    a = apply_camera(img, mask, fx, np.random.default_rng(3), 100.0)
    b = apply_camera(
        img, mask, dataclasses.replace(fx, look=LookEffects()), np.random.default_rng(3), 100.0
    )
    np.testing.assert_array_equal(a[0], b[0])


def test_shapes_and_smoke() -> None:
    img, mask = _frame()
    out, m = apply_camera(
        img, mask, CameraEffects(jpeg_quality=50, look=HARD), np.random.default_rng(1), 90.0
    )
    assert out.shape == (H, W, 3) and out.dtype == np.uint8
    assert m.shape == (H, W) and m.dtype == bool
    assert apply_optics(img, HARD).shape == (H, W, 3)


def test_vignetting_reference_values() -> None:
    g = vignette_gain(H, W, 0.4)[:, :, 0]
    assert g.max() <= 1.0 and g[H // 2, W // 2] == pytest.approx(1.0, abs=1e-3)
    assert g[0, 0] == pytest.approx(0.6, abs=1e-3)  # r = 1 at the corner → 1 - k
    off = vignette_gain(H, W, 0.4, (0.1, 0.0))[:, :, 0]
    assert off[H // 2, -1] > off[H // 2, 0]  # centre moved right: left edge darker


def test_white_balance_scales_channel_means() -> None:
    img, _ = _frame()
    gains = (1.25, 1.0, 0.75)
    out = apply_white_balance(img, gains)
    np.testing.assert_allclose(out.mean(axis=(0, 1)), img.mean(axis=(0, 1)) * gains, rtol=1e-5)


def test_tone_curve_monotone_fixes_ends() -> None:
    x = np.linspace(0.0, 1.0, 1001, dtype=np.float32)
    for s in (0.0, 0.1, 0.5, 1.0):
        y = tone_curve(x, s)
        assert y[0] == 0.0 and y[-1] == pytest.approx(1.0)
        assert np.all(np.diff(y) >= 0)
    y = tone_curve(x, 0.5)
    assert y[250] < x[250] and y[750] > x[750]  # S-shape: more contrast in mid-tones
    np.testing.assert_allclose(tone_curve(x, 0.0), x)


def test_motion_kernel_normalised_and_directional() -> None:
    k = motion_kernel(3.0, 0.0)
    assert k.sum() == pytest.approx(1.0)
    c = k.shape[0] // 2
    assert k[c].sum() == pytest.approx(1.0)  # horizontal: all weight in the centre row


def test_dust_never_changes_mask_and_is_local() -> None:
    img, mask = _frame()
    fx = CameraEffects(full_well=1e6, read_noise=0.0, look=LookEffects(dust_count=15, seed=2))
    base = CameraEffects(full_well=1e6, read_noise=0.0)
    out, m = apply_camera(img, mask, fx, np.random.default_rng(0), 90.0)
    ref, m0 = apply_camera(img, mask, base, np.random.default_rng(0), 90.0)
    np.testing.assert_array_equal(m, mask)
    np.testing.assert_array_equal(m0, m)
    dusty = add_dust(img, 3, np.random.default_rng(5))
    assert 0 < np.mean(np.abs(dusty - img) > 1e-3) < 0.2
    assert not np.array_equal(out, ref)


def test_same_seed_same_frame() -> None:
    img, mask = _frame()
    fx = CameraEffects(jpeg_quality=80, read_noise=0.01, look=HARD)
    a = apply_camera(img, mask, fx, np.random.default_rng(11), 90.0)
    b = apply_camera(img, mask, fx, np.random.default_rng(11), 90.0)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


@pytest.mark.parametrize(
    "kwargs",
    [
        {"vignetting": -0.1},
        {"vignetting": 1.0},
        {"wb_gains": (1.0, 0.0, 1.0)},
        {"wb_gains": (1.0, 1.0)},
        {"tone_strength": 1.5},
        {"motion_blur_px": -1.0},
        {"dust_count": -1},
        {"stray_amplitude": 2.0},
        {"vignette_centre": (0.9, 0.0)},
        {"seed": -1},
    ],
)
def test_bad_input_raises(kwargs: dict) -> None:
    with pytest.raises(ValueError, match="synth/look.py"):
        LookEffects(**kwargs)


def test_camera_rejects_non_look() -> None:
    with pytest.raises(ValueError, match="synth/camera.py"):
        CameraEffects(look="none")  # type: ignore[arg-type]


def test_sessions_draw_looks_in_range() -> None:
    for seed in range(40):
        nominal = sample_session(np.random.default_rng([seed, 0])).camera.look
        hard_s = sample_session(np.random.default_rng([seed, 0]), hard=True)
        hard = hard_s.camera.look
        assert 0 <= nominal.vignetting <= 0.1 and 0 <= hard.vignetting <= 0.4
        assert all(0.97 <= g <= 1.03 for g in nominal.wb_gains)
        assert all(0.75 <= g <= 1.25 for g in hard.wb_gains)
        assert nominal.motion_blur_px == 0 and nominal.stray_amplitude == 0
        assert 0 <= nominal.dust_count <= 3 and 0 <= hard.dust_count <= 15
        assert 10.5 <= hard_s.rig.lgp_inner_radius_mm <= 12.5
        rig = sample_session(np.random.default_rng([seed, 0])).rig
        assert rig.lgp_inner_radius_mm == 11.5


def test_smooth_coating_in_the_chosen_share_of_hard_sessions_only() -> None:
    smooth = 0
    for seed in range(60):
        nominal = sample_session(np.random.default_rng([seed, 1])).optics
        assert 0.5 <= nominal.particle_tilt_deg <= 1.5 and 0.02 <= nominal.roughness_alpha <= 0.06
        rng = np.random.default_rng([seed, 1])
        hard = sample_session(rng, hard=True, smooth_fraction=0.5).optics
        plain = sample_session(np.random.default_rng([seed, 1]), hard=True).optics  # option off
        assert 1.0 <= plain.particle_tilt_deg <= 4.0 and plain.roughness_alpha >= 0.03
        if hard.roughness_alpha < 0.02:  # smooth: both the tilt and α come from SMOOTH_DRAWS
            assert 0.1 <= hard.particle_tilt_deg <= 0.5 and hard.roughness_alpha >= 0.005
            smooth += 1
        else:
            assert 1.0 <= hard.particle_tilt_deg <= 4.0 and hard.roughness_alpha <= 0.15
    assert 18 <= smooth <= 42  # smooth_fraction 0.5 of 60


def _drawn_with_and_without(**option: float) -> Iterator[tuple[SessionParams, SessionParams]]:
    """``(plain, with option)`` sessions of one seed each, for 60 seeds × normal and hard."""
    for seed in range(60):
        for hard in (False, True):
            plain = sample_session(np.random.default_rng([seed, 2]), hard=hard)
            yield plain, sample_session(np.random.default_rng([seed, 2]), hard=hard, **option)


def test_centre_speck_in_the_chosen_share_of_sessions_other_draws_unchanged() -> None:
    """The option only adds a speck: every other parameter is what the seed gave before."""
    specks = 0
    for plain, with_speck in _drawn_with_and_without(speck_fraction=0.5):
        assert plain.camera.look.centre_speck == (0.0, 0.0, 0.0, 0.0)
        strength, radius, x, y = with_speck.camera.look.centre_speck
        look = dataclasses.replace(with_speck.camera.look, centre_speck=(0.0, 0.0, 0.0, 0.0))
        camera = dataclasses.replace(with_speck.camera, look=look)
        assert dataclasses.replace(with_speck, camera=camera) == plain
        if strength > 0:
            specks += 1
            assert 0.1 <= strength <= 0.4 and 1.0 <= radius <= 4.0
            assert np.hypot(x, y) <= 0.12
    assert 40 <= specks <= 80  # speck_fraction 0.5 of 120


def test_centre_speck_brightens_the_centre_only() -> None:
    img = np.full((H, W, 3), 0.05, np.float32)
    assert add_centre_speck(img, (0.0, 2.0, 0.1, 0.0)) is img  # none: the image itself
    # σ = 20 px · 80/400 / 1.5 = 2.7 px; 6 px right and 3 px up of the centre
    out = add_centre_speck(img, (0.3, 20.0, 0.1, -0.05))
    glow = out[..., 0] - img[..., 0]
    assert glow.min() >= 0.0
    y, x = np.unravel_index(int(np.argmax(glow)), glow.shape)
    assert (x, y) in {(45, 26), (46, 26), (45, 27), (46, 27)}  # centre (39.5 + 6, 29.5 - 3)
    assert glow.max() == pytest.approx(0.3, rel=0.1)  # the peak falls between pixels
    assert glow[0, 0] < 1e-6 and glow[-1, -1] < 1e-6
    look = dataclasses.replace(LookEffects(), centre_speck=(0.3, 20.0, 0.1, -0.05))
    np.testing.assert_allclose(apply_optics(img, look), out)
    with pytest.raises(ValueError, match="centre_speck strength"):
        LookEffects(centre_speck=(1.5, 2.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="centre_speck x, y"):
        LookEffects(centre_speck=(0.2, 2.0, 0.7, 0.0))


def test_camera_blur_means_the_same_optics_at_every_width() -> None:
    """Defocus, motion blur and axis offset are given at 400 px wide and scale with the width:
    under defocus, ridges of the same physical period keep the same contrast at 400 and 1296 px."""
    fx = CameraEffects(
        defocus_sigma_px=1.0,
        shift_px=(1.5, -1.0),
        full_well=1e7,
        read_noise=0.0,
        gamma=1.0,
        look=LookEffects(motion_blur_px=2.0),
    )
    wide = fx.at_width(1296)
    assert wide.defocus_sigma_px == pytest.approx(3.24)
    assert wide.shift_px == pytest.approx((4.86, -3.24))
    assert wide.look.motion_blur_px == pytest.approx(6.48)
    assert fx.at_width(400) == fx
    kept = []
    # defocus alone: a 2-px motion kernel and a sub-pixel shift's interpolation are coarser at 400
    fx = dataclasses.replace(fx, shift_px=(0.0, 0.0), look=LookEffects())
    for w in (400, 1296):
        period = 5.0 * w / 400  # the same ridges, 5 px apart at 400 wide
        x = np.arange(w, dtype=np.float32)
        row = 0.5 + 0.2 * np.sin(2 * np.pi * x / period)
        img = np.repeat(np.broadcast_to(row, (32, w))[:, :, None], 3, axis=2).astype(np.float32)
        out, _ = apply_camera(img, np.zeros((32, w), bool), fx, np.random.default_rng(0), 1e3)
        centre = out[16, w // 4 : 3 * w // 4, 1].astype(np.float32) / 255.0
        kept.append(float(centre.std() / row[w // 4 : 3 * w // 4].std()))
    assert 0.1 < kept[0] < 0.9  # the blur is visible ...
    assert kept[1] == pytest.approx(kept[0], abs=0.05)  # ... and the same at both widths


def test_membrane_departure_in_the_chosen_share_of_sessions_other_draws_unchanged() -> None:
    """Like the speck: drawn last, so every other parameter is what the seed gave before."""
    departs = 0
    for plain, with_d in _drawn_with_and_without(departure_fraction=0.5):
        assert plain.membrane.departure_slope == 0.0
        slope = with_d.membrane.departure_slope
        membrane = dataclasses.replace(with_d.membrane, departure_slope=0.0)
        assert dataclasses.replace(with_d, membrane=membrane) == plain
        if slope > 0:
            departs += 1
            assert slope <= 0.5
    assert 40 <= departs <= 80  # departure_fraction 0.5 of 120


def test_the_departure_draws_come_after_every_earlier_table() -> None:
    """Values of the last tables before the departure draws, pinned from the code before the
    departure existed (2c31a8a): drawing it anywhere earlier would change them, and every
    existing dataset's frames with them."""
    s = sample_session(
        np.random.default_rng([7, 3]), hard=True, speck_fraction=1.0, smooth_fraction=1.0
    )
    assert s.camera.look.centre_speck == (
        0.10116129820748236,
        2.033684505698352,
        -0.09605662453718411,
        0.025155428916479348,
    )
    assert s.optics.roughness_alpha == 0.005523328532230446
    assert (s.membrane.slack_seed, s.finger.radius_mm) == (556782903, 9.732108635989364)

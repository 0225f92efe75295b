"""The ridge-energy channel: band-pass reference values, channel layout, spec and training."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.prepare import prepare, session_reference
from contactcal.infer.methods.unet.ridge import ridge_band_frequency, ridge_energy
from contactcal.infer.methods.unet.spec import ModelSpec

SIZE, WORK = 32, 64
CFG = PreprocessConfig(input_size=SIZE, ridge_work_px=WORK)


def _gain(period_px: float, cfg: PreprocessConfig) -> float:
    """The DoG's amplitude response at ``period_px`` (Gaussian transfer functions)."""
    f2 = (1.0 / period_px) ** 2
    fine, coarse = cfg.ridge_sigma_fine_px, cfg.ridge_sigma_coarse_px
    return float(np.exp(-2 * np.pi**2 * fine**2 * f2) - np.exp(-2 * np.pi**2 * coarse**2 * f2))


def _ring_frame(ridges: float = 0.0) -> np.ndarray:
    """``(120, 160) uint8``: a bright ring; inside, a flat disc with optional stripes."""
    yy, xx = np.mgrid[:120, :160].astype(np.float64)
    r = np.hypot(xx - 80, yy - 60)
    img = np.where((r > 40) & (r < 50), 230.0, 20.0)
    disc = r < 32
    img[disc] = 100.0 + ridges * np.sin(2 * np.pi * xx[disc] / 7.0)  # ~4.5 px at WORK
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("period", [4.0, 5.0, 7.0])
def test_sinusoid_reference_values(period: float) -> None:
    """A sinusoid of amplitude a: energy = a · |DoG(f)| / √2 / level / ridge_norm."""
    x = np.arange(WORK, dtype=np.float32)
    a, level = 20.0, 200.0
    work = np.broadcast_to(100.0 + a * np.sin(2 * np.pi * x / period), (WORK, WORK))
    e = ridge_energy(np.ascontiguousarray(work, np.float32), CFG, level)
    assert e.shape == (SIZE, SIZE) and e.dtype == np.float32
    expected = a * _gain(period, CFG) / np.sqrt(2.0) / level / CFG.ridge_norm
    centre = e[SIZE // 4 : -SIZE // 4, SIZE // 4 : -SIZE // 4]
    assert float(np.median(centre)) == pytest.approx(expected, rel=0.05)


def test_in_place_work_equals_the_plain_expression() -> None:
    """The in-place steps give, bit for bit, the channel as first written (the float32 ops of
    the models' training), and leave the caller's crop as it was."""
    rng = np.random.default_rng(3)
    work = rng.uniform(0, 255, (WORK, WORK)).astype(np.float32)
    before = work.copy()
    level = 187.3
    w = work.astype(np.float32) / level
    band = cv2.GaussianBlur(w, (0, 0), CFG.ridge_sigma_fine_px) - cv2.GaussianBlur(
        w, (0, 0), CFG.ridge_sigma_coarse_px
    )
    energy = np.sqrt(cv2.GaussianBlur(band * band, (0, 0), CFG.ridge_smooth_px))
    small = cv2.resize(energy, (SIZE, SIZE), interpolation=cv2.INTER_AREA)
    expected = (small / CFG.ridge_norm).astype(np.float32)
    got = ridge_energy(work, CFG, level)
    assert got.dtype == np.float32 and np.array_equal(got, expected)
    assert np.array_equal(work, before)


def test_flat_crop_has_no_energy() -> None:
    e = ridge_energy(np.full((WORK, WORK), 90.0, np.float32), CFG, 200.0)
    assert float(np.abs(e).max()) < 1e-4  # float32 rounding of the blurs


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="ridge_work_px is 0"):
        ridge_energy(np.zeros((WORK, WORK), np.float32), PreprocessConfig(), 1.0)
    with pytest.raises(ValueError, match=r"expected a \(64, 64\) crop"):
        ridge_energy(np.zeros((WORK, WORK + 1), np.float32), CFG, 1.0)
    with pytest.raises(ValueError, match="ridge_work_px must be 0"):
        PreprocessConfig(input_size=SIZE, ridge_work_px=SIZE - 1)
    with pytest.raises(ValueError, match="ridge band"):
        PreprocessConfig(ridge_sigma_fine_px=2.0, ridge_sigma_coarse_px=1.0)


def test_prepare_appends_the_ridge_channel_last() -> None:
    """Frame and reference channels are those of the model without ridge; ridged contact lights
    the last channel, a flat one does not."""
    flat, striped = _ring_frame(0.0), _ring_frame(40.0)
    ref = session_reference(flat, CFG)
    x3 = prepare(striped, ref, CFG, channels=3).x
    x2 = prepare(
        striped,
        session_reference(flat, dataclasses.replace(CFG, ridge_work_px=0)),
        dataclasses.replace(CFG, ridge_work_px=0),
        channels=2,
    ).x
    assert x3.shape == (3, SIZE, SIZE)
    np.testing.assert_array_equal(x3[:2], x2)
    centre = (slice(SIZE // 2 - 1, SIZE // 2 + 1),) * 2
    lit = float(x3[2][centre].mean())
    dark = float(prepare(flat, ref, CFG, channels=3).x[2][centre].mean())
    assert lit > 1.0 and dark < 0.01
    assert prepare(striped, ref, CFG, channels=2).x.shape == (2, SIZE, SIZE)  # frame + ridge
    with pytest.raises(ValueError, match="channels must be 2 or 3"):
        prepare(striped, ref, CFG, channels=1)


def test_spec_channels_follow_the_ridge_setting() -> None:
    assert ModelSpec(3, CFG, 0.5, 10.0).uses_reference
    assert not ModelSpec(2, CFG, 0.5, 10.0).uses_reference
    assert ModelSpec(2, PreprocessConfig(), 0.5, 10.0).uses_reference
    with pytest.raises(ValueError, match="channels must be 2 or 3"):
        ModelSpec(4, CFG, 0.5, 10.0)
    with pytest.raises(ValueError, match="channels must be 1 or 2"):
        ModelSpec(3, PreprocessConfig(), 0.5, 10.0)


def test_train_config_and_augmenter_with_ridge() -> None:
    torch = pytest.importorskip("torch")
    pytest.importorskip("kornia")
    from contactcal.train.augment import AugmentConfig, Augmenter
    from contactcal.train.config import TrainConfig

    cfg = TrainConfig(input_size=SIZE, ridge_work_px=WORK).resolved()
    assert cfg.model.in_channels == 3 and cfg.preprocess.ridge_work_px == WORK
    assert cfg.spec().channels == 3
    with pytest.raises(ValueError, match="ridge_work_px must be 0"):
        TrainConfig(input_size=SIZE, ridge_work_px=SIZE // 2)
    x = torch.randn((4, 3, SIZE, SIZE)).abs()
    m = torch.zeros((4, 1, SIZE, SIZE))
    geometry_off = AugmentConfig(flip_p=0.0, affine_p=0.0)
    out, _ = Augmenter(geometry_off, cfg.preprocess, seed=1)(x, m)
    assert out.shape == x.shape
    torch.testing.assert_close(out[:, 2], x[:, 2])  # camera ops leave the ridge energy alone
    assert not torch.allclose(out[:, 0], x[:, 0])


def test_band_centre_is_the_dog_peak() -> None:
    periods = np.linspace(2.5, 12.0, 2000)
    best = periods[np.argmax([_gain(p, CFG) for p in periods])]
    assert 1.0 / ridge_band_frequency(CFG) == pytest.approx(best, abs=0.01)


@pytest.mark.parametrize("sigma_in", [0.3, 0.6, 0.8])
def test_blurred_ridge_gain_matches_a_blurred_sinusoid(sigma_in: float) -> None:
    """Ridges at the band centre, blurred by σ input px (σ·W/S work px): the energy ratio."""
    torch = pytest.importorskip("torch")
    from contactcal.train.augment import blurred_ridge_gain

    x = np.arange(WORK, dtype=np.float32)
    period = 1.0 / ridge_band_frequency(CFG)
    work = np.ascontiguousarray(
        np.broadcast_to(100.0 + 20.0 * np.sin(2 * np.pi * x / period), (WORK, WORK)), np.float32
    )
    blurred = cv2.GaussianBlur(work, (0, 0), sigma_in * WORK / SIZE)
    c = slice(SIZE // 4, -SIZE // 4)
    sharp_e = float(np.median(ridge_energy(work, CFG, 200.0)[c, c]))
    blur_e = float(np.median(ridge_energy(blurred, CFG, 200.0)[c, c]))
    gain = float(blurred_ridge_gain(torch.tensor([sigma_in]), CFG)[0])
    assert blur_e / sharp_e == pytest.approx(gain, rel=0.1, abs=0.005)


def test_augmenter_ridge_blur_weakens_only_the_ridge_channel() -> None:
    """Same draws with and without ridge_blur; exactly the blurred samples' ridge energy fades,
    by the gain of the σ drawn for them."""
    torch = pytest.importorskip("torch")
    pytest.importorskip("kornia")
    from contactcal.train.augment import AugmentConfig, Augmenter, blurred_ridge_gain
    from contactcal.train.config import TrainConfig

    cfg = TrainConfig(input_size=SIZE, ridge_work_px=WORK).resolved()
    x = torch.rand((8, 3, SIZE, SIZE), generator=torch.Generator().manual_seed(3)) * 0.5 + 0.5
    m = torch.zeros((8, 1, SIZE, SIZE))
    base = AugmentConfig(  # blur is the only camera operation left
        flip_p=0.0, affine_p=0.0, brightness=0.0, contrast=0.0, gamma=(1.0, 1.0), noise_p=0.0,
        blur_p=0.5, blur_sigma=(0.5, 1.2),
    )  # fmt: skip
    sharp, _ = Augmenter(base, cfg.preprocess, seed=2)(x, m)
    aug = Augmenter(dataclasses.replace(base, ridge_blur=True), cfg.preprocess, seed=2)
    soft, _ = aug(x, m)
    torch.testing.assert_close(soft[:, :2], sharp[:, :2])
    torch.testing.assert_close(sharp[:, 2], x[:, 2])
    ratio = (soft[:, 2] / x[:, 2]).flatten(1)
    torch.testing.assert_close(ratio.min(1).values, ratio.max(1).values)  # one gain per sample
    blurred = (soft[:, 0] - x[:, 0]).flatten(1).abs().amax(1) > 1e-4
    assert 0 < int(blurred.sum()) < 8
    blur = next(p.data for p in aug.camera._params if p.name.startswith("RandomGaussianBlur"))
    sigma = torch.where(blurred, blur["sigma"], torch.zeros_like(blur["sigma"]))
    torch.testing.assert_close(ratio[:, 0], blurred_ridge_gain(sigma, cfg.preprocess))
    assert bool((ratio[blurred, 0] < 0.7).all())  # σ ≥ 0.5 input px: a visible loss
    with pytest.raises(ValueError, match="ridge_blur needs the ridge-energy channel"):
        TrainConfig(input_size=SIZE, augment=AugmentConfig(ridge_blur=True))


def test_drawn_blur_sigma_both_kornia_layouts() -> None:
    torch = pytest.importorskip("torch")
    from contactcal.train.augment import drawn_blur_sigma

    applied = torch.tensor([1.0, 0.0, 1.0, 0.0])
    full = torch.tensor([0.4, 0.9, 0.7, 0.2])
    expected = torch.tensor([0.4, 0.0, 0.7, 0.0])
    torch.testing.assert_close(drawn_blur_sigma(full, applied), expected)
    torch.testing.assert_close(drawn_blur_sigma(torch.tensor([0.4, 0.7]), applied), expected)
    torch.testing.assert_close(drawn_blur_sigma(torch.tensor([]), torch.zeros(4)), torch.zeros(4))
    with pytest.raises(ValueError, match="3 sigmas for 2 blurred of 4 samples"):
        drawn_blur_sigma(torch.tensor([0.1, 0.2, 0.3]), applied)


def test_cli_ridge_blur_option() -> None:
    import argparse

    pytest.importorskip("torch")
    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser(prog="contactcal")
    add_parsers(parser.add_subparsers(dest="command", required=True))
    base = ["train", "--data", "a", "--out", "r", "--input-size", "64", "--ridge-channel", "96"]
    assert build_config(parser.parse_args([*base, "--ridge-blur"])).augment.ridge_blur
    assert not build_config(parser.parse_args(base)).augment.ridge_blur
    with pytest.raises(ValueError, match="ridge-energy channel"):
        build_config(parser.parse_args([*base[:-2], "--ridge-blur"]))

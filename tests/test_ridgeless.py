"""``train.ridgeless``: contact patches with their ridges erased are labelled "no contact"."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("kornia")

from contactcal.train.ridgeless import RidgelessConfig, ridgeless  # noqa: E402

S = 44  # crop = 2.2 ring radii → ring radius 20 px
CROP = 2.2


def _batch(n: int = 4, ridge_inside: float = 1.0) -> tuple[torch.Tensor, torch.Tensor]:
    """Frame with a striped 'ridge' disc; channel 1 a flat reference; channel 2 ridge energy
    (``ridge_inside`` in the disc, 0.2 on the membrane)."""
    yy, xx = torch.meshgrid(torch.arange(S), torch.arange(S), indexing="ij")
    disc = ((yy - S / 2 + 0.5) ** 2 + (xx - S / 2 + 0.5) ** 2 < 6.0**2).float()
    frame = 0.3 * (1 - disc) + (0.5 + 0.15 * torch.sin(xx * 2.0)) * disc
    energy = 0.2 * (1 - disc) + ridge_inside * disc
    u = torch.stack([frame, torch.full((S, S), 0.3), energy]).expand(n, 3, S, S).clone()
    return u, disc.expand(n, 1, S, S).clone()


def test_erased_patch_loses_ridges_not_level_and_mask() -> None:
    u, m = _batch()
    cfg = RidgelessConfig(p=1.0, keep=(0.0, 0.0), level=(1.0, 1.0))
    out, mo = ridgeless(u, m, cfg, torch.Generator().manual_seed(0), CROP)
    assert out.shape == u.shape and mo.shape == m.shape
    assert float(mo.sum()) == 0.0  # labelled no contact
    core = (slice(None), 0, slice(S // 2 - 3, S // 2 + 3), slice(S // 2 - 3, S // 2 + 3))
    assert float(out[core].std()) < 0.2 * float(u[core].std())  # ridges gone
    assert float(out[core].mean()) == pytest.approx(float(u[core].mean()), abs=0.03)  # level kept
    centre = out[:, 2, S // 2, S // 2]
    assert torch.allclose(centre, torch.full_like(centre, 0.2), atol=1e-4)  # membrane level
    assert torch.equal(out[:, 1], u[:, 1])  # reference untouched
    assert torch.equal(out[:, :, :3, :3], u[:, :, :3, :3])  # far outside untouched


def test_invisible_ridges_and_p_zero_unchanged() -> None:
    u, m = _batch(ridge_inside=0.25)  # inside/outside 1.25 < min_ratio 1.5
    g = torch.Generator().manual_seed(0)
    out, mo = ridgeless(u, m, RidgelessConfig(p=1.0), g, CROP)
    assert torch.equal(out, u) and torch.equal(mo, m)
    u, m = _batch()
    out, mo = ridgeless(u, m, RidgelessConfig(p=0.0), g, CROP)
    assert out is u and mo is m
    out, mo = ridgeless(u, torch.zeros_like(m), RidgelessConfig(p=1.0), g, CROP)
    assert torch.equal(out, u)  # no contact: nothing to erase


def test_share_and_determinism() -> None:
    u, m = _batch(64)
    cfg = RidgelessConfig(p=0.25)
    a = ridgeless(u, m, cfg, torch.Generator().manual_seed(3), CROP)
    b = ridgeless(u, m, cfg, torch.Generator().manual_seed(3), CROP)
    assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[1])
    erased = int((a[1].flatten(1).sum(1) == 0).sum())
    assert 6 <= erased <= 26  # ~16 of 64


@pytest.mark.parametrize(
    "bad",
    [
        {"p": 1.5},
        {"keep": (0.3, 0.1)},
        {"level": (0.0, 1.0)},
        {"min_ratio": -1.0},
        {"flatten": 2.0},
        {"membrane_radius": 0.0},
        {"low_sigma_px": 0.0},
        {"edge_sigma_px": -1.0},
    ],
)
def test_bad_config(bad: dict) -> None:
    with pytest.raises(ValueError, match="RidgelessConfig"):
        RidgelessConfig(**bad)


def test_needs_ridge_channel() -> None:
    from contactcal.train.augment import AugmentConfig
    from contactcal.train.config import TrainConfig

    aug = AugmentConfig(ridgeless=RidgelessConfig(p=0.2))
    with pytest.raises(ValueError, match="ridge-energy channel"):
        TrainConfig(augment=aug)
    TrainConfig(augment=aug, ridge_work_px=288, input_size=192)
    flat_only = AugmentConfig(ridgeless=RidgelessConfig(flatten=0.5))
    with pytest.raises(ValueError, match="--ridgeless P"):
        TrainConfig(augment=flat_only, ridge_work_px=288, input_size=192)


def test_no_membrane_energy_outside_leaves_the_frame() -> None:
    """A ridge channel of 0 outside the patch gives no level to erase to: nothing changes."""
    u, m = _batch()
    u[:, 2] = u[:, 2] * m[:, 0]  # energy inside only
    out, mo = ridgeless(u, m, RidgelessConfig(p=1.0), torch.Generator().manual_seed(0), CROP)
    assert torch.equal(out, u) and torch.equal(mo, m)


def test_cli_option_sets_the_share() -> None:
    import argparse

    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser(prog="contactcal")
    add_parsers(parser.add_subparsers(dest="command", required=True))
    base = ["train", "--data", "a", "--out", "r", "--input-size", "64"]
    cfg = build_config(parser.parse_args([*base, "--ridge-channel", "96", "--ridgeless", "0.3"]))
    assert cfg.augment.ridgeless.p == 0.3 and cfg.augment.ridgeless.min_ratio == 1.5
    assert cfg.augment.ridgeless.flatten == 0.0
    argv = [*base, "--ridge-channel", "96", "--ridgeless", "0.3", "--ridgeless-flatten", "0.5"]
    assert build_config(parser.parse_args(argv)).augment.ridgeless.flatten == 0.5
    assert build_config(parser.parse_args(base)).augment.ridgeless.p == 0.0
    with pytest.raises(ValueError, match="ridge-energy channel"):
        build_config(parser.parse_args([*base, "--ridgeless", "0.3"]))


def test_augmenter_empties_erased_masks() -> None:
    """Through the Augmenter (warp, look, erasure, camera): masks stay binary; with p = 1 and no
    geometric change every frame with visible ridges comes out labelled "no contact"."""
    from contactcal.infer.methods.unet.config import PreprocessConfig
    from contactcal.infer.methods.unet.prepare import unit_to_network
    from contactcal.train.augment import AugmentConfig, Augmenter

    pre = PreprocessConfig(input_size=S, ridge_work_px=S)
    aug = AugmentConfig(affine_p=0.0, flip_p=0.0, ridgeless=RidgelessConfig(p=1.0))
    u, m = _batch(6)
    x = torch.cat([unit_to_network(u[:, :2], pre), u[:, 2:]], 1)
    out, mo = Augmenter(aug, pre, seed=0)(x, m)
    assert out.shape == x.shape and set(mo.unique().tolist()) <= {0.0, 1.0}
    assert float(mo.sum()) == 0.0


def test_flatten_gives_the_patch_the_membrane_level() -> None:
    """flatten = 1: the patch's grey level becomes the membrane's (0.3 × level 1), ridges gone."""
    u, m = _batch()
    cfg = RidgelessConfig(p=1.0, keep=(0.0, 0.0), level=(1.0, 1.0), flatten=1.0)
    out, mo = ridgeless(u, m, cfg, torch.Generator().manual_seed(0), CROP)
    core = out[:, 0, S // 2 - 2 : S // 2 + 2, S // 2 - 2 : S // 2 + 2]
    assert torch.allclose(core, torch.full_like(core, 0.3), atol=0.02)
    assert float(mo.sum()) == 0.0

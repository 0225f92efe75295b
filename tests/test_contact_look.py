"""``train.contact_look``: the contact region's brightness and ridge contrast, training only."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("kornia")

from contactcal.train.contact_look import ContactLookConfig, contact_look  # noqa: E402

S = 32


def _batch(n: int = 4) -> tuple[torch.Tensor, torch.Tensor]:
    """Frames with a striped 'ridge' disc on a flat membrane; channel 1 a flat reference."""
    yy, xx = torch.meshgrid(torch.arange(S), torch.arange(S), indexing="ij")
    disc = ((yy - S / 2) ** 2 + (xx - S / 2) ** 2 < (S / 4) ** 2).float()
    ridges = 0.4 + 0.1 * torch.sin(xx * 2.0)  # period ~3 px
    frame = 0.3 * (1 - disc) + ridges * disc
    u = torch.stack([frame, torch.full((S, S), 0.3)]).expand(n, 2, S, S).clone()
    return u, disc.expand(n, 1, S, S).clone()


def test_shape_range_and_channels() -> None:
    u, m = _batch()
    out = contact_look(u, m, ContactLookConfig(p=1.0), torch.Generator().manual_seed(0))
    assert out.shape == u.shape and out.dtype == u.dtype
    assert float(out.min()) >= 0.0 and float(out.max()) <= 1.0
    assert torch.equal(out[:, 1], u[:, 1])  # the reference has no contact
    assert not torch.equal(out[:, 0], u[:, 0])


def test_no_contact_and_p_zero_unchanged() -> None:
    u, m = _batch()
    g = torch.Generator().manual_seed(0)
    assert torch.equal(contact_look(u, torch.zeros_like(m), ContactLookConfig(p=1.0), g), u)
    assert torch.equal(contact_look(u, m, ContactLookConfig(p=0.0), g), u)


def test_gain_and_detail_reference_values() -> None:
    """Fixed factors: the disc's mean scales by ``gain``, its ripple by ``gain × detail``;
    far outside the disc nothing changes."""
    u, m = _batch(1)
    cfg = ContactLookConfig(p=1.0, gain=(1.5, 1.5), detail=(2.0, 2.0))
    out = contact_look(u, m, cfg, torch.Generator().manual_seed(0))
    core = (slice(None), 0, slice(S // 2 - 3, S // 2 + 3), slice(S // 2 - 3, S // 2 + 3))
    assert float(out[core].mean()) == pytest.approx(1.5 * float(u[core].mean()), rel=0.05)
    assert float(out[core].std()) == pytest.approx(3.0 * float(u[core].std()), rel=0.1)
    assert torch.equal(out[0, 0, :3, :3], u[0, 0, :3, :3])


def test_deterministic_per_generator_seed() -> None:
    u, m = _batch(8)
    cfg = ContactLookConfig()
    a = contact_look(u, m, cfg, torch.Generator().manual_seed(5))
    b = contact_look(u, m, cfg, torch.Generator().manual_seed(5))
    c = contact_look(u, m, cfg, torch.Generator().manual_seed(6))
    assert torch.equal(a, b) and not torch.equal(a, c)


@pytest.mark.parametrize(
    "kwargs",
    [{"p": 1.5}, {"gain": (0.0, 1.0)}, {"detail": (2.0, 1.0)}, {"edge_sigma_px": 0.0}],
)
def test_bad_config(kwargs: dict[str, object]) -> None:
    with pytest.raises(ValueError, match="ContactLookConfig"):
        ContactLookConfig(**kwargs)  # type: ignore[arg-type]


def test_cli_contact_gain() -> None:
    import argparse

    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser()
    add_parsers(parser.add_subparsers())
    base = ["train", "--data", "d", "--out", "r"]
    assert build_config(parser.parse_args(base)).augment.contact.gain == (0.6, 1.5)
    cfg = build_config(parser.parse_args([*base, "--contact-gain", "0.3", "1.5"]))
    assert cfg.augment.contact.gain == (0.3, 1.5) and cfg.augment.contact.detail == (0.5, 3.0)
    with pytest.raises(ValueError, match="gain must be 0 < lo <= hi"):
        build_config(parser.parse_args([*base, "--contact-gain", "1.5", "0.3"]))


def test_cli_camera_ranges() -> None:
    import argparse

    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser()
    add_parsers(parser.add_subparsers())
    base = ["train", "--data", "d", "--out", "r"]
    cfg = build_config(parser.parse_args(base))
    assert (cfg.augment.gamma, cfg.augment.blur_sigma) == ((0.7, 1.4), (0.1, 1.2))
    args = [*base, "--gamma", "0.6", "1.7", "--blur-sigma", "0.1", "1.8"]
    args += ["--ridge-channel", "288", "--ridge-blur"]
    cfg = build_config(parser.parse_args(args))
    assert (cfg.augment.gamma, cfg.augment.blur_sigma) == ((0.6, 1.7), (0.1, 1.8))
    assert cfg.augment.ridge_blur
    for bad in (["--gamma", "1.7", "0.6"], ["--blur-sigma", "0", "1"]):
        with pytest.raises(ValueError, match="expected a range 0 < lo <= hi"):
            build_config(parser.parse_args([*base, *bad]))


def test_cli_blur_share() -> None:
    """--blur-p sets the share of blurred training frames (H18's lever: placing the edge without
    ridges); a value outside [0, 1] is refused naming the option."""
    import argparse

    from contactcal.train.commands import add_parsers, build_config

    parser = argparse.ArgumentParser()
    add_parsers(parser.add_subparsers())
    base = ["train", "--data", "d", "--out", "r"]
    assert build_config(parser.parse_args(base)).augment.blur_p == 0.3
    assert build_config(parser.parse_args([*base, "--blur-p", "0.6"])).augment.blur_p == 0.6
    for bad in ("1.5", "-0.1"):
        said = rf"--blur-p {bad}: expected a probability in \[0, 1\]"
        with pytest.raises(ValueError, match=said):
            build_config(parser.parse_args([*base, "--blur-p", bad]))

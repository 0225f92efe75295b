"""Contact appearance randomisation: how bright the skin looks, and how strong its ridges are.

A renderer fixes how the contact region looks against the rest of the membrane: in our Mitsuba
renders the skin glows brighter than the surrounding membrane and its ridges are faint at the
network's input size, so a model can learn "bright blob = contact" instead of the ridges and the
inner ring that define it. On other generators (``synth/procedural``) and on the real rig the
skin can be as bright as the membrane, darker, or carry saturated ridges. This augmentation uses
the (already warped) training mask to change, inside the contact only and with a soft edge:

- the region's brightness, ``gain`` (× about its own local mean);
- its fine detail (the ridges): ``detail`` × (frame − local mean).

Both are drawn log-uniformly from a seeded ``torch.Generator`` and applied to the frame channel
only (a reference frame has no contact). Frames without contact are left unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import kornia.filters as KF
import torch


@dataclass(frozen=True)
class ContactLookConfig:
    """Ranges of the contact-region appearance change (training only)."""

    p: float = 0.5  # probability per frame; the rest keep the renderer's look
    gain: tuple[float, float] = (0.6, 1.5)  # × contact brightness; 1 = as rendered (skin
    #   darker to brighter than the membrane); wider teaches less about brightness
    detail: tuple[float, float] = (0.5, 3.0)  # × ridge contrast; 3 turns faint rendered ridges
    #   into saturated ones, 0.5 hides them further
    edge_sigma_px: float = 1.0  # px at input size, softness of the region's edge
    low_sigma_px: float = 1.5  # px at input size, local mean that separates detail from level

    def __post_init__(self) -> None:
        if not 0.0 <= self.p <= 1.0:
            raise ValueError(f"ContactLookConfig.p must be in [0, 1], got {self.p}")
        for name in ("gain", "detail"):
            lo, hi = getattr(self, name)
            if not 0.0 < lo <= hi:
                raise ValueError(f"ContactLookConfig.{name} must be 0 < lo <= hi, got {lo, hi}")
        if not (self.edge_sigma_px > 0.0 and self.low_sigma_px > 0.0):
            raise ValueError("ContactLookConfig: edge_sigma_px and low_sigma_px must be > 0")


def log_uniform(n: int, lo: float, hi: float, generator: torch.Generator) -> torch.Tensor:
    """``(n,)`` float32 factors, log-uniform in ``[lo, hi]``."""
    r = torch.rand(n, generator=generator)
    lo_t, hi_t = torch.log(torch.tensor(lo)), torch.log(torch.tensor(hi))
    return torch.exp(lo_t + r * (hi_t - lo_t))


def blur(x: torch.Tensor, sigma: float) -> torch.Tensor:
    """Gaussian blur of ``(N, C, S, S)`` with a kernel of ±3σ (odd size)."""
    k = 2 * max(1, round(3.0 * sigma)) + 1
    return KF.gaussian_blur2d(x, (k, k), (sigma, sigma), border_type="replicate")


def contact_look(
    u: torch.Tensor,
    mask: torch.Tensor,
    config: ContactLookConfig,
    generator: torch.Generator,
    ridge: bool = False,
) -> torch.Tensor:
    """Change the contact region's brightness and ridge contrast in channel 0.

    Args:
        u: ``(N, C, S, S) float32``; channel 0 = the frame, intensities in ``[0, 1]``.
        mask: ``(N, 1, S, S) float32`` contact mask in {0, 1}, registered with ``u``.
        config: ranges.
        generator: CPU generator the per-frame draws come from (3 draws of ``N`` values).
        ridge: the last channel is the ridge energy (RMS ridge amplitude); it is scaled by
            ``gain × detail`` inside the region, as the frame's ridges are.

    Returns:
        ``(N, C, S, S)`` float32 (the frame in ``[0, 1]``); frames not drawn, or without
        contact, unchanged.
    """
    n = u.shape[0]
    apply = torch.rand(n, generator=generator) < config.p
    gain = log_uniform(n, *config.gain, generator)
    detail = log_uniform(n, *config.detail, generator)
    if not bool(apply.any()):
        return u
    dev = u.device
    frame = u[:, :1]
    low = blur(frame, config.low_sigma_px)
    g = gain.to(dev).view(n, 1, 1, 1)
    k = detail.to(dev).view(n, 1, 1, 1)
    changed = (g * (low + k * (frame - low))).clamp(0.0, 1.0)
    soft = blur(mask.to(frame.dtype), config.edge_sigma_px) * apply.to(dev).view(n, 1, 1, 1)
    out = u.clone()
    out[:, :1] = frame + soft * (changed - frame)
    if ridge:
        out[:, -1:] = u[:, -1:] * (1.0 + soft * (g * k - 1.0))
    return out

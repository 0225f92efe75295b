"""Ridgeless patches: a contact-shaped region whose fingerprint ridges are erased is *not* contact.

The paper defines contact by its evidence: "at lower pressures, the lack of fingerprints revealed
that contact was either absent or too weak"; the contact region is the ridge region bounded by
the inner ring. A renderer ties other cues to contact too (in ours the skin glows brighter than
the membrane and the inner ring hugs the patch), and a model can learn those instead of the
ridges: on the procedural cross-check generator the shipped model calls the disc inside a sharp
pre-contact ring contact. This augmentation takes a training frame with contact and visible
ridges, keeps everything but the ridges (the patch's brightness, its edge, the inner ring
around it), and labels it "no contact":

- frame channel, inside the mask (soft edge): local level (Gaussian σ ``low_sigma_px``) plus
  ``keep`` × the detail, ``keep`` drawn in ``config.keep`` (0 = smooth, a little = faded);
- with probability ``flatten`` the patch also loses its own brightness: its level becomes the
  membrane's outside it (× a factor in ``level``), so only the ring around it is left — the
  look of the inner ring before contact, shrinking around a membrane that touches nothing;
- ridge-energy channel, inside the mask: rescaled so its median becomes the frame's membrane
  level outside the patch (× a factor in ``config.level``), i.e. the energy of a smooth membrane
  with its noise and sparkle;
- the mask becomes empty.

Only frames whose ridges are visible take part (median ridge energy inside ≥ ``min_ratio`` × the
membrane's outside): a hard render whose ridges are already invisible stays a (hard) contact.
Applied after :func:`~contactcal.train.contact_look.contact_look`, before the camera operations.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from contactcal.train.contact_look import blur, log_uniform


@dataclass(frozen=True)
class RidgelessConfig:
    """Ranges of the ridge erasure (training only; ``p = 0`` draws nothing: old runs unchanged)."""

    p: float = 0.0  # probability per eligible frame; more teaches "no ridges → no contact"
    #   harder but leaves fewer positive frames (and onset frames with faint ridges at risk)
    keep: tuple[float, float] = (0.0, 0.2)  # × detail left inside the patch; > 0 keeps a
    #   trace of noise and sparkle so the patch is not suspiciously smooth
    level: tuple[float, float] = (0.7, 1.4)  # × outside membrane level = ridge energy inside
    #   (and, when flattened, the patch's grey level)
    flatten: float = 0.0  # share of erased patches whose brightness also becomes the membrane's;
    #   0 keeps the renderer's bright (or dark) patch, 1 leaves only the ring around it
    min_ratio: float = 1.5  # inside/outside median ridge energy needed to take part; 0 = every
    #   contact frame with ridge energy on both sides (invisible ridges then get both labels)
    membrane_radius: float = 0.8  # × the ring radius: the "outside" disc (crop = 2.2 radii)
    low_sigma_px: float = 1.5  # px at input size, local level that separates ridges from level
    edge_sigma_px: float = 1.0  # px at input size, softness of the patch edge

    def __post_init__(self) -> None:
        if not 0.0 <= self.p <= 1.0:
            raise ValueError(f"RidgelessConfig.p must be in [0, 1], got {self.p}")
        lo, hi = self.keep
        if not 0.0 <= lo <= hi <= 1.0:
            raise ValueError(f"RidgelessConfig.keep must be 0 <= lo <= hi <= 1, got {self.keep}")
        lo, hi = self.level
        if not 0.0 < lo <= hi:
            raise ValueError(f"RidgelessConfig.level must be 0 < lo <= hi, got {self.level}")
        if not 0.0 <= self.flatten <= 1.0:
            raise ValueError(f"RidgelessConfig.flatten must be in [0, 1], got {self.flatten}")
        if self.min_ratio < 0.0 or not 0.0 < self.membrane_radius <= 1.0:
            raise ValueError("RidgelessConfig: min_ratio >= 0 and 0 < membrane_radius <= 1")
        if not (self.low_sigma_px > 0.0 and self.edge_sigma_px > 0.0):
            raise ValueError("RidgelessConfig: low_sigma_px and edge_sigma_px must be > 0")


def _levels(
    planes: torch.Tensor,
    mask: torch.Tensor,
    which: torch.Tensor,
    config: RidgelessConfig,
    crop_factor: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Medians inside the mask and on the membrane outside it, for the frames in ``which``.

    Args:
        planes: ``(N, K, S, S)``; each of the K planes is measured.
        mask: ``(N, 1, S, S)`` in {0, 1}.
        which: ``(N,)`` bool (CPU), the frames to measure (the drawn ones).

    Returns:
        ``(inside, outside)``, each ``(N, K)`` on the CPU; zeros for frames not in ``which`` and
        where either region is empty.
    """
    n, k, s, _ = planes.shape
    c = (torch.arange(s, device=planes.device, dtype=planes.dtype) + 0.5) - s / 2
    r = torch.sqrt(c.view(-1, 1) ** 2 + c.view(1, -1) ** 2)
    disc = r < config.membrane_radius * s / crop_factor
    near = F.max_pool2d(mask, 7, stride=1, padding=3) > 0.5  # the patch and its ring
    inside, outside = torch.zeros(n, k), torch.zeros(n, k)
    for i in torch.nonzero(which).flatten().tolist():
        m_in, m_out = mask[i, 0] > 0.5, disc & ~near[i, 0]
        if bool(m_in.any()) and bool(m_out.any()):
            inside[i] = planes[i][:, m_in].median(dim=1).values.cpu()
            outside[i] = planes[i][:, m_out].median(dim=1).values.cpu()
    return inside, outside


def ridgeless(
    u: torch.Tensor,
    mask: torch.Tensor,
    config: RidgelessConfig,
    generator: torch.Generator,
    crop_factor: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Erase the ridges of some contact patches and label those frames "no contact".

    Args:
        u: ``(N, C, S, S) float32``; channel 0 the frame (intensities in ``[0, 1]``), the last
            channel the ridge energy (network units, ``infer.methods.unet.ridge``).
        mask: ``(N, 1, S, S) float32`` contact mask in {0, 1}, registered with ``u``.
        config: ranges; with ``config.p == 0`` nothing is drawn and ``(u, mask)`` is returned.
        generator: CPU generator of the per-frame draws (3 draws of ``N`` values, a 4th when
            ``config.flatten > 0``).
        crop_factor: crop side / ring radius of the preprocessing (the membrane's extent).

    Returns:
        ``(u, mask)`` of the same shapes; erased frames have an all-zero mask.
    """
    if config.p <= 0.0:
        return u, mask
    n = u.shape[0]
    draw = torch.rand(n, generator=generator) < config.p
    keep = config.keep[0] + torch.rand(n, generator=generator) * (config.keep[1] - config.keep[0])
    level = log_uniform(n, *config.level, generator)
    flat = torch.rand(n, generator=generator) < config.flatten if config.flatten > 0 else None
    if not bool(draw.any()):
        return u, mask
    planes = torch.cat([u[:, -1:], u[:, :1]], 1)
    inside, outside = _levels(planes, mask, draw, config, crop_factor)
    ridge_in, ridge_out = inside[:, 0], outside[:, 0]
    erase = draw & (ridge_out > 0) & (ridge_in >= config.min_ratio * ridge_out)
    if not bool(erase.any()):
        return u, mask
    dev = u.device
    on = erase.to(dev).view(n, 1, 1, 1).to(u.dtype)
    soft = blur(mask, config.edge_sigma_px) * on
    frame = u[:, :1]
    low = blur(frame, config.low_sigma_px)
    detail = frame - low
    if flat is not None:  # the patch's level → the membrane's: × target / the patch's median
        gain = torch.where(flat, level * outside[:, 1] / inside[:, 1].clamp_min(1e-3), 1.0)
        low = low * gain.to(dev).view(n, 1, 1, 1)
    smooth = (low + keep.to(dev).view(n, 1, 1, 1) * detail).clamp(0.0, 1.0)
    scale = torch.where(erase, level * ridge_out / ridge_in.clamp_min(1e-6), 1.0)
    out = u.clone()
    out[:, :1] = frame + soft * (smooth - frame)
    out[:, -1:] = u[:, -1:] * (1.0 + soft * (scale.to(dev).view(n, 1, 1, 1) - 1.0))
    return out, mask * (1.0 - on)

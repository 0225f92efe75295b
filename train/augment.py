"""Batch augmentation with kornia: image and mask transformed together.

The cached network inputs are normalised (``contactcal.infer.methods.unet.prepare``);
augmentation maps them back to ``[0, 1]`` intensities with the same constants
(``network_to_unit``), so that photometric operations (gamma, contrast, clipping) and zero padding
mean what they do on a camera image, and then re-applies ``unit_to_network``. With a dark floor
(``norm_floor_percentile`` > 0) the camera operations act on grey levels instead: each image
channel is mapped back to them with the levels its normalisation used (``CachedSet.levels``) and,
after brightness, contrast and gamma, normalised again between those levels as the same operations
moved them, which is what deployment computes on such a frame (the percentiles commute with these
monotone operations). Blur and noise then change the frame without moving the levels, as they do
without a floor.

Randomness: the :class:`Augmenter` owns an explicit, seeded ``torch.Generator`` (its
``generator``). kornia draws from torch's global generators, so each batch draws one seed from the
Augmenter's generator and runs kornia inside ``torch.random.fork_rng`` with the global CPU (and
the batch's CUDA device) generator seeded from it: the augmentations depend only on the
Augmenter's seed and the number of batches seen, the global generators are left untouched, and
the Augmenter's generator state is all a checkpoint needs to resume bit-exactly.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import kornia.augmentation as K
import torch

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.prepare import network_to_unit, unit_to_network
from contactcal.infer.methods.unet.ridge import ridge_band_frequency
from contactcal.train.contact_look import ContactLookConfig, contact_look
from contactcal.train.ridgeless import RidgelessConfig, ridgeless

#: The first camera operations, pointwise and increasing (brightness, contrast, gamma): the
#: levels of a floored normalisation move with them (``Augmenter._floored_camera``).
TONE_OPS = 3


@dataclass(frozen=True)
class AugmentConfig:
    """Augmentation ranges; each models a real rig/camera variation the renderer does not."""

    enabled: bool = True  # False: train on the rendered frames as they are (ablation, debugging)
    brightness: float = 0.1  # ± additive, in [0, 1] units; exposure offset / stray light
    contrast: float = 0.25  # ± multiplicative; camera gain; too much hides faint ridges
    gamma: tuple[float, float] = (0.7, 1.4)  # tone curve range; camera/sensor response
    flip_p: float = 0.5  # probability of each of the horizontal and vertical flips
    rotation_deg: float = 180.0  # ± degrees; the rig is rotationally symmetric about the axis
    translate: float = 0.03  # fraction of the side; ring-fit error of the crop
    scale: tuple[float, float] = (0.92, 1.08)  # zoom range; ring radius/finger size variation
    affine_p: float = 0.8  # probability of the rotation/translation/scale
    blur_sigma: tuple[float, float] = (0.1, 1.2)  # px at input size; defocus (too much erases
    #   ridges)
    blur_p: float = 0.3  # probability of a blur
    blur_kernel_px: int = 0  # taps of the blur kernel; 0 = 2·⌈3·σ_max⌉ + 1, the whole Gaussian
    #   (9 for σ 1.2); 5 (models up to v2.2) truncates σ ≳ 0.8: σ 1.2 blurred like ~1.08
    noise_std: float = 0.02  # in [0, 1] units; sensor noise
    noise_p: float = 0.5  # probability of added noise
    ridge_blur: bool = False  # the drawn blur also weakens the ridge-energy channel, as it weakens
    #   ridges at the band's centre (``blurred_ridge_gain``); False keeps that channel sharp under
    #   blur (v2.1), which a defocused rig frame contradicts
    contact: ContactLookConfig = field(default_factory=ContactLookConfig)  # the contact region's
    #   brightness and ridge contrast (``contact_look``), after the warp, before the camera ops
    ridgeless: RidgelessConfig = field(default_factory=RidgelessConfig)  # contact patches with
    #   their ridges erased, labelled "no contact" (``ridgeless``; needs the ridge channel)

    def __post_init__(self) -> None:
        for name in ("gamma", "scale", "blur_sigma"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise ValueError(
                    f"AugmentConfig.{name}: expected a range 0 < lo <= hi, got ({lo}, {hi})"
                )
        if self.blur_kernel_px != 0 and (self.blur_kernel_px < 3 or self.blur_kernel_px % 2 == 0):
            raise ValueError(
                f"AugmentConfig.blur_kernel_px must be 0 (whole Gaussian) or odd >= 3, "
                f"got {self.blur_kernel_px}"
            )
        for name in ("flip_p", "affine_p", "blur_p", "noise_p"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(
                    f"AugmentConfig.{name} must be in [0, 1], got {getattr(self, name)}"
                )


class Augmenter(torch.nn.Module):
    """Random geometric + photometric transform of ``(x, mask)`` batches.

    Args:
        config: augmentation ranges.
        preprocess: the normalisation constants of the cached inputs.
        seed: seed of the Augmenter's own generator (``self.generator``, CPU); save and restore
            its ``get_state()`` / ``set_state()`` to resume.
        reference_dropout: share of samples whose reference channel (channel 1 of a 2-channel
            input) becomes the blank placeholder, drawn from ``self.generator``.
    """

    def __init__(
        self,
        config: AugmentConfig,
        preprocess: PreprocessConfig,
        seed: int = 0,
        reference_dropout: float = 0.0,
    ) -> None:
        super().__init__()
        self.config = config
        self.reference_dropout = reference_dropout
        self.preprocess = preprocess
        self.generator = torch.Generator().manual_seed(seed)
        c = config
        geometric = [
            K.RandomHorizontalFlip(p=c.flip_p),
            K.RandomVerticalFlip(p=c.flip_p),
            K.RandomAffine(
                degrees=c.rotation_deg,
                translate=(c.translate, c.translate),
                scale=c.scale,
                padding_mode="zeros",
                p=c.affine_p,
            ),
        ]
        k = blur_kernel_size(c)
        camera = [
            K.RandomBrightness(brightness=(1.0 - c.brightness, 1.0 + c.brightness), p=0.8),
            K.RandomContrast(contrast=(1.0 - c.contrast, 1.0 + c.contrast), p=0.8),
            K.RandomGamma(gamma=c.gamma, p=0.8),
            K.RandomGaussianBlur(kernel_size=(k, k), sigma=c.blur_sigma, p=c.blur_p),
            K.RandomGaussianNoise(mean=0.0, std=c.noise_std, p=c.noise_p),
        ]
        self.geometric = K.AugmentationSequential(*geometric, data_keys=["input", "mask"])
        self.camera = K.AugmentationSequential(*camera, data_keys=["input"])
        self.tone = K.AugmentationSequential(*camera[:TONE_OPS], data_keys=["input"])

    def forward(
        self, x: torch.Tensor, mask: torch.Tensor, levels: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Augment one batch.

        Args:
            x: ``(N, C, S, S) float32`` normalised network inputs: frame[, reference][, ridge
                energy] (``prepare``). Every channel gets the same warp (the reference and the
                ridge energy stay registered with the frame); the camera operations change the
                image channels only (the ridge energy keeps the renderer's camera);
                :func:`contact_look` changes the frame and the ridge energy, and
                :func:`~contactcal.train.ridgeless.ridgeless` erases the ridges of some contact
                patches and empties their masks (models with a ridge channel).
            mask: ``(N, 1, S, S) float32`` in {0, 1}; warped with nearest-neighbour sampling.
            levels: ``(N, I, 2) float32``, the image channels' grey levels / 255 mapped to 0
                and 1 (``CachedSet.levels``); needed with ``norm_floor_percentile`` > 0.

        Returns:
            ``(x, mask)`` of the same shapes and dtypes; mask stays binary.

        Raises:
            ValueError: a floored normalisation without ``levels``.
        """
        if self.preprocess.norm_floor_percentile > 0.0 and levels is None:
            raise ValueError(
                "Augmenter: norm_floor_percentile > 0 needs each sample's levels "
                "(CachedSet.levels) to take the floor again after the camera operations"
            )
        ridge = self.preprocess.ridge_work_px > 0
        n_img = x.shape[1] - int(ridge)  # image channels (frame[, reference]), intensities
        u = torch.cat(
            [network_to_unit(x[:, :n_img], self.preprocess).clamp(0.0, 1.0), x[:, n_img:]], 1
        )
        m = mask
        if self.config.enabled:
            with self._seeded(x.device):
                u, m = self.geometric(u, mask)
                m = (m > 0.5).to(u.dtype)
                u = contact_look(u, m, self.config.contact, self.generator, ridge=ridge)
                if ridge:
                    u, m = ridgeless(
                        u, m, self.config.ridgeless, self.generator, self.preprocess.crop_factor
                    )
                floored = self.preprocess.norm_floor_percentile > 0.0
                u = self._camera_ops(u, n_img, ridge, levels if floored else None)
        if self.reference_dropout > 0.0 and n_img == 2:
            drop = torch.rand(u.shape[0], generator=self.generator) < self.reference_dropout
            u[drop.to(u.device), 1] = 0.0  # prepare.blank_reference: black, after the warp
        x_out = torch.cat([unit_to_network(u[:, :n_img], self.preprocess), u[:, n_img:]], 1)
        return x_out, (m > 0.5).to(mask.dtype)

    def _camera_ops(
        self, u: torch.Tensor, n_img: int, ridge: bool, levels: torch.Tensor | None
    ) -> torch.Tensor:
        """The camera operations on the image channels (on grey levels, given ``levels``);
        with ``ridge_blur`` the ridge channel loses what the drawn blur takes from ridges (same
        draws as without it)."""
        params = self.camera.forward_parameters(u[:, :n_img].shape)
        if levels is None:
            img = self.camera(u[:, :n_img], params=params).clamp(0.0, 1.0)
        else:
            img = self._floored_camera(u[:, :n_img], levels.to(u), params)
        rest = u[:, n_img:]
        if ridge and self.config.ridge_blur:
            blur = next(p.data for p in params if p.name.startswith("RandomGaussianBlur"))
            sigma = drawn_blur_sigma(blur["sigma"], blur["batch_prob"]).to(u)
            rest = rest * blurred_ridge_gain(sigma, self.preprocess).view(-1, 1, 1, 1)
        return torch.cat([img, rest], 1)

    def _floored_camera(self, u: torch.Tensor, levels: torch.Tensor, params: list) -> torch.Tensor:
        """The camera operations on grey levels, normalised again as deployment would.

        Args:
            u: ``(N, I, S, S)`` image channels in ``[0, 1]``, floored (``(g - F) / (P - F)``).
            levels: ``(N, I, 2)`` their ``(F, P)`` grey levels / 255.
            params: the camera operations' drawn parameters.

        Returns:
            ``(N, I, S, S)`` in ``[0, 1]``: ``(op(g) - op(F)) / (op(P) - op(F))`` with ``op`` the
            drawn brightness, contrast and gamma, then blur and noise.
        """
        lo, hi = levels[..., :1, None], levels[..., 1:, None]  # (N, I, 1, 1)
        gray = self.camera(lo + u * (hi - lo), params=params).clamp(0.0, 1.0)
        ends = self.tone(levels[:, :, None, :], params=params[:TONE_OPS]).clamp(0.0, 1.0)
        lo2, hi2 = ends[..., :1], ends[..., 1:]  # the levels as the tone operations moved them
        return ((gray - lo2) / (hi2 - lo2).clamp_min(1.0 / 255.0)).clamp(0.0, 1.0)

    @contextmanager
    def _seeded(self, device: torch.device) -> Iterator[None]:
        """Run kornia on global generators seeded from ``self.generator``, then restore them."""
        seed = int(torch.randint(0, 2**62, (), generator=self.generator))
        devices: list[int] = []
        if device.type == "cuda":
            devices = [torch.cuda.current_device() if device.index is None else device.index]
        with torch.random.fork_rng(devices=devices):
            torch.random.default_generator.manual_seed(seed)
            for d in devices:
                with torch.cuda.device(d):
                    torch.cuda.manual_seed(seed)
            yield


def blur_kernel_size(config: AugmentConfig) -> int:
    """Taps of the blur kernel: ``config.blur_kernel_px``, or with 0 the odd size that holds the
    largest σ's Gaussian to ±3σ (``2·⌈3·σ_max⌉ + 1``; 9 for σ 1.2 px)."""
    if config.blur_kernel_px:
        return config.blur_kernel_px
    return 2 * math.ceil(3.0 * config.blur_sigma[1]) + 1


def drawn_blur_sigma(sigma: torch.Tensor, batch_prob: torch.Tensor) -> torch.Tensor:
    """``(N,)`` blur σ per sample, 0 where no blur was applied, from kornia's blur parameters.

    Args:
        sigma: the drawn σ, one per sample (kornia 0.9) or one per blurred sample (kornia 0.7).
        batch_prob: ``(N,)`` 1 where the blur was applied, else 0.
    """
    applied = batch_prob > 0.5
    if sigma.numel() == applied.numel():
        return torch.where(applied, sigma, torch.zeros_like(sigma))
    if sigma.numel() != int(applied.sum()):
        raise ValueError(
            f"kornia blur parameters: {sigma.numel()} sigmas for {int(applied.sum())} blurred "
            f"of {applied.numel()} samples"
        )
    out = torch.zeros(applied.numel(), dtype=sigma.dtype, device=sigma.device)
    out[applied] = sigma
    return out


def blurred_ridge_gain(sigma_px: torch.Tensor, preprocess: PreprocessConfig) -> torch.Tensor:
    """What a Gaussian blur leaves of the ridge-energy channel: its transfer at the band's centre.

    A blur of σ input pixels is σ · W / S pixels at the ridge channel's work side ``W``; a ridge
    at the band's centre frequency ``f`` (``ridge_band_frequency``) keeps ``exp(-2π² σ_w² f²)``
    of its amplitude, and the channel (an RMS amplitude) scales with it.

    Args:
        sigma_px: ``(N,)`` blur σ in network-input pixels (0 = no blur).
        preprocess: input size, ridge work side and band.

    Returns:
        ``(N,)`` gains in (0, 1].
    """
    f = ridge_band_frequency(preprocess)
    sigma_work = sigma_px * (preprocess.ridge_work_px / preprocess.input_size)
    return torch.exp(-2.0 * torch.pi**2 * (sigma_work * f) ** 2)

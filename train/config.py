"""A training run's settings (``TrainConfig``, written resolved to ``config.json``) and device."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import torch

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.spec import ModelSpec
from contactcal.train.augment import AugmentConfig, blur_kernel_size
from contactcal.train.checkpoint import config_from_dict
from contactcal.train.model import UNetConfig

#: ``augment.blur_kernel_px`` of a config saved before the field existed: the fixed kernel it
#: trained with, taps.
LEGACY_BLUR_KERNEL_PX = 5
#: px, largest network input side: 5× the shipped 192 and past any CPU budget per frame; larger
#: sides once reached OpenCV's allocator ("Insufficient memory") as a traceback.
MAX_INPUT_SIZE = 1024


@dataclass(frozen=True)
class TrainConfig:
    """Everything a run depends on (written resolved to ``config.json``)."""

    epochs: int = 40  # passes over the training frames; more fits better, costs linear time
    batch_size: int = 16  # frames per step; larger is smoother but fewer steps per epoch
    lr: float = 3e-3  # peak learning rate of the one-cycle schedule; higher diverges
    weight_decay: float = 1e-4  # AdamW decoupled decay; regularises the tiny model lightly
    seed: int = 0  # split, weight init, shuffling and augmentation
    input_size: int = 256  # px, network input side (overrides preprocess.input_size)
    use_reference: bool = True  # 2nd channel = session's zero-pressure frame; helps the onset,
    #   needs a reference frame at deployment
    reference_dropout: float = 0.0  # share of training frames whose reference channel is the
    #   blank placeholder (deployment without a reference frame); more = better without a
    #   reference, less use of the reference's onset cue
    ridge_work_px: int = 0  # px; > 0 adds the ridge-energy channel measured at this crop side
    #   (``infer.methods.unet.ridge``); finer ridges, a finer JPEG decode at deployment
    ema_decay: float = 0.0  # per-step weight of the past in the exponential average of the
    #   weights that is validated and saved (``train/ema.py``); 0 = off (the trained weights);
    #   0.995 spans ~200 steps: a smoother epoch choice, but it lags the one-cycle schedule
    bce_weight: float = 1.0  # weight of per-pixel BCE (calibration, stable gradients)
    dice_weight: float = 1.0  # weight of per-frame soft Dice (small contacts count fully)
    device: str = "auto"  # "cpu", "cuda" or "auto" (cuda when available)
    num_threads: int = 0  # torch CPU threads; 0 = torch's default
    val_fraction: float = 0.2  # fraction of FINGERS held out for validation
    prob_threshold: float = 0.5  # probability above which a pixel is contact
    min_contact_area_px: float = 30.0  # network px at input_size; smaller predicted regions are
    #   "no contact" (higher misses the onset, lower reports specks as contact)
    model: UNetConfig = field(default_factory=UNetConfig)  # in_channels: from use_reference, ridge
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)  # size from input_size
    augment: AugmentConfig = field(default_factory=AugmentConfig)  # training-time only

    def __post_init__(self) -> None:
        if self.epochs < 1 or self.batch_size < 2:
            raise ValueError(
                f"--epochs must be >= 1 and --batch-size >= 2, got {self.epochs}, {self.batch_size}"
            )
        if self.seed < 0:  # numpy and torch seeds are >= 0
            raise ValueError(f"--seed must be >= 0, got {self.seed}")
        if self.num_threads < 0:
            raise ValueError(
                f"num_threads must be >= 0 (0 = torch's default), got {self.num_threads}"
            )
        if self.device not in ("cpu", "cuda", "auto"):
            raise ValueError(f"device must be cpu, cuda or auto, got {self.device!r}")
        if not 16 <= self.input_size <= MAX_INPUT_SIZE:
            raise ValueError(f"--input-size must be 16-{MAX_INPUT_SIZE} px, got {self.input_size}")
        k = blur_kernel_size(self.augment)
        if self.augment.enabled and k // 2 >= self.input_size:  # reflect padding needs less
            raise ValueError(
                f"--blur-sigma {self.augment.blur_sigma[1]:g} / --blur-kernel: a {k}-tap blur "
                f"kernel cannot filter a {self.input_size} px input (at most "
                f"{2 * self.input_size - 1} taps); expected a smaller σ or a larger --input-size"
            )
        if not 0.0 <= self.reference_dropout < 1.0:
            raise ValueError(f"reference_dropout must be in [0, 1), got {self.reference_dropout}")
        if self.reference_dropout > 0.0 and not self.use_reference:
            raise ValueError("reference_dropout needs the reference channel (use_reference)")
        if self.augment.ridgeless.flatten > 0.0 and self.augment.ridgeless.p == 0.0:
            raise ValueError(
                "augment.ridgeless.flatten > 0 does nothing without ridgeless patches: give "
                "augment.ridgeless.p > 0 (contactcal train --ridgeless P)"
            )
        needs_ridge = {
            "augment.ridgeless.p > 0": self.augment.ridgeless.p > 0.0,
            "augment.ridge_blur": self.augment.ridge_blur,
        }
        for what, on in needs_ridge.items():
            if on and self.ridge_work_px <= 0:
                raise ValueError(
                    f"{what} needs the ridge-energy channel (ridge_work_px > 0, "
                    "contactcal train --ridge-channel W)"
                )
        if self.ridge_work_px < 0 or 0 < self.ridge_work_px < self.input_size:
            raise ValueError(
                f"ridge_work_px must be 0 (off) or >= input_size {self.input_size}, "
                f"got {self.ridge_work_px}"
            )
        if not 0.0 <= self.ema_decay < 1.0:
            raise ValueError(f"ema_decay must be in [0, 1) (0 = off), got {self.ema_decay}")
        if not 0.0 < self.prob_threshold < 1.0:
            raise ValueError(f"prob_threshold must be in (0, 1), got {self.prob_threshold}")

    def resolved(self) -> TrainConfig:
        """Copy with the derived fields of the nested configs made consistent."""
        return dataclasses.replace(
            self,
            model=dataclasses.replace(
                self.model,
                in_channels=1 + int(self.use_reference) + int(self.ridge_work_px > 0),
            ),
            preprocess=dataclasses.replace(
                self.preprocess,
                input_size=self.input_size,
                ridge_work_px=self.ridge_work_px,
                no_reference="blank" if self.reference_dropout > 0.0 else "self",
            ),
            augment=dataclasses.replace(
                self.augment, blur_kernel_px=blur_kernel_size(self.augment)
            ),
        )

    def spec(self) -> ModelSpec:
        """The deployment spec of this run (validation, threshold tuning and export use it)."""
        cfg = self.resolved()
        return ModelSpec(
            cfg.model.in_channels, cfg.preprocess, cfg.prob_threshold, cfg.min_contact_area_px
        )


def saved_train_config(data: Any, where: str) -> TrainConfig:
    """A saved ``TrainConfig`` (``config.json``'s ``train``, a checkpoint's ``config``) as the
    run that saved it trained: one saved before ``augment.blur_kernel_px`` existed blurred with
    :data:`LEGACY_BLUR_KERNEL_PX` taps, not with today's default.

    Raises:
        ValueError: unknown field or invalid value (:func:`config_from_dict`).
    """
    if isinstance(data, dict):
        augment = data.get("augment", {})
        if isinstance(augment, dict) and "blur_kernel_px" not in augment:
            data = {**data, "augment": {**augment, "blur_kernel_px": LEGACY_BLUR_KERNEL_PX}}
    return config_from_dict(TrainConfig, data, where)


def resolve_device(name: str) -> torch.device:
    """``"auto"`` → cuda when available, else cpu; ``"cuda"`` without CUDA → ValueError."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise ValueError("device 'cuda' requested but torch sees no CUDA device; use cpu or auto")
    return torch.device(name)

"""Exponential moving average of a model's weights, the copy that is validated and saved.

A small network trained on a few thousand frames ends each epoch at a point that depends on its
last batches; which epoch the validation picks, and how that epoch's model handles frames unlike
the validation fingers, then moves from run to run. Averaging the weights over the last few
hundred steps (Polyak averaging; timm's ``ModelEmaV2``) smooths that walk at no cost at
deployment: the averaged network has the same graph and size.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


@torch.no_grad()
def ema_update(
    average: dict[str, torch.Tensor], current: dict[str, torch.Tensor], decay: float
) -> None:
    """In place, per tensor: ``average ← decay · average + (1 − decay) · current``.

    Floating tensors (weights, BatchNorm running mean and variance) are averaged; integer ones
    (BatchNorm's batch counter) are copied.

    Args:
        average: state dict of the averaged model, updated in place.
        current: state dict of the trained model, same keys and shapes.
        decay: weight of the past, in ``[0, 1)``; 0 copies ``current``.

    Raises:
        ValueError: ``decay`` outside ``[0, 1)``, or the two state dicts differ in keys or shapes.
    """
    if not 0.0 <= decay < 1.0:
        raise ValueError(f"EMA decay must be in [0, 1), got {decay}")
    if average.keys() != current.keys():
        raise ValueError("EMA: the averaged and trained models have different parameters")
    for name, avg in average.items():
        new = current[name].detach()
        if new.shape != avg.shape:
            raise ValueError(f"EMA: {name} is {tuple(new.shape)}, its average {tuple(avg.shape)}")
        if avg.is_floating_point():
            avg.mul_(decay).add_(new.to(avg.dtype), alpha=1.0 - decay)
        else:
            avg.copy_(new)


class WeightAverage:
    """A copy of ``model`` whose weights follow the trained ones by :func:`ema_update`.

    Args:
        model: the model being trained; copied (weights and buffers) at construction.
        decay: weight of the past per optimiser step; the average spans about
            ``1 / (1 − decay)`` steps (0.995: ~200 steps, about two epochs of the 1846-frame
            recipe at batch 16, 80 % of it for training). No warm-up: in the first epochs the
            average still holds much of the initial weights, so early validation rows look
            worse than the trained weights would.

    Raises:
        ValueError: ``decay`` outside ``(0, 1)``.
    """

    def __init__(self, model: nn.Module, decay: float) -> None:
        if not 0.0 < decay < 1.0:
            raise ValueError(f"EMA decay must be in (0, 1), got {decay}")
        self.decay = decay
        self.model = copy.deepcopy(model).eval()
        for p in self.model.parameters():
            p.requires_grad_(False)

    def update(self, model: nn.Module) -> None:
        """Move the average one step towards ``model``'s current weights."""
        ema_update(self.model.state_dict(), model.state_dict(), self.decay)

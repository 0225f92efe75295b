"""A small U-Net for CPU inference: depthwise-separable blocks, bilinear upsampling.

Any input size works: pooling uses ``ceil_mode`` and each decoder level upsamples to its skip
connection's exact size (no padding, no divisibility requirement), which also keeps the ONNX
graph free of shape arithmetic beyond a ``Resize`` to the skip's shape.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn


@dataclass(frozen=True)
class UNetConfig:
    """Architecture; channels at level ``l`` are ``base · 2**l`` (bottleneck: ``l = levels``)."""

    in_channels: int = 1  # frame [+ session reference] [+ ridge energy] (TrainConfig.resolved)
    base: int = 8  # channels at full resolution; ×2 ≈ ×4 parameters and ×2-4 time
    levels: int = 3  # poolings; each doubles the receptive field, costs little (low resolution)
    depthwise: bool = (
        True  # depthwise-separable 3×3 convs: ~8× fewer weights/FLOPs, slightly weaker
    )
    convs_per_block: int = 2  # 3×3 convs per level; more = larger receptive field, slower
    head_bias: float = -2.0  # initial logit (sigmoid ≈ 0.12): contact is the minority class

    def __post_init__(self) -> None:
        if self.in_channels < 1 or self.base < 1 or self.levels < 1 or self.convs_per_block < 1:
            raise ValueError(
                f"UNetConfig: channels, base, levels and convs must be >= 1, got {self}"
            )


def _conv(cin: int, cout: int, depthwise: bool) -> nn.Sequential:
    """3×3 conv (plain or depthwise+pointwise), BN, ReLU: ``(N, cin, H, W) → (N, cout, H, W)``."""
    if depthwise and cin > 1:
        layers: list[nn.Module] = [
            nn.Conv2d(cin, cin, 3, padding=1, groups=cin, bias=False),
            nn.Conv2d(cin, cout, 1, bias=False),
        ]
    else:  # a depthwise conv on 1-2 input channels would see too little: use a full conv
        layers = [nn.Conv2d(cin, cout, 3, padding=1, bias=False)]
    return nn.Sequential(*layers, nn.BatchNorm2d(cout), nn.ReLU(inplace=True))


def _block(cin: int, cout: int, config: UNetConfig) -> nn.Sequential:
    """``convs_per_block`` convs; the first one changes the width. The stem is never depthwise."""
    first_dw = config.depthwise and cin > config.in_channels
    convs = [_conv(cin, cout, first_dw)]
    convs += [_conv(cout, cout, config.depthwise) for _ in range(config.convs_per_block - 1)]
    return nn.Sequential(*convs)


class UNet(nn.Module):
    """U-Net mapping ``(N, C, H, W)`` network inputs to ``(N, 1, H, W)`` contact logits."""

    def __init__(self, config: UNetConfig = UNetConfig()) -> None:
        super().__init__()
        self.config = config
        widths = [config.base * 2**level for level in range(config.levels + 1)]
        self.down = nn.ModuleList()
        cin = config.in_channels
        for w in widths[:-1]:
            self.down.append(_block(cin, w, config))
            cin = w
        self.bottleneck = _block(widths[-2], widths[-1], config)
        self.up = nn.ModuleList(
            _block(widths[level + 1] + widths[level], widths[level], config)
            for level in reversed(range(config.levels))
        )
        self.head = nn.Conv2d(widths[0], 1, 1)
        nn.init.constant_(self.head.bias, config.head_bias)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Logits.

        Args:
            x: ``(N, C, H, W) float32`` network input (any ``H, W >= 1``).

        Returns:
            ``(N, 1, H, W) float32`` logits (sigmoid → contact probability).
        """
        skips = []
        for block in self.down:
            x = block(x)
            skips.append(x)
            x = F.max_pool2d(x, 2, ceil_mode=True)
        x = self.bottleneck(x)
        for block, skip in zip(self.up, reversed(skips), strict=True):
            x = F.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
            x = block(torch.cat([x, skip], dim=1))
        return self.head(x)


def count_parameters(model: nn.Module, trainable_only: bool = True) -> int:
    """Number of (trainable) parameters; BatchNorm running statistics are buffers, not counted."""
    return sum(p.numel() for p in model.parameters() if p.requires_grad or not trainable_only)

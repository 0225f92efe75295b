"""Skin condition: how the fingerprint's ridges couple to the membrane (polarity, dry, wet, scars).

The ridge texture (``fingerprint.py``, 1 = ridge crest) says where skin touches the membrane. Real
fingers vary (docs/synth.md, "skin"): dry skin touches only in broken ridge fragments, sweat fills
the valleys and smears the ridges, scars leave ridge-free lines, and depending on skin and coating
the touching ridges can look brighter *or darker* than the valleys. None of this moves the contact
region (the mask), so the segmenter must not depend on crisp, bright ridges.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["SkinCondition", "apply_skin"]

DRY_GRAIN_MM = 0.35  # smoothing of the dry-skin break pattern; ~ a ridge period
WET_SMEAR_MM = 0.25  # blur of the ridges under sweat; ~ half a period fills the valleys
SCAR_WIDTH_MM = (0.15, 0.4)  # width range of a scar line
SCAR_LENGTH_MM = (2.0, 8.0)  # length range of a scar line
SCAR_SPREAD_MM = 6.0  # scars are placed within this distance of the finger's lowest point
SCAR_LEVEL = 0.5  # coupling inside a scar: smooth skin, touching but without ridges


@dataclass(frozen=True)
class SkinCondition:
    """One finger's skin condition (drawn per session)."""

    polarity: int = 1  # +1: ridges couple (brighter than valleys); -1: inverted look
    dryness: float = 0.0  # 0-1, share of the ridge area lost to dry breaks
    wetness: float = 0.0  # 0-1, how far sweat smears the ridges into the valleys
    scars: int = 0  # ridge-free scar lines on the pulp
    seed: int = 0  # seed of the dry pattern and of the scars

    def __post_init__(self) -> None:
        """Reject out-of-range values (``ValueError`` naming ``synth/skin.py``)."""
        if self.polarity not in (1, -1):
            raise ValueError(f"synth/skin.py: polarity must be +1 or -1, got {self.polarity}")
        for name in ("dryness", "wetness"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"synth/skin.py: {name} must be in [0, 1], got {v}")
        if self.scars < 0:
            raise ValueError(f"synth/skin.py: scars must be >= 0, got {self.scars}")


def apply_skin(
    ridges: np.ndarray, texel_mm: float, centre_px: tuple[float, float], skin: SkinCondition
) -> np.ndarray:
    """Apply a skin condition to a ridge texture.

    Args:
        ridges: ``(M, M) float32`` ridge coupling in [0, 1] (1 = crest touching).
        texel_mm: size of one texel, mm.
        centre_px: ``(col, row)`` texel of the finger's lowest point (scars are placed around it).
        skin: the condition; the default changes nothing.

    Returns:
        ``(M, M) float32`` in [0, 1], deterministic for a given ``skin.seed``.
    """
    r = np.clip(np.asarray(ridges, np.float32), 0.0, 1.0)
    if skin.wetness > 0:
        smeared = cv2.GaussianBlur(r, (0, 0), WET_SMEAR_MM / texel_mm)
        r = (1.0 - skin.wetness) * r + skin.wetness * np.clip(smeared + 0.25, 0.0, 1.0)
    rng = np.random.default_rng(skin.seed)
    if skin.dryness > 0:
        noise = rng.standard_normal(r.shape).astype(np.float32)
        grain = cv2.GaussianBlur(noise, (0, 0), DRY_GRAIN_MM / texel_mm)
        r = np.where(grain < np.quantile(grain, skin.dryness), 0.0, r)
    if skin.polarity < 0:
        r = 1.0 - r
    if skin.scars:
        r = np.where(_scar_mask(r.shape, texel_mm, centre_px, skin.scars, rng), SCAR_LEVEL, r)
    return np.clip(r, 0.0, 1.0).astype(np.float32)


def _scar_mask(
    shape: tuple[int, ...],
    texel_mm: float,
    centre_px: tuple[float, float],
    count: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """``(M, M) bool`` scar lines around ``centre_px``."""
    scar = np.zeros(shape, np.uint8)
    for _ in range(count):
        c = np.asarray(centre_px) + rng.uniform(-1, 1, 2) * SCAR_SPREAD_MM / texel_mm
        ang = rng.uniform(0, np.pi)
        length = rng.uniform(*SCAR_LENGTH_MM) / texel_mm
        half = 0.5 * length * np.array([np.cos(ang), np.sin(ang)])
        width = max(1, round(rng.uniform(*SCAR_WIDTH_MM) / texel_mm))
        p0, p1 = np.rint(c - half).astype(int), np.rint(c + half).astype(int)
        cv2.line(scar, (int(p0[0]), int(p0[1])), (int(p1[0]), int(p1[1])), 1, width)
    return scar > 0

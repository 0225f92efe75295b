"""The robustness suite's table: each perturbation, its levels, its reference handling and the
range the training randomises (``contactcal bench --robustness``; the perturbations themselves
are the pure functions of :mod:`contactcal.infer.bench.perturb`, whose docstring says what each
level means and how the reference frame is treated)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from contactcal.infer.bench.perturb import (
    SECTOR_DEG,
    blur,
    contrast,
    dim_sector,
    exposure,
    gamma,
    jpeg,
    noise,
    offset,
    resolution,
    speck,
    unchanged,
)

#: How a perturbation treats the session's reference frame.
REFERENCE_MODES = {
    "same": "perturbed as the frame, identically seeded",
    "independent": "perturbed as the frame, independently seeded",
    "kept": "unperturbed",
    "dropped": "none given above the baseline level",
}


@dataclass(frozen=True)
class Perturbation:
    """One perturbation of the suite and its levels."""

    name: str
    apply: Callable[..., np.ndarray]  # (gray, level, rng[, ring=RingFit]) -> gray, pure
    levels: tuple[float, ...]  # in the order shown; more levels cost more frames measured
    baseline: float  # the unperturbed level (one of ``levels``): each row's own baseline
    unit: str  # what a level is
    reference: str  # key of REFERENCE_MODES
    needs_ring: bool = False  # ``apply`` takes the session's ring as ``ring=``
    moves_mask: bool = False  # the mask is perturbed too (else its area scales with the size)
    names: tuple[tuple[float, str], ...] = ()  # levels shown as words
    #: Draw the same random placement at every level (the generator is seeded without the
    #: level), so that the levels differ in strength only and are compared frame by frame.
    paired_draws: bool = False
    #: ``(lo, hi)``: the levels the training data or augmentation randomise (``docs/synth.md``,
    #: ``docs/training.md``), where the error target holds; None: not randomised (only the
    #: baseline is in range).
    randomised: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.baseline not in self.levels:
            raise ValueError(f"{self.name}: baseline {self.baseline} not in levels {self.levels}")
        if self.reference not in REFERENCE_MODES:
            raise ValueError(f"{self.name}: unknown reference mode {self.reference!r}")

    def in_range(self, level: float) -> bool:
        """True for the baseline and for levels inside :attr:`randomised`."""
        if level == self.baseline:
            return True
        return self.randomised is not None and self.randomised[0] <= level <= self.randomised[1]

    def label(self, level: float) -> str:
        """The level as shown in tables and figures."""
        return dict(self.names).get(level, f"{level:g}")


#: The suite, in report order.
PERTURBATIONS: tuple[Perturbation, ...] = (
    # augmentation: contrast ± 25 %
    Perturbation(
        "contrast",
        contrast,
        (0.5, 0.75, 1.0, 1.5, 2.0),
        1.0,
        "× about grey 128",
        "same",
        randomised=(0.75, 1.25),
    ),
    # augmentation: gamma 0.7-1.4 (renders: display gamma 1.8-2.4)
    Perturbation(
        "gamma", gamma, (0.5, 0.7, 1.0, 1.4, 2.0), 1.0, "exponent", "same", randomised=(0.7, 1.4)
    ),
    # hard renders: exposure gain 0.25-4
    Perturbation(
        "exposure",
        exposure,
        (-2.0, -1.0, 0.0, 1.0, 2.0),
        0.0,
        "stops",
        "same",
        randomised=(-2.0, 2.0),
    ),
    # hard renders: defocus σ ≤ 2.2 px at 400 wide = 14 px at 2592
    Perturbation(
        "blur",
        blur,
        (0.0, 3.0, 6.0, 12.0, 24.0),
        0.0,
        "σ, px at 2592 wide",
        "same",
        randomised=(0.0, 14.0),
    ),
    # renders: shot noise (full well ≥ 300 e⁻, ~10 grey levels at mid grey) + read noise
    Perturbation(
        "noise",
        noise,
        (0.0, 3.0, 6.0, 12.0, 24.0),
        0.0,
        "sd, grey levels",
        "independent",
        randomised=(0.0, 12.0),
    ),
    Perturbation(
        "JPEG",
        jpeg,
        (0.0, 95.0, 75.0, 50.0, 25.0, 10.0),
        0.0,
        "quality",
        "same",
        names=((0, "off"),),
        randomised=(50.0, 98.0),  # renders: JPEG q 50-98 (half the sessions)
    ),
    Perturbation(
        "resolution",
        resolution,
        (0.0, 400.0, 648.0, 1296.0, 2592.0),
        0.0,
        "width, px",
        "same",
        names=((0, "native"),),
        randomised=(400.0, 2592.0),  # training renders to the rig's frames: the deployed chain
    ),
    Perturbation(
        "dimmed sector",
        dim_sector,
        (0.0, 0.3, 0.6, 0.9),
        0.0,
        f"fraction, {SECTOR_DEG:g}° of the ring",
        "same",
        needs_ring=True,
        randomised=(0.0, 0.85),  # hard renders: 2-4 LEDs dimmed to 15 %
    ),
    Perturbation(
        "offset",
        offset,
        (0.0, 0.02, 0.05, 0.1),
        0.0,
        "× ring radius",
        "kept",
        needs_ring=True,
        moves_mask=True,
    ),
    Perturbation(
        "no reference",
        unchanged,
        (0.0, 1.0),
        0.0,
        "reference frame",
        "dropped",
        names=((0, "with"), (1, "without")),
    ),
    # Last in the suite, so the other rows keep their seeds (the seed counts perturbations).
    # Not randomised: the renderer's bright dust has these strengths but is placed anywhere,
    # so the shipped model's data almost never had one in the central disc.
    Perturbation(
        "window speck",
        speck,
        (0.0, 0.1, 0.2, 0.4),
        0.0,
        "added white (linear)",
        "same",
        needs_ring=True,
        names=((0, "none"),),
        paired_draws=True,
    ),
)

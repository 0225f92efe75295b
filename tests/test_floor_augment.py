"""With a dark floor, training's camera augmentation gives what deployment computes on a frame
changed the same way: the floor is taken again after brightness, contrast and gamma."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("kornia")

from contactcal.infer.image.read import load_image  # noqa: E402
from contactcal.infer.methods.unet.config import PreprocessConfig  # noqa: E402
from contactcal.infer.methods.unet.prepare import (  # noqa: E402
    network_to_unit,
    prepare,
    session_reference,
)
from contactcal.train.augment import AugmentConfig, Augmenter  # noqa: E402
from contactcal.train.contact_look import ContactLookConfig  # noqa: E402
from contactcal.train.data import _levels  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
FLOORED = PreprocessConfig(input_size=96, norm_floor_percentile=1.0, ridge_work_px=0)
#: Copies of the frame in the batch: each draws its own operation (applied with p 0.8).
BATCH = 8
#: Mean |difference| in [0, 1] units allowed against deployment: gamma on the resized crop is not
#: gamma on the frame before its area resize (~0.013 here, as without a floor); with the
#: camera operations on the floored values instead of grey levels it is 0.028-0.049.
TOLERANCE = 0.02


def _pair() -> tuple[np.ndarray, np.ndarray]:
    """The example's 10 kPa frame and its reference with a black level of 40 (stray light:
    what the floor is for), ``(H, W) uint8`` each."""
    lift = lambda g: np.rint(40 + 0.8 * g).astype(np.uint8)  # noqa: E731
    return lift(load_image(EXAMPLE / "p10.0kpa.jpg")), lift(load_image(EXAMPLE / "p00.0kpa.jpg"))


def _only(**camera: object) -> AugmentConfig:
    """No warp, no contact look, no blur or noise: only the given tone operation."""
    base = {"brightness": 0.0, "contrast": 0.0, "gamma": (1.0, 1.0)}
    return AugmentConfig(
        flip_p=0.0,
        affine_p=0.0,
        blur_p=0.0,
        noise_p=0.0,
        contact=ContactLookConfig(p=0.0),
        **(base | camera),  # type: ignore[arg-type]
    )


def _deployed(gray: np.ndarray, ref: np.ndarray, op) -> np.ndarray:
    """``(2, S, S)`` in [0, 1]: deployment's frame and reference channels of the changed pair."""

    def change(g: np.ndarray) -> np.ndarray:
        return np.clip(np.rint(255.0 * op(g / 255.0)), 0, 255).astype(np.uint8)

    r = session_reference(change(ref), FLOORED)
    return network_to_unit(prepare(change(gray), r, FLOORED, 2).x, FLOORED)


def _augmented(gray: np.ndarray, ref: np.ndarray, config: AugmentConfig, seed: int) -> np.ndarray:
    """``(BATCH, 2, S, S)`` in [0, 1]: the cached pair after the Augmenter."""
    r = session_reference(ref, FLOORED)
    prep = prepare(gray, r, FLOORED, 2)
    levels = torch.tensor(_levels(gray, r, prep.box, FLOORED)) / 255
    x = torch.from_numpy(prep.x)[None].repeat(BATCH, 1, 1, 1)
    m = torch.zeros((BATCH, 1, 96, 96))
    out, _ = Augmenter(config, FLOORED, seed=seed)(x, m, levels[None].repeat(BATCH, 1, 1))
    return network_to_unit(out.numpy(), FLOORED)


@pytest.mark.parametrize("gamma", [0.7, 1.4])
def test_floored_gamma_matches_deployment(gamma: float) -> None:
    gray, ref = _pair()
    changed = _deployed(gray, ref, lambda v: v**gamma)
    cached = _augmented(gray, ref, _only(), seed=3)  # no operation: the cached inputs
    got = _augmented(gray, ref, _only(gamma=(gamma, gamma)), seed=3)
    applied = np.abs(got - cached).max(axis=(1, 2, 3)) > 1e-6  # gamma is drawn with p 0.8
    assert 0 < applied.sum() < BATCH
    assert np.abs(got[applied] - changed).mean(axis=(1, 2, 3)).max() < TOLERANCE
    assert np.abs(cached[0] - changed).mean() > TOLERANCE  # the change is larger than that


def test_floored_brightness_and_contrast_cancel_as_in_deployment() -> None:
    """Deployment's floored normalisation undoes an offset and a gain (up to clipping); so do
    the augmented inputs, where the camera operations on the floored values moved them by
    0.008-0.042."""
    gray, ref = _pair()
    cached = _augmented(gray, ref, _only(), seed=5)
    got = _augmented(gray, ref, _only(brightness=0.05, contrast=0.1), seed=5)
    assert np.abs(got - cached).mean(axis=(1, 2, 3)).max() < 1e-3


def test_a_floored_augmenter_needs_the_levels() -> None:
    x = torch.zeros((2, 2, 96, 96))
    with pytest.raises(ValueError, match="needs each sample's levels"):
        Augmenter(_only(), FLOORED, seed=0)(x, torch.zeros((2, 1, 96, 96)))

"""One model with and without a reference frame: the blank placeholder and reference dropout."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.prepare import (
    blank_reference,
    prepare,
    session_reference,
    unit_to_network,
)

SIZE = 32


def _frame() -> np.ndarray:
    yy, xx = np.mgrid[:120, :160]
    r = np.hypot(xx - 80, yy - 60)
    return np.where((r > 40) & (r < 50), 230, 20).astype(np.uint8)


def test_without_reference_the_mode_decides_the_second_channel() -> None:
    frame = _frame()
    none = session_reference(None)
    own = prepare(frame, none, PreprocessConfig(input_size=SIZE), channels=2).x
    np.testing.assert_array_equal(own[1], own[0])  # "self": the frame itself (v1 models)
    cfg = PreprocessConfig(input_size=SIZE, no_reference="blank")
    blank = prepare(frame, none, cfg, channels=2).x
    np.testing.assert_array_equal(blank[0], own[0])
    np.testing.assert_array_equal(blank[1], blank_reference(cfg))
    assert blank_reference(cfg).shape == (SIZE, SIZE)
    assert np.all(blank[1] == np.float32(unit_to_network(0.0, cfg)))


def test_with_a_reference_the_mode_changes_nothing() -> None:
    frame = _frame()
    ref = session_reference(frame, PreprocessConfig(input_size=SIZE))
    a = prepare(frame, ref, PreprocessConfig(input_size=SIZE), channels=2).x
    cfg = PreprocessConfig(input_size=SIZE, no_reference="blank")
    b = prepare(frame, session_reference(frame, cfg), cfg, channels=2).x
    np.testing.assert_array_equal(a, b)


def test_bad_mode_is_refused() -> None:
    with pytest.raises(ValueError, match="no_reference"):
        PreprocessConfig(no_reference="zeros")


def test_augmenter_blanks_the_reference_channel_of_a_share_of_samples() -> None:
    torch = pytest.importorskip("torch")
    pytest.importorskip("kornia")
    from contactcal.train.augment import AugmentConfig, Augmenter

    cfg = PreprocessConfig(input_size=SIZE)
    x = torch.full((64, 2, SIZE, SIZE), 0.5)
    m = torch.zeros((64, 1, SIZE, SIZE))
    off = AugmentConfig(enabled=False)
    out, _ = Augmenter(off, cfg, seed=1, reference_dropout=0.5)(x.clone(), m)
    blank = unit_to_network(0.0, cfg)
    dropped = (out[:, 1] == blank).flatten(1).all(1)
    assert 16 <= int(dropped.sum()) <= 48  # about half of 64
    assert torch.equal(out[~dropped, 1], x[~dropped, 1]) and torch.equal(out[:, 0], x[:, 0])
    same, _ = Augmenter(off, cfg, seed=1, reference_dropout=0.5)(x.clone(), m)
    assert torch.equal(same, out)  # seeded
    kept, _ = Augmenter(off, cfg, seed=1)(x.clone(), m)
    assert torch.equal(kept, x)


def test_train_config_resolves_the_placeholder() -> None:
    pytest.importorskip("torch")
    from contactcal.train.config import TrainConfig

    assert TrainConfig(reference_dropout=0.3).resolved().preprocess.no_reference == "blank"
    assert TrainConfig().resolved().preprocess.no_reference == "self"
    with pytest.raises(ValueError, match="reference_dropout"):
        TrainConfig(reference_dropout=0.3, use_reference=False)
    with pytest.raises(ValueError, match="reference_dropout"):
        TrainConfig(reference_dropout=1.0)


@pytest.mark.parametrize(
    ("mode", "words"), [("self", "its own reference"), ("blank", "placeholder")]
)
def test_measure_note_says_what_stood_in_for_the_reference(
    tmp_path: Path, mode: str, words: str
) -> None:
    """The note a frame measured without a reference gets follows the model's own mode."""
    onnx = pytest.importorskip("onnx")
    from contactcal.infer.methods.unet.method import UnetMethod
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    model = onnx.load(str(DEFAULT_MODEL))
    for prop in model.metadata_props:
        if prop.key == "preprocess":
            prop.value = json.dumps({**json.loads(prop.value), "no_reference": mode})
    path = tmp_path / f"{mode}.onnx"
    onnx.save(model, str(path))
    assert words in UnetMethod(path).NO_REFERENCE

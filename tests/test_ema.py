"""train/ema.py: the running average of the weights (reference values, buffers, bad input)."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from contactcal.train.checkpoint import config_to_dict  # noqa: E402
from contactcal.train.config import (  # noqa: E402
    LEGACY_BLUR_KERNEL_PX,
    TrainConfig,
    saved_train_config,
)
from contactcal.train.ema import WeightAverage, ema_update  # noqa: E402


def test_ema_update_reference_values() -> None:
    avg = {"w": torch.tensor([1.0, 2.0]), "n": torch.tensor(3)}
    new = {"w": torch.tensor([3.0, 6.0]), "n": torch.tensor(7)}
    ema_update(avg, new, 0.75)
    assert torch.allclose(avg["w"], torch.tensor([1.5, 3.0]))  # 0.75·old + 0.25·new
    assert int(avg["n"]) == 7  # integer buffers (BatchNorm's counter) are copied
    ema_update(avg, new, 0.0)
    assert torch.equal(avg["w"], new["w"])


@pytest.mark.parametrize("decay", [-0.1, 1.0, 1.5])
def test_ema_update_bad_decay(decay: float) -> None:
    w = {"w": torch.zeros(2)}
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        ema_update(w, {"w": torch.ones(2)}, decay)


def test_ema_update_mismatched_models() -> None:
    with pytest.raises(ValueError, match="different parameters"):
        ema_update({"a": torch.zeros(1)}, {"b": torch.zeros(1)}, 0.5)
    with pytest.raises(ValueError, match=r"a is \(3,\), its average \(1,\)"):
        ema_update({"a": torch.zeros(1)}, {"a": torch.zeros(3)}, 0.5)


def test_weight_average_follows_the_trained_model() -> None:
    torch.manual_seed(0)
    model = torch.nn.Sequential(torch.nn.Conv2d(1, 2, 3), torch.nn.BatchNorm2d(2))
    average = WeightAverage(model, 0.5)
    start = average.model[0].weight.clone()
    with torch.no_grad():
        model[0].weight.add_(1.0)
    model(torch.randn(2, 1, 5, 5))  # train mode: BatchNorm statistics move
    average.update(model)
    assert torch.allclose(average.model[0].weight, start + 0.5)
    bn, avg_bn = model[1], average.model[1]
    assert torch.allclose(avg_bn.running_mean, 0.5 * bn.running_mean)  # started at 0
    assert not average.model.training
    assert not any(p.requires_grad for p in average.model.parameters())


@pytest.mark.parametrize("decay", [0.0, 1.0])
def test_weight_average_needs_a_decay_in_the_open_interval(decay: float) -> None:
    with pytest.raises(ValueError, match=r"\(0, 1\)"):
        WeightAverage(torch.nn.Linear(1, 1), decay)


@pytest.mark.parametrize("decay", [-0.5, 1.0])
def test_config_rejects_bad_ema_decay(decay: float) -> None:
    with pytest.raises(ValueError, match="ema_decay"):
        TrainConfig(ema_decay=decay)


def test_saved_config_keeps_its_blur_kernel() -> None:
    """A config saved before ``blur_kernel_px`` existed blurred with 5 taps, and resumes so."""
    saved = config_to_dict(TrainConfig().resolved())
    assert saved["augment"]["blur_kernel_px"] == 9  # resolved: the taps actually used
    del saved["augment"]["blur_kernel_px"]
    assert saved_train_config(saved, "old").augment.blur_kernel_px == LEGACY_BLUR_KERNEL_PX == 5
    old = {k: v for k, v in saved.items() if k != "augment"}  # older still: no augment at all
    assert saved_train_config(old, "older").augment.blur_kernel_px == 5
    saved["augment"]["blur_kernel_px"] = 0  # written by this version before resolving: auto
    assert saved_train_config(saved, "new").resolved().augment.blur_kernel_px == 9

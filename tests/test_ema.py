"""train/ema.py: the running average of the weights (reference values, buffers, bad input)."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from contactcal.train.config import TrainConfig  # noqa: E402
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

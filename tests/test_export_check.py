"""Export's decision check: torch and ONNX must decide alike on the run's validation frames."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from procedural import write_dataset  # noqa: E402
from test_train import tiny_config  # noqa: E402

from contactcal.train.export import load_run, to_onnx  # noqa: E402
from contactcal.train.export_check import check_decisions  # noqa: E402
from contactcal.train.loop import train  # noqa: E402
from contactcal.train.model import UNet  # noqa: E402
from contactcal.train.split import validation_rows  # noqa: E402


@pytest.mark.slow
def test_decisions_agree_and_disagreement_is_caught(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data", fingers=3)
    train([data], tmp_path / "run", tiny_config(epochs=1, input_size=64), progress=False)
    cfg, info, ckpt = load_run(tmp_path / "run")
    net = UNet(cfg.model).eval()
    net.load_state_dict(ckpt["model"])
    data_bytes = to_onnx(net, cfg.model.in_channels, cfg.input_size, 17).SerializeToString()
    spec = cfg.spec()
    val = validation_rows(tmp_path / "run", info, cfg.val_fraction, cfg.seed)
    assert check_decisions(net, data_bytes, spec, val) > 0
    # A graph that always says "contact everywhere" (logits +30) must be caught.
    other = UNet(cfg.model).eval()
    with torch.no_grad():
        for p in other.parameters():
            p.zero_()
        last = list(other.parameters())[-1]
        last.fill_(30.0)
    wrong = to_onnx(other, cfg.model.in_channels, cfg.input_size, 17).SerializeToString()
    with pytest.raises(RuntimeError, match="decide differently"):
        check_decisions(net, wrong, spec, val)
    missing = {**info, "data_dirs": [str(tmp_path / "gone")]}
    with pytest.raises(ValueError, match="gone"):
        validation_rows(tmp_path / "run", missing, cfg.val_fraction, cfg.seed)
    assert json.loads((tmp_path / "run" / "config.json").read_text())["data_dirs"]

"""torch and onnxruntime agree on every hard case (tiny model trained and exported here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from test_hard_cases import CASES, _frame  # noqa: E402
from test_train import tiny_config, write_dataset  # noqa: E402

from contactcal.infer.methods import UnetMethod  # noqa: E402
from contactcal.train.export import PARITY_ATOL, PARITY_RTOL, export_onnx, load_run  # noqa: E402
from contactcal.train.loop import train  # noqa: E402
from contactcal.train.model import UNet  # noqa: E402


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("parity")
    data = write_dataset(root / "data", fingers=3)
    train([data], root / "run", tiny_config(epochs=1, input_size=64), progress=False)
    return root / "run", export_onnx(root / "run", root / "tiny.onnx")


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_torch_and_onnx_agree(exported: tuple[Path, Path], case: str) -> None:
    run, model = exported
    cfg, _, ckpt = load_run(run)
    net = UNet(cfg.model).eval()
    net.load_state_dict(ckpt["model"])
    method = UnetMethod(str(model))
    seg = method.segmenter
    seg.set_reference(CASES[case](_frame(0)))
    from contactcal.infer.preprocess import to_network

    gray = CASES[case](_frame(12))
    box = seg._box
    assert box is not None
    x = np.stack([to_network(gray, box, seg.spec.preprocess), seg._ref_x])[None]
    got = seg.session.run(None, {seg.input_name: x.astype(np.float32)})[0]
    with torch.no_grad():
        ref = net(torch.from_numpy(x.astype(np.float32))).numpy()
    np.testing.assert_allclose(got, ref, atol=PARITY_ATOL, rtol=PARITY_RTOL, err_msg=case)
    assert np.all(np.isfinite(got))

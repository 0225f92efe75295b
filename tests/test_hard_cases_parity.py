"""torch and onnxruntime agree on every hard case (tiny model trained and exported here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from procedural import write_dataset  # noqa: E402
from test_hard_cases import CASES, _frame  # noqa: E402
from test_train import tiny_config  # noqa: E402

from contactcal.infer.methods.unet.postprocess import postprocess  # noqa: E402
from contactcal.infer.methods.unet.prepare import prepare, session_reference  # noqa: E402
from contactcal.infer.methods.unet.runner import OnnxSegmenter, sigmoid  # noqa: E402
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
    """Same prepare → torch vs onnxruntime logits; deployment's segment() vs the torch decision."""
    run, model = exported
    cfg, _, ckpt = load_run(run)
    net = UNet(cfg.model).eval()
    net.load_state_dict(ckpt["model"])
    seg = OnnxSegmenter(model)
    spec = seg.spec
    ref = session_reference(CASES[case](_frame(0)), spec.preprocess)
    gray = CASES[case](_frame(12))
    prep = prepare(gray, ref, spec.preprocess, spec.channels)
    x = prep.x[None].astype(np.float32)
    got = seg.ort_session.run(None, {seg.input_name: x})[0]
    with torch.no_grad():
        logits = net(torch.from_numpy(x)).numpy()
    np.testing.assert_allclose(got, logits, atol=PARITY_ATOL, rtol=PARITY_RTOL, err_msg=case)
    assert np.all(np.isfinite(got))
    deployed = seg.segment(gray, ref)
    trained = postprocess(sigmoid(logits[0, 0]), prep.box, gray.shape[:2], spec)
    assert deployed.box == trained.box
    np.testing.assert_allclose(deployed.prob, trained.prob, atol=PARITY_ATOL, err_msg=case)

"""Export's decision check: torch and onnxruntime decide alike on the run's own frames.

Beyond logit parity on random inputs (:func:`contactcal.train.export.check_parity`), the exported
graph is run on real frames prepared by the one preprocessing path
(:func:`contactcal.infer.methods.unet.prepare.prepare`, through the training cache) and decided
by the one decision (:func:`contactcal.infer.methods.unet.postprocess.postprocess`): contact and
area must agree with the torch model's.
"""

from __future__ import annotations

from collections.abc import Sequence

import onnxruntime as ort
import torch

from contactcal.infer.bench.dataset import IndexRow, spread
from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.infer.methods.unet.runner import sigmoid
from contactcal.infer.methods.unet.spec import ModelSpec
from contactcal.train.data import build_cache

#: Largest area difference (network pixels) between torch's and onnxruntime's decision: logits
#: agree to PARITY_ATOL, so a pixel within that of the threshold may flip.
DECISION_TOL_NET_PX = 2.0
#: Frames checked: spread over the validation fingers' pressures.
DECISION_FRAMES = 8


class ExportCheckError(RuntimeError):
    """An exported graph that fails one of the export's own checks (checker, parity, decisions,
    metadata read-back); nothing is written then."""


def check_decisions(
    model: torch.nn.Module,
    onnx_bytes: bytes,
    spec: ModelSpec,
    val: Sequence[IndexRow],
) -> int:
    """Compare torch's and onnxruntime's contact decisions on validation frames of the run.

    Args:
        model: the torch model (eval mode).
        onnx_bytes: the exported graph.
        spec: the exported spec.
        val: the frames of the run's validation fingers
            (:func:`~contactcal.train.split.validation_rows`).

    Returns:
        The number of frames checked.

    Raises:
        RuntimeError: a decision differs.
    """
    picks = [val[i] for i in spread(len(val), DECISION_FRAMES)]
    cache = build_cache(picks, spec.preprocess, spec.channels)
    sess = ort.InferenceSession(onnx_bytes, providers=["CPUExecutionProvider"])
    with torch.no_grad():
        p_torch = torch.sigmoid(model(cache.x)).numpy()[:, 0]
    p_ort = sigmoid(sess.run(None, {"input": cache.x.numpy()})[0][:, 0])
    for i, row in enumerate(picks):
        a = postprocess(p_torch[i], cache.boxes[i], cache.shapes[i], spec)
        b = postprocess(p_ort[i], cache.boxes[i], cache.shapes[i], spec)
        if a.contact != b.contact or abs(a.region_net_px - b.region_net_px) > DECISION_TOL_NET_PX:
            raise ExportCheckError(
                f"{row.frame}: torch and ONNX decide differently (contact {a.contact} vs "
                f"{b.contact}, region {a.region_net_px:g} vs {b.region_net_px:g} network px)"
            )
    return len(picks)

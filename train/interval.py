"""Calibrate the U-Net's stated interval of the contact area on validation data.

A frame's interval comes from its kept region's boundary band
(:func:`contactcal.infer.methods.unet.postprocess.boundary_band`): the region at a stricter and a
looser probability threshold, plus half a network pixel across its outline, widened by a factor.
Here the thresholds (symmetric in logits around the decision threshold, one of
:data:`LOGIT_MARGINS`) and the factor are chosen on validation frames, never on the benchmark:

* for each candidate pair, every frame gets the smallest factor whose interval covers its true
  area (:func:`required_widen`); the factor is the split-conformal quantile of these, the
  ``ceil((n + 1)·level)``-th smallest of n (capped at n), so that the interval covers about
  ``level`` of such frames;
* frames with neither true nor called contact are left out: their interval, ``(0, …)``, covers
  the true area 0 whatever the factor;
* of the candidates, the one with the narrowest median relative width on true-contact frames wins.

``contactcal export`` calibrates on the run's validation fingers (:func:`calibrate_run`);
``python -m contactcal.train.interval`` recalibrates an exported model's ``interval`` metadata on
rendered data (:func:`recalibrate_model`; the weights are copied untouched), and with ``--region``
states the model's contact region (``region`` metadata, :data:`REGIONS`) at the same time: the
interval is the region's, so the two are set together. It refuses a folder given twice and the
model's training data as far as the model records it, and records in the ``interval`` entry what
it was calibrated on (:mod:`contactcal.train.calibration_data`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.bench.dataset import IndexRow, read_index
from contactcal.infer.methods.unet.postprocess import Band, Segmentation, boundary_band
from contactcal.infer.methods.unet.spec import REGIONS, IntervalSpec, ModelSpec
from contactcal.train.calibration_data import (
    calibration_data,
    calibration_folders,
    with_record,
)
from contactcal.train.restate import (
    check_paths,
    metadata_of,
    read_model,
    restating_parser,
    run_restating,
    save_restated,
)

#: Stated coverage of the interval.
LEVEL = 0.9
#: Candidate half-widths of the threshold pair, logits around the decision threshold (1 → 0.27
#: and 0.73 at a threshold of 0.5; 3 → 0.047 and 0.95): narrower pairs need a larger factor.
LOGIT_MARGINS = (0.5, 1.0, 2.0, 3.0)


def required_widen(band: Band, truth_net: float) -> float:
    """The smallest factor whose interval covers ``truth_net`` (network px); inf if none does."""
    if truth_net >= band.area:
        gap, room = truth_net - band.area, band.loose - band.area + band.edge
    else:
        gap, room = band.area - truth_net, band.area - band.strict + band.edge
    if gap <= 0.0:
        return 0.0
    return gap / room if room > 0.0 else math.inf


def _pair(spec: ModelSpec, margin: float, level: float) -> IntervalSpec:
    logit = math.log(spec.threshold / (1.0 - spec.threshold))

    def sig(z: float) -> float:
        return 1.0 / (1.0 + math.exp(-z))

    return IntervalSpec(level, sig(logit - margin), sig(logit + margin), 0.0, 1)


def _candidate(widen: float, width: float, reaches: bool) -> dict[str, Any]:
    """One candidate pair in the summary, standard JSON: its factor and median relative width,
    both null where no factor reaches the level on its frames (``reaches_level`` false)."""
    return {
        "reaches_level": reaches,
        "widen": widen if reaches else None,
        "median_rel_width": width if reaches else None,
    }


def _try(
    pair: IntervalSpec, segs: Sequence[Segmentation], truths: np.ndarray, spec: ModelSpec
) -> tuple[float, float, int]:
    """``(factor, median relative width on true-contact frames, frames used)`` of one pair."""
    bands = [boundary_band(s.prob, s.mask_net, pair, spec.min_contact_area_px) for s in segs]
    ppn = np.array([s.box.scale(s.prob.shape[0]) ** 2 for s in segs])
    used = [i for i, b in enumerate(bands) if b.area > 0 or truths[i] > 0]
    if not used:
        return math.inf, math.inf, 0
    need = np.sort([required_widen(bands[i], truths[i] / ppn[i]) for i in used])
    rank = min(math.ceil((len(used) + 1) * pair.level), len(used))
    widen = float(need[rank - 1])
    if not math.isfinite(widen):
        return widen, math.inf, len(used)
    spans = [(bands[i].interval(widen), ppn[i] / truths[i]) for i in used if truths[i] > 0]
    widths = [(hi - lo) * scale for (lo, hi), scale in spans]
    return widen, float(np.median(widths)) if widths else 0.0, len(used)


def calibrate(
    segs: Sequence[Segmentation], truths: Sequence[float], spec: ModelSpec, level: float = LEVEL
) -> tuple[IntervalSpec, dict[str, Any]]:
    """Choose the interval's thresholds and factor on calibration frames.

    Args:
        segs: each frame's :func:`~contactcal.infer.methods.unet.postprocess.postprocess` result
            under ``spec`` (probabilities, kept region, crop).
        truths: each frame's true contact area, input pixels (mask pixel count).
        spec: the model's spec (threshold, minimum area).
        level: the stated coverage.

    Returns:
        ``(interval, summary)``; the summary lists each candidate's factor and median width
        (:func:`_candidate`: null for a candidate that cannot reach ``level``).

    Raises:
        ValueError: no usable frames, or no candidate reaches ``level`` (more frames than
            ``1 - level`` have true contact but no region at any looser threshold).
    """
    t = np.asarray(truths, dtype=np.float64)
    if len(segs) != len(t) or not len(t):
        raise ValueError(f"expected one true area per frame, got {len(t)} for {len(segs)} frames")
    tried = {m: _try(_pair(spec, m, level), segs, t, spec) for m in LOGIT_MARGINS}
    ok = {m: v for m, v in tried.items() if math.isfinite(v[0]) and v[2] > 0}
    if not ok:
        raise ValueError(
            f"the area interval cannot reach {level:.0%} coverage on {len(t)} calibration frames "
            "(too many missed contacts or no contact frames); calibrate on more frames"
        )
    margin = min(ok, key=lambda m: (ok[m][1], m))
    widen, width, used = ok[margin]
    pair = _pair(spec, margin, level)
    interval = dataclasses.replace(pair, widen=widen, frames=used)
    summary = {
        "frames": len(t),
        "frames_used": used,
        "candidates": {str(m): _candidate(v[0], v[1], m in ok) for m, v in tried.items()},
        "margin_logit": margin,
        "median_rel_width": width,
        "interval": dataclasses.asdict(interval),
    }
    return interval, summary


def calibrate_run(
    model: Any, spec: ModelSpec, val: Sequence[IndexRow]
) -> tuple[IntervalSpec, dict[str, Any]]:
    """Calibrate on a training run's validation fingers with its torch model (eval mode).

    Args:
        model: the run's torch model (eval mode).
        spec: its deployment spec.
        val: the frames of its validation fingers
            (:func:`~contactcal.train.split.validation_rows`).

    Raises:
        ValueError: :func:`calibrate` fails.
    """
    import torch

    from contactcal.infer.methods.unet.postprocess import postprocess
    from contactcal.train.data import build_cache

    cache = build_cache(val, spec.preprocess, spec.channels)
    segs = []
    with torch.no_grad():
        for i in range(0, len(cache), 16):
            prob = torch.sigmoid(model(cache.x[i : i + 16].float()))[:, 0].numpy()
            for k, p in enumerate(prob):
                segs.append(postprocess(p, cache.boxes[i + k], cache.shapes[i + k], spec))
    return calibrate(segs, cache.area_px.numpy().tolist(), spec)


def _segment_dataset(
    model: Path, content: bytes, data_dirs: Sequence[Path], region: str | None = None
) -> tuple[list[Segmentation], list[float], ModelSpec]:
    """Every frame of the datasets through the deployment runner (each session's lowest-pressure
    frame is its reference; large frames shrunk as deployment shrinks them: ``session_inputs``),
    the true areas (in pixels of the shrunk frame), and the model's spec without its interval (the
    model's own ``interval`` key, if any, is not used), with ``region`` when given. The model is
    ``content``, the file ``model`` as read once by the caller. Its change gate (``min_change``)
    acts as deployed, so the interval is the gated decision's (:func:`calibrate_run`, at export,
    has no gate yet)."""
    import onnx

    from contactcal.infer.methods.unet.runner import OnnxSegmenter
    from contactcal.train.sessions import session_inputs

    proto = onnx.load_from_string(content)  # a copy: the caller rewrites its own proto
    meta = metadata_of(proto)
    # Any valid interval lets the strict reader accept a model exported before intervals.
    meta["interval"] = json.dumps(dataclasses.asdict(IntervalSpec(LEVEL, 1e-6, 1 - 1e-6, 1.0, 1)))
    if region is not None:
        meta["region"] = region
    onnx.helper.set_model_props(proto, meta)
    runner = OnnxSegmenter(model, content=proto.SerializeToString())
    segs, truths = [], []
    for d in data_dirs:
        for sess in session_inputs(read_index(d), runner.spec.preprocess).values():
            for r in sess.rows:
                segs.append(runner.segment(sess.frame(r.frame), sess.reference))
                truths.append(r.area_px / sess.shrink**2)
    return segs, truths, dataclasses.replace(runner.spec, interval=None)


def recalibrate_model(
    model: str | os.PathLike[str],
    data_dirs: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    region: str | None = None,
) -> dict[str, Any]:
    """Write ``model`` with its ``interval`` metadata calibrated on ``data_dirs`` to ``out``.

    Only the metadata changes (the graph and weights are copied); the result passes
    ``onnx.checker`` (full check) and deployment's ``read_spec`` before it is written (atomic).

    Args:
        model: an exported ``.onnx`` model (with or without an ``interval`` key).
        data_dirs: ``contactcal synth`` datasets that are neither its training, its benchmark
            nor any held-out check data; what of this is checked:
            :mod:`contactcal.train.calibration_data`.
        out: the new ``.onnx`` file; must not be ``model`` (inputs are never overwritten).
        region: the contact region to state (one of :data:`REGIONS`); None keeps the model's.

    Returns:
        The calibration summary (:func:`calibrate`), with the region it was calibrated for and
        the datasets' record (``data``, also written in the ``interval`` entry).

    Raises:
        ValueError: bad output name, an unknown region, a folder given twice, the model's
            training data, or data the calibration cannot use.
    """

    src, dst = check_paths(model, out)
    if region is not None and region not in REGIONS:
        raise ValueError(f"{src}: region must be one of {', '.join(REGIONS)}, got {region!r}")
    dirs = calibration_folders(data_dirs)  # the folders before the model is read
    content, proto = read_model(src)  # once: the model measured is the model rewritten
    record = calibration_data(dirs, metadata_of(proto))
    segs, truths, base = _segment_dataset(src, content, dirs, region)
    interval, summary = calibrate(segs, truths, base)
    spec = dataclasses.replace(base, interval=interval)
    new = spec.to_metadata()
    updates = {"interval": with_record(new["interval"], record), "region": new["region"]}
    save_restated(proto, updates, spec, dst)
    return {**summary, "region": spec.region, "data": record}


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m contactcal.train.interval MODEL --data DIR... --out NEW.onnx [--region R]``."""
    ap = restating_parser(
        "python -m contactcal.train.interval",
        "Recalibrate an exported model's area interval (metadata only) on validation renders, "
        "optionally stating its contact region.",
    )
    ap.add_argument(
        "--region",
        choices=REGIONS,
        default=None,
        help="contact region to state: the largest region as segmented, or its convex hull "
        "(default: keep the model's)",
    )
    a = ap.parse_args(argv)
    return run_restating(lambda: recalibrate_model(a.model, a.data, a.out, a.region), a.out)


if __name__ == "__main__":
    raise SystemExit(main())

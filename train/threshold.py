"""Choose the minimum contact area (the no-contact decision) on a run's validation fingers.

The deployed contact decision keeps the largest connected region above the probability threshold
and calls it contact if it covers at least ``min_contact_area_px`` network pixels
(:func:`contactcal.infer.methods.unet.postprocess.postprocess`, whose ``region_net_px`` this
reads: the same function as validation and deployment). The training default is a guess; this
picks the value that minimises false contacts + missed contacts on the validation fingers (never
on the benchmark). The errors change only at the region sizes seen, so the fewest errors hold on
an interval of values; the pick is the geometric middle of the lowest such interval (the widest
margin on both sides: the largest false region it rejects and the smallest contact it keeps).
Its lower end, the value chosen before, had no margin: a validation set with almost no false
specks drove it to a few pixels, and unseen frames (the slack membrane at 0 kPa) then passed
with specks just above it.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import torch

from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.train.data import build_cache
from contactcal.train.export import load_run
from contactcal.train.model import UNet
from contactcal.train.split import validation_rows


def largest_region_areas(run_dir: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """Largest predicted region (network px) and true contact of every validation frame.

    Returns:
        ``(areas, contact)``: ``(N,) float64`` and ``(N,) bool``.

    Raises:
        ValueError: the run has no validation fingers, its data folders are missing, or its
            recorded split is contradicted (:func:`~contactcal.train.split.validation_rows`).
    """
    cfg, info, ckpt = load_run(run_dir)
    val = validation_rows(run_dir, info, cfg.val_fraction, cfg.seed)
    cache = build_cache(val, cfg.preprocess, cfg.model.in_channels)
    net = UNet(cfg.model)
    net.load_state_dict(ckpt["model"])
    net.eval()
    spec = cfg.spec()  # region_net_px is measured before the minimum-area test
    areas = []
    with torch.no_grad():
        for i in range(0, len(cache), 16):
            prob = torch.sigmoid(net(cache.x[i : i + 16].float()))[:, 0].numpy()
            for k, p in enumerate(prob):
                seg = postprocess(p, cache.boxes[i + k], cache.shapes[i + k], spec)
                areas.append(seg.region_net_px)
    return np.asarray(areas), cache.area_px.numpy() > 0


def widest_margin(areas: np.ndarray, contact: np.ndarray, default: float) -> float:
    """The minimum area (network px) in the middle of the lowest interval of fewest errors.

    Args:
        areas: ``(N,)`` largest predicted region per validation frame, network px.
        contact: ``(N,) bool`` true contact per frame.
        default: the training default (a candidate too).

    Returns:
        ``sqrt(lo · hi)``: ``lo`` the smallest value with the fewest false + missed contacts,
        ``hi`` the largest such value below the next rise of that count (region sizes are whole
        pixels; ``lo`` when it never rises), so the pick keeps the fewest errors.
    """

    def errors(t: float) -> int:
        return int(np.sum(~contact & (areas >= t)) + np.sum(contact & (areas < t)))

    # Candidates: 1 px (any region) and just above each region size seen (the decision changes
    # only there).
    candidates = sorted({1.0, default, *(float(a) + 1.0 for a in areas if a > 0)})
    counts = [errors(t) for t in candidates]
    i = counts.index(min(counts))
    j = next((k for k in range(i + 1, len(candidates)) if counts[k] > counts[i]), None)
    # Region sizes are whole pixels: every value in [lo, next rise − 1] keeps the same decisions.
    lo = candidates[i]
    hi = max(lo, candidates[j] - 1.0) if j is not None else lo
    return float(np.sqrt(lo * hi))


def tune_min_area(run_dir: str | os.PathLike[str]) -> tuple[float, dict[str, Any]]:
    """The minimum area (network px) with the fewest validation errors and the widest margin.

    Returns:
        ``(min_area, summary)`` with the error counts before and after.
    """
    cfg, _, _ = load_run(run_dir)
    areas, contact = largest_region_areas(run_dir)

    def errors(t: float) -> tuple[int, int]:
        return int(np.sum(~contact & (areas >= t))), int(np.sum(contact & (areas < t)))

    best = widest_margin(areas, contact, cfg.min_contact_area_px)
    fp0, fn0 = errors(cfg.min_contact_area_px)
    fp1, fn1 = errors(best)
    summary = {
        "frames": len(areas),
        "no_contact_frames": int((~contact).sum()),
        "default_min_area_px": cfg.min_contact_area_px,
        "default_false_contacts": fp0,
        "default_missed_contacts": fn0,
        "tuned_min_area_px": best,
        "tuned_false_contacts": fp1,
        "tuned_missed_contacts": fn1,
    }
    return best, summary

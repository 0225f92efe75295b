"""Loss and validation metrics.

Loss = BCE + soft Dice. BCE is a per-pixel proper scoring rule (calibrated probabilities, stable
gradients, and it is what teaches "no contact" on pre-onset frames); soft Dice, computed per
frame over the frames with contact, weights each frame's region as a whole regardless of its
size, so small contacts near the onset (a few % of the pixels) are not drowned by the
background, and it tracks the overlap/area we are judged on.

Areas are measured in INPUT pixels: the probability map is mapped back with
:func:`contactcal.infer.preprocess.from_network` (as in deployment) and thresholded; IoU is
computed in network pixels (the cached masks) to avoid keeping full-resolution masks in memory.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from contactcal.infer.preprocess import from_network

#: Pressure bins of the validation table, kPa, [lo, hi).
PRESSURE_BINS: tuple[tuple[float, float], ...] = ((0, 3), (3, 5), (5, 10), (10, 20), (20, 1e9))


def soft_dice_loss(logits: torch.Tensor, target: torch.Tensor, eps: float = 1.0) -> torch.Tensor:
    """Mean of ``1 - (2·Σpt + eps) / (Σp + Σt + eps)`` over the frames WITH contact.

    Frames with an empty target are left to BCE: their soft Dice would be ``1 - 1/(Σp + 1)``,
    which stays near 1 until every pixel's probability is ~0 and so drives all logits to large
    negative values (miscalibrated, and it dominates the loss when many frames are pre-onset).

    Args:
        logits: ``(N, 1, H, W)``.
        target: ``(N, 1, H, W)`` in {0, 1}.
        eps: smoothing, px (keeps tiny contacts' gradients finite).

    Returns:
        Scalar; 0 when no frame of the batch has contact.
    """
    p = torch.sigmoid(logits).flatten(1)
    t = target.flatten(1)
    has = t.sum(1) > 0
    if not bool(has.any()):
        return logits.sum() * 0.0
    p, t = p[has], t[has]
    dice = (2.0 * (p * t).sum(1) + eps) / (p.sum(1) + t.sum(1) + eps)
    return (1.0 - dice).mean()


def segmentation_loss(
    logits: torch.Tensor, target: torch.Tensor, bce_weight: float, dice_weight: float
) -> torch.Tensor:
    """``bce_weight · BCE + dice_weight · soft Dice`` (scalar)."""
    bce = F.binary_cross_entropy_with_logits(logits, target)
    return bce_weight * bce + dice_weight * soft_dice_loss(logits, target)


@dataclass(frozen=True)
class FrameResult:
    """One validation frame's outcome."""

    pressure_kpa: float
    contact_true: bool  # index.csv flag
    contact_pred: bool  # predicted area >= min_contact_area_px (network px)
    iou: float  # in network pixels; 1.0 when both prediction and truth are empty
    area_pred_px: float  # input pixels (0.0 when no contact is predicted)
    area_true_px: float  # input pixels


def frame_results(
    prob: np.ndarray,
    target: np.ndarray,
    boxes: Sequence,
    shapes: Sequence[tuple[int, int]],
    pressure_kpa: np.ndarray,
    contact: np.ndarray,
    area_true_px: np.ndarray,
    prob_threshold: float,
    min_contact_area_px: float,
) -> list[FrameResult]:
    """Per-frame metrics of a batch of predictions.

    Args:
        prob: ``(N, S, S) float32`` probabilities.
        target: ``(N, S, S)`` {0, 1} masks in network pixels.
        boxes, shapes: each frame's crop and input ``(H, W)``.
        pressure_kpa, contact, area_true_px: ``(N,)`` truth.
        prob_threshold: probability above which a pixel is contact.
        min_contact_area_px: network pixels; a smaller predicted region means no contact.
    """
    out = []
    for i in range(prob.shape[0]):
        pred = prob[i] > prob_threshold
        t = target[i] > 0
        union = int((pred | t).sum())
        iou = 1.0 if union == 0 else float((pred & t).sum()) / union
        is_contact = float(pred.sum()) >= min_contact_area_px
        area = 0.0
        if is_contact:
            area = float((from_network(prob[i], boxes[i], shapes[i]) > prob_threshold).sum())
        out.append(
            FrameResult(
                float(pressure_kpa[i]),
                bool(contact[i]),
                is_contact,
                iou,
                area,
                float(area_true_px[i]),
            )
        )
    return out


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def rel_area_error(r: FrameResult) -> float:
    """``|pred - true| / true`` (frames with true contact area > 0 only)."""
    return abs(r.area_pred_px - r.area_true_px) / r.area_true_px


def summarise(results: Sequence[FrameResult]) -> dict[str, float | None]:
    """Epoch summary; None where a quantity is undefined (no such frames).

    Keys: ``val_iou`` (mean over all frames), ``val_iou_contact`` (mean over contact frames),
    ``rel_area_err_ge5`` / ``rel_area_err_3to5`` (median over contact frames at >= 5 and
    3-5 kPa), ``no_contact_acc`` (fraction of no-contact frames predicted as no contact),
    ``contact_recall`` (fraction of contact frames predicted as contact).
    """
    contact = [r for r in results if r.contact_true and r.area_true_px > 0]
    free = [r for r in results if not r.contact_true]
    return {
        "val_iou": float(np.mean([r.iou for r in results])) if results else None,
        "val_iou_contact": float(np.mean([r.iou for r in contact])) if contact else None,
        "rel_area_err_ge5": _median([rel_area_error(r) for r in contact if r.pressure_kpa >= 5]),
        "rel_area_err_3to5": _median(
            [rel_area_error(r) for r in contact if 3 <= r.pressure_kpa < 5]
        ),
        "no_contact_acc": float(np.mean([not r.contact_pred for r in free])) if free else None,
        "contact_recall": float(np.mean([r.contact_pred for r in contact])) if contact else None,
    }


def bin_table(
    results: Sequence[FrameResult], bins: Sequence[tuple[float, float]] = PRESSURE_BINS
) -> list[dict[str, object]]:
    """Per-pressure-bin validation table (rows for non-empty bins; "" where undefined)."""
    rows: list[dict[str, object]] = []
    for lo, hi in bins:
        sel = [r for r in results if lo <= r.pressure_kpa < hi]
        if not sel:
            continue
        s = summarise(sel)
        contact = [r for r in sel if r.contact_true and r.area_true_px > 0]
        rows.append(
            {
                "bin_kpa": f"{lo:g}-{hi:g}" if hi < 1e8 else f">={lo:g}",
                "frames": len(sel),
                "contact_frames": len(contact),
                "iou_median": _median([r.iou for r in contact]),
                "rel_area_err_median": _median([rel_area_error(r) for r in contact]),
                "no_contact_acc": s["no_contact_acc"],
                "contact_recall": s["contact_recall"],
            }
        )
    return [{k: ("" if v is None else v) for k, v in row.items()} for row in rows]

"""Loss and validation metrics.

Loss = BCE + soft Dice. BCE is a per-pixel proper scoring rule (calibrated probabilities, stable
gradients, and it is what teaches "no contact" on pre-onset frames); soft Dice, computed per
frame over the frames with contact, weights each frame's region as a whole regardless of its
size, so small contacts near the onset (a few % of the pixels) are not drowned by the
background, and it tracks the overlap/area we are judged on.

Validation makes the DEPLOYED decision: every probability map goes through
:func:`contactcal.infer.methods.unet.postprocess.postprocess` (pixels outside the image masked,
largest connected region above the threshold, minimum area, area in input pixels = network
pixels × the crop's scale²) and becomes a :class:`~contactcal.infer.bench.scoring.ScoredFrame`,
the record ``contactcal bench`` scores; the per-bin table is
:func:`~contactcal.infer.bench.scoring.bin_table`. So ``best.pt`` is selected on the numbers the
benchmark reports. IoU is computed in network pixels (the kept region vs the cached mask), which
avoids keeping full-resolution masks in memory.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch
import torch.nn.functional as F

from contactcal.infer.bench.dataset import IndexRow
from contactcal.infer.bench.scoring import ScoredFrame, bin_row
from contactcal.infer.methods.unet.crop import CropBox
from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.infer.methods.unet.spec import ModelSpec
from contactcal.train.data import CachedSet

#: Keys of :func:`summarise` (columns of metrics.csv); ``val_iou`` selects ``best.pt``.
SUMMARY_KEYS = (
    "val_iou",
    "val_iou_contact",
    "rel_area_err_ge5",
    "rel_area_err_3to5",
    "no_contact_acc",
    "contact_recall",
)


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


def score_frame(
    prob: np.ndarray,
    target: np.ndarray,
    box: CropBox,
    shape: tuple[int, int],
    row: IndexRow,
    true_area_px: float,
    spec: ModelSpec,
) -> ScoredFrame:
    """One validation frame, decided by the deployed :func:`postprocess`.

    Args:
        prob: ``(S, S) float32`` probabilities in network pixels.
        target: ``(S, S)`` {0, 1} true mask in network pixels (same crop).
        box, shape: the frame's crop and input ``(H, W)``.
        row: the frame's index row (session, pressure, mm/px, onset, hard).
        true_area_px: true mask area, input pixels.
        spec: threshold and minimum area (network pixels).

    Returns:
        The frame's record (method ``"unet"``); ``iou`` of the kept region vs ``target`` in
        network pixels, 1.0 when both are empty.
    """
    seg = postprocess(prob.astype(np.float32), box, shape, spec)
    t = target > 0
    union = int((seg.mask_net | t).sum())
    iou = 1.0 if union == 0 else float((seg.mask_net & t).sum()) / union
    return ScoredFrame(
        method="unet",
        session=row.session_key,
        frame=str(row.frame),
        pressure_kpa=row.pressure_kpa,
        true_area_px=float(true_area_px),
        area_px=seg.area_px,
        contact=seg.contact,
        iou=iou,
        mm_per_px=row.mm_per_px,
        onset_kpa=row.onset_kpa,
        hard=row.hard,
    )


def score_batch(
    prob: np.ndarray, data: CachedSet, start: int, spec: ModelSpec
) -> list[ScoredFrame]:
    """:func:`score_frame` for ``prob`` ``(B, S, S)`` = frames ``start .. start + B - 1``."""
    return [
        score_frame(
            p,
            data.y[start + k, 0].numpy(),
            data.boxes[start + k],
            data.shapes[start + k],
            data.rows[start + k],
            float(data.area_px[start + k]),
            spec,
        )
        for k, p in enumerate(prob)
    ]


@torch.no_grad()
def evaluate(
    model: torch.nn.Module,
    data: CachedSet,
    spec: ModelSpec,
    loss_weights: tuple[float, float],
    batch_size: int,
    device: torch.device,
) -> tuple[float | None, list[ScoredFrame]]:
    """Validation loss (mean over frames) and scored frames; ``(None, [])`` when empty.

    Args:
        loss_weights: ``(bce_weight, dice_weight)``.
    """
    if len(data) == 0:
        return None, []
    model.eval()
    total, frames = 0.0, []
    for i in range(0, len(data), batch_size):
        x = data.x[i : i + batch_size].to(device).float()
        y = data.y[i : i + batch_size].to(device).float()
        logits = model(x)
        total += float(segmentation_loss(logits, y, *loss_weights)) * len(x)
        frames += score_batch(torch.sigmoid(logits)[:, 0].cpu().numpy(), data, i, spec)
    return total / len(data), frames


def summarise(frames: Sequence[ScoredFrame]) -> dict[str, float | None]:
    """Epoch summary (:data:`SUMMARY_KEYS`); None where a quantity is undefined (no frames).

    ``val_iou``: mean IoU over all frames (1.0 for a correctly empty prediction; selects
    ``best.pt``); ``val_iou_contact``: mean over frames with true contact;
    ``rel_area_err_ge5`` / ``rel_area_err_3to5``: median ``|area - true| / true`` of contact
    frames at >= 5 and 3-5 kPa; ``no_contact_acc``: fraction of no-contact frames decided "no
    contact"; ``contact_recall``: fraction of contact frames decided "contact". The medians and
    fractions are :func:`contactcal.infer.bench.scoring.bin_row`'s.
    """
    ious = [f.iou for f in frames if f.iou is not None]
    contact = [f.iou for f in frames if f.true_contact and f.iou is not None]
    every = bin_row(frames)
    return {
        "val_iou": float(np.mean(ious)) if ious else None,
        "val_iou_contact": float(np.mean(contact)) if contact else None,
        "rel_area_err_ge5": _err([f for f in frames if f.pressure_kpa >= 5.0]),
        "rel_area_err_3to5": _err([f for f in frames if 3.0 <= f.pressure_kpa < 5.0]),
        "no_contact_acc": _float(every["no_contact_accuracy"]),
        "contact_recall": _float(every["contact_recall"]),
    }


def _float(v: float | int | None) -> float | None:
    return None if v is None else float(v)


def _err(frames: Sequence[ScoredFrame]) -> float | None:
    return _float(bin_row(frames)["median_abs_rel_error"])

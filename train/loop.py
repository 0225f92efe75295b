"""Training loop: cached data → U-Net with BCE + soft Dice, AdamW, one-cycle schedule, resume."""

from __future__ import annotations

import dataclasses
import math
import os
import platform
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch
from tqdm import tqdm

from contactcal.infer import __version__
from contactcal.infer.atomic import write_json
from contactcal.infer.preprocess import PreprocessConfig
from contactcal.train.augment import AugmentConfig, Augmenter
from contactcal.train.checkpoint import (
    config_diff,
    config_from_dict,
    config_to_dict,
    load_checkpoint,
    rng_state,
    save_checkpoint,
    set_rng_state,
)
from contactcal.train.data import (
    CachedSet,
    build_cache,
    dataset_digest,
    load_records,
    split_by_finger,
)
from contactcal.train.metrics import bin_table, frame_results, segmentation_loss, summarise
from contactcal.train.model import UNet, UNetConfig, count_parameters
from contactcal.train.report import METRIC_COLUMNS, plot_curves, write_csv


@dataclass(frozen=True)
class TrainConfig:
    """Everything a run depends on (written resolved to ``config.json``)."""

    epochs: int = 40  # passes over the training frames; more fits better, costs linear time
    batch_size: int = 16  # frames per step; larger is smoother but fewer steps per epoch
    lr: float = 3e-3  # peak learning rate of the one-cycle schedule; higher diverges
    weight_decay: float = 1e-4  # AdamW decoupled decay; regularises the tiny model lightly
    seed: int = 0  # split, weight init, shuffling and augmentation
    input_size: int = 256  # px, network input side (overrides preprocess.input_size)
    use_reference: bool = True  # 2nd channel = session's zero-pressure frame; helps the onset,
    #   needs a reference frame at deployment
    bce_weight: float = 1.0  # weight of per-pixel BCE (calibration, stable gradients)
    dice_weight: float = 1.0  # weight of per-frame soft Dice (small contacts count fully)
    device: str = "auto"  # "cpu", "cuda" or "auto" (cuda when available)
    num_threads: int = 0  # torch CPU threads; 0 = torch's default
    val_fraction: float = 0.2  # fraction of FINGERS held out for validation
    prob_threshold: float = 0.5  # probability above which a pixel is contact
    min_contact_area_px: float = 30.0  # network px at input_size; smaller predicted regions are
    #   "no contact" (higher misses the onset, lower reports specks as contact)
    model: UNetConfig = field(default_factory=UNetConfig)  # in_channels is set from use_reference
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)  # size from input_size
    augment: AugmentConfig = field(default_factory=AugmentConfig)  # training-time only

    def __post_init__(self) -> None:
        if self.epochs < 1 or self.batch_size < 2:
            raise ValueError(
                f"epochs must be >= 1 and batch_size >= 2, got {self.epochs}, {self.batch_size}"
            )
        if self.device not in ("cpu", "cuda", "auto"):
            raise ValueError(f"device must be cpu, cuda or auto, got {self.device!r}")
        if self.input_size < 16:
            raise ValueError(f"input_size must be >= 16 px, got {self.input_size}")
        if not 0.0 < self.prob_threshold < 1.0:
            raise ValueError(f"prob_threshold must be in (0, 1), got {self.prob_threshold}")

    def resolved(self) -> TrainConfig:
        """Copy with the derived fields of the nested configs made consistent."""
        return dataclasses.replace(
            self,
            model=dataclasses.replace(self.model, in_channels=2 if self.use_reference else 1),
            preprocess=dataclasses.replace(self.preprocess, input_size=self.input_size),
        )


def resolve_device(name: str) -> torch.device:
    """``"auto"`` → cuda when available, else cpu; ``"cuda"`` without CUDA → ValueError."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise ValueError("device 'cuda' requested but torch sees no CUDA device; use cpu or auto")
    return torch.device(name)


@torch.no_grad()
def evaluate(
    model: torch.nn.Module, data: CachedSet, config: TrainConfig, device: torch.device
) -> tuple[float | None, list]:
    """Validation loss (mean over frames) and per-frame results; ``(None, [])`` when empty."""
    if len(data) == 0:
        return None, []
    model.eval()
    total, results = 0.0, []
    for i in range(0, len(data), config.batch_size):
        x = data.x[i : i + config.batch_size].to(device).float()
        y = data.y[i : i + config.batch_size].to(device).float()
        logits = model(x)
        total += float(segmentation_loss(logits, y, config.bce_weight, config.dice_weight)) * len(x)
        j = slice(i, i + len(x))
        results += frame_results(
            torch.sigmoid(logits)[:, 0].cpu().numpy(),
            data.y[j, 0].numpy(),
            data.boxes[j],
            data.shapes[j],
            data.pressure_kpa[j].numpy(),
            data.contact[j].numpy(),
            data.area_px[j].numpy(),
            config.prob_threshold,
            config.min_contact_area_px,
        )
    return total / len(data), results


def _run_info(
    cfg: TrainConfig, data_dirs: Sequence[Path], digest: str, split: dict, dev: Any
) -> dict:
    return {
        "train": config_to_dict(cfg),
        "data_dirs": [str(d) for d in data_dirs],
        "data_digest": digest,
        "split": split,
        "device": str(dev),
        "contactcal_version": __version__,
        "torch_version": torch.__version__,
        "python": platform.python_version(),
    }


def train(
    data_dirs: Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str],
    config: TrainConfig = TrainConfig(),
    resume: bool = False,
    progress: bool = True,
) -> dict[str, Any]:
    """Train (or resume) a run.

    Args:
        data_dirs: dataset folders (``index.csv`` layout).
        out_dir: run folder; receives ``config.json``, ``last.pt``, ``best.pt``, ``metrics.csv``,
            ``curves.png`` and ``val_bins.csv``.
        config: run settings; with ``resume`` it must equal the run's saved config.
        resume: continue from ``out_dir/last.pt`` (model, optimizer, scheduler, epoch, RNGs).
        progress: tqdm bars.

    Returns:
        Summary: ``best_epoch``, ``best_score`` (val IoU, or -train loss without validation),
        ``parameters``, ``epochs_run``, ``out_dir``, and the final ``val`` summary.

    Raises:
        ValueError: bad dataset, config, or resume request.
    """
    cfg = config.resolved()
    out = Path(out_dir)
    dirs = [Path(d) for d in data_dirs]
    records = load_records(dirs)
    digest = dataset_digest(dirs)
    train_recs, val_recs = split_by_finger(records, cfg.val_fraction, cfg.seed)
    if len(train_recs) < 2:
        raise ValueError(
            f"{dirs[0]}: need >= 2 training frames after the split, got {len(train_recs)}"
        )
    split = {
        "train": sorted({r.finger_key for r in train_recs}),
        "val": sorted({r.finger_key for r in val_recs}),
    }
    device = resolve_device(cfg.device)
    if cfg.num_threads > 0:
        torch.set_num_threads(cfg.num_threads)
    if not resume and (out / "last.pt").exists():
        raise ValueError(f"{out}: already holds a run (last.pt); pass --resume or another --out")
    ckpt = load_checkpoint(out / "last.pt") if resume else None
    if ckpt is not None:
        saved = config_from_dict(TrainConfig, ckpt["config"], str(out / "last.pt"))
        diff = [k for k in config_diff(saved, cfg) if k not in ("device", "num_threads")]
        if diff:
            raise ValueError(f"{out}: --resume with a different config ({', '.join(diff)})")
        if ckpt["data_digest"] != digest:
            raise ValueError(f"{out}: --resume with different data (index.csv digest changed)")

    torch.manual_seed(cfg.seed)
    model = UNet(cfg.model).to(device)
    train_set = build_cache(train_recs, cfg.preprocess, cfg.use_reference, progress)
    val_set = build_cache(val_recs, cfg.preprocess, cfg.use_reference, progress)
    n = len(train_set)
    steps = math.ceil(n / cfg.batch_size)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    sched = torch.optim.lr_scheduler.OneCycleLR(
        opt, max_lr=cfg.lr, total_steps=cfg.epochs * steps, pct_start=0.15
    )
    shuffle = torch.Generator().manual_seed(cfg.seed)
    augment = Augmenter(cfg.augment, cfg.preprocess).to(device)
    start, history, best, best_epoch = 0, [], -math.inf, -1
    if ckpt is not None:
        model.load_state_dict(ckpt["model"])
        opt.load_state_dict(ckpt["optimizer"])
        sched.load_state_dict(ckpt["scheduler"])
        shuffle.set_state(ckpt["shuffle_rng"])
        set_rng_state(ckpt["rng"])
        start, history = int(ckpt["epoch"]) + 1, list(ckpt["history"])
        best, best_epoch = float(ckpt["best_score"]), int(ckpt["best_epoch"])
    write_json(out / "config.json", _run_info(cfg, dirs, digest, split, device))

    for epoch in range(start, cfg.epochs):
        t0 = time.perf_counter()
        model.train()
        perm = torch.randperm(n, generator=shuffle)
        batches = [perm[i : i + cfg.batch_size] for i in range(0, n, cfg.batch_size)]
        running = 0.0
        seen = 0
        bar = tqdm(
            batches, desc=f"epoch {epoch + 1}/{cfg.epochs}", disable=not progress, leave=False
        )
        for idx in bar:
            x = train_set.x[idx].to(device).float()
            y = train_set.y[idx].to(device).float()
            x, y = augment(x, y)
            loss = segmentation_loss(model(x), y, cfg.bce_weight, cfg.dice_weight)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            sched.step()
            running += loss.item() * len(idx)
            seen += len(idx)
            bar.set_postfix(loss=f"{running / seen:.4f}")
        val_loss, results = evaluate(model, val_set, cfg, device)
        row: dict[str, Any] = {
            "epoch": epoch + 1,
            "train_loss": running / seen,
            "val_loss": val_loss,
            "lr": float(sched.get_last_lr()[0]),
            **summarise(results),
            "seconds": time.perf_counter() - t0,
        }
        history.append(row)
        score = row["val_iou"] if row["val_iou"] is not None else -row["train_loss"]
        meta = {"config": config_to_dict(cfg), "data_digest": digest, "epoch": epoch}
        if score > best:
            best, best_epoch = score, epoch + 1
            save_checkpoint(out / "best.pt", {**meta, "model": model.state_dict(), "metrics": row})
        save_checkpoint(
            out / "last.pt",
            {
                **meta,
                "model": model.state_dict(),
                "optimizer": opt.state_dict(),
                "scheduler": sched.state_dict(),
                "shuffle_rng": shuffle.get_state(),
                "rng": rng_state(),
                "history": history,
                "best_score": best,
                "best_epoch": best_epoch,
            },
        )
        write_csv(out / "metrics.csv", history, METRIC_COLUMNS)
        plot_curves(out / "curves.png", history)
        if progress:
            tqdm.write(_format_row(row))

    model.load_state_dict(load_checkpoint(out / "best.pt")["model"])
    _, results = evaluate(model, val_set, cfg, device)
    bins = bin_table(results)
    write_csv(out / "val_bins.csv", bins, list(bins[0]) if bins else ["bin_kpa"])
    return {
        "out_dir": str(out),
        "best_epoch": best_epoch,
        "best_score": best,
        "epochs_run": cfg.epochs - start,
        "parameters": count_parameters(model),
        "train_frames": n,
        "val_frames": len(val_set),
        "val": summarise(results),
    }


def _format_row(row: dict[str, Any]) -> str:
    parts = [f"epoch {row['epoch']}"]
    for key in ("train_loss", "val_loss", "val_iou", "rel_area_err_ge5", "no_contact_acc"):
        v = row.get(key)
        parts.append(f"{key}={'-' if v is None else f'{v:.4f}'}")
    return "  ".join(parts)

"""Training loop: cached data → U-Net with BCE + soft Dice, AdamW, one-cycle schedule, resume.

:func:`train` reads as its three steps: :func:`_prepare` (data and split,
:mod:`~contactcal.train.run_data`; model, optimiser and generators, restored from ``last.pt`` on
resume), :func:`_run_epochs` (train, validate with the deployed decision, checkpoint) and
:func:`_finish` (``best.pt`` on the validation fingers). With ``ema_decay`` > 0 the weights'
running average is validated and saved; ``last.pt`` keeps both.

Randomness is explicit: the finger split (numpy Generator from ``seed``), weight init (torch's
global generator seeded with ``seed``), the batch order (``Run.shuffle``, seeded ``seed``) and the
augmentation (the Augmenter's own generator, seeded ``seed + 1``); all states are checkpointed.
"""

from __future__ import annotations

import math
import os
import platform
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch
from tqdm import tqdm

from contactcal.infer import __version__
from contactcal.infer.bench.scoring import ScoredFrame, bin_table
from contactcal.infer.files.atomic import write_json
from contactcal.train.augment import Augmenter
from contactcal.train.checkpoint import (
    config_to_dict,
    load_checkpoint,
    rng_state,
    save_checkpoint,
    set_rng_state,
)
from contactcal.train.config import TrainConfig, resolve_device
from contactcal.train.data import CachedSet, build_cache
from contactcal.train.ema import WeightAverage
from contactcal.train.metrics import evaluate, segmentation_loss, summarise
from contactcal.train.model import UNet, count_parameters
from contactcal.train.report import METRIC_COLUMNS, plot_curves, write_csv
from contactcal.train.resume import finished_summary, is_finished, resume_checkpoint
from contactcal.train.run_data import run_data
from contactcal.train.run_folder import check_run_folder
from contactcal.train.split import Split


@dataclass
class Run:
    """A run's state between the steps of :func:`train`."""

    cfg: TrainConfig  # resolved
    out: Path  # run folder
    digest: str  # sha256 of the index.csv files
    device: torch.device
    train_set: CachedSet
    val_set: CachedSet
    model: UNet
    opt: torch.optim.Optimizer
    sched: torch.optim.lr_scheduler.LRScheduler
    shuffle: torch.Generator  # batch order
    augment: Augmenter  # owns the augmentation generator
    start: int = 0  # first epoch to run (0-based)
    history: list[dict[str, Any]] = field(default_factory=list)  # metrics.csv rows
    best: float = -math.inf  # best selection score so far
    best_epoch: int = -1  # 1-based epoch of best.pt
    average: WeightAverage | None = None  # the weights' running average (ema_decay > 0)
    info: dict[str, Any] = field(default_factory=dict)  # config.json, written with last.pt

    @property
    def scored(self) -> torch.nn.Module:
        """The model that is validated and saved: the running average when there is one."""
        return self.model if self.average is None else self.average.model


def _run_info(
    cfg: TrainConfig, data_dirs: Sequence[Path], digests: tuple[str, str], split: Split, dev: Any
) -> dict[str, Any]:
    """The content of ``config.json``."""
    return {
        "train": config_to_dict(cfg),
        "data_dirs": [str(Path(d).resolve()) for d in data_dirs],  # export reads them anywhere
        "data_digest": digests[0],  # the frames' rows (index.csv): the model's provenance
        "render_digest": digests[1],  # how they were rendered (config.json): export checks it
        "split": split,
        "device": str(dev),
        "contactcal_version": __version__,
        "torch_version": torch.__version__,
        "python": platform.python_version(),
    }


def _prepare(dirs: list[Path], out: Path, cfg: TrainConfig, resume: bool, progress: bool) -> Run:
    """Step 1: data, split, model, optimiser, schedule and generators (restored on resume)."""
    check_run_folder(out, resume)
    train_rows, val_rows, digests, split = run_data(cfg, dirs)
    device = resolve_device(cfg.device)
    if cfg.num_threads > 0:
        torch.set_num_threads(cfg.num_threads)
    ckpt = resume_checkpoint(out, cfg, digests, split) if resume else None
    torch.manual_seed(cfg.seed)  # weight init
    model = UNet(cfg.model).to(device)
    c = cfg.model.in_channels
    train_set = build_cache(train_rows, cfg.preprocess, c, progress)
    val_set = build_cache(val_rows, cfg.preprocess, c, progress)
    steps = math.ceil(len(train_set) / cfg.batch_size)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    sched = torch.optim.lr_scheduler.OneCycleLR(
        opt, max_lr=cfg.lr, total_steps=cfg.epochs * steps, pct_start=0.15
    )
    shuffle = torch.Generator().manual_seed(cfg.seed)
    # A stream apart from the shuffling's (seeded cfg.seed).
    augment = Augmenter(
        cfg.augment, cfg.preprocess, seed=cfg.seed + 1, reference_dropout=cfg.reference_dropout
    ).to(device)
    run = Run(cfg, out, digests[0], device, train_set, val_set, model, opt, sched, shuffle, augment)
    if cfg.ema_decay > 0.0:
        run.average = WeightAverage(model, cfg.ema_decay)
    if ckpt is not None:
        model.load_state_dict(ckpt.get("trained_model", ckpt["model"]))
        if run.average is not None:
            run.average.model.load_state_dict(ckpt["model"])
        opt.load_state_dict(ckpt["optimizer"])
        sched.load_state_dict(ckpt["scheduler"])
        shuffle.set_state(ckpt["shuffle_rng"])
        augment.generator.set_state(ckpt["augment_rng"])
        set_rng_state(ckpt["rng"])
        run.start, run.history = int(ckpt["epoch"]) + 1, list(ckpt["history"])
        run.best, run.best_epoch = float(ckpt["best_score"]), int(ckpt["best_epoch"])
    run.info = _run_info(cfg, dirs, digests, split, device)  # written with last.pt
    return run


def _train_epoch(run: Run, epoch: int, progress: bool) -> float:
    """Step 2a: one pass over the training frames; returns the mean training loss."""
    cfg, data = run.cfg, run.train_set
    run.model.train()
    n = len(data)
    perm = torch.randperm(n, generator=run.shuffle)
    batches = [perm[i : i + cfg.batch_size] for i in range(0, n, cfg.batch_size)]
    running, seen = 0.0, 0
    bar = tqdm(batches, desc=f"epoch {epoch + 1}/{cfg.epochs}", disable=not progress, leave=False)
    for idx in bar:
        x = data.x[idx].to(run.device).float()
        y = data.y[idx].to(run.device).float()
        x, y = run.augment(x, y, data.levels[idx].to(run.device))
        loss = segmentation_loss(run.model(x), y, cfg.bce_weight, cfg.dice_weight)
        run.opt.zero_grad(set_to_none=True)
        loss.backward()
        run.opt.step()
        run.sched.step()
        if run.average is not None:
            run.average.update(run.model)
        running += loss.item() * len(idx)
        seen += len(idx)
        bar.set_postfix(loss=f"{running / seen:.4f}")
    return running / seen


def _validate(run: Run) -> tuple[float | None, list[ScoredFrame]]:
    """Validation loss and the deployed decision on every validation frame."""
    cfg = run.cfg
    weights = (cfg.bce_weight, cfg.dice_weight)
    return evaluate(run.scored, run.val_set, cfg.spec(), weights, cfg.batch_size, run.device)


def _save_epoch(run: Run, epoch: int, row: dict[str, Any]) -> None:
    """Step 2b: ``best.pt`` (when the score improved), ``last.pt``, metrics.csv, curves.png."""
    score = row["val_iou"] if row["val_iou"] is not None else -row["train_loss"]
    meta = {"config": config_to_dict(run.cfg), "data_digest": run.digest, "epoch": epoch}
    weights = run.scored.state_dict()
    if score > run.best:
        run.best, run.best_epoch = score, epoch + 1
        save_checkpoint(run.out / "best.pt", {**meta, "model": weights, "metrics": row})
    state = {
        "trained_model": run.model.state_dict(),  # differs from "model" with an average
        "optimizer": run.opt.state_dict(),
        "scheduler": run.sched.state_dict(),
        "shuffle_rng": run.shuffle.get_state(),
        "augment_rng": run.augment.generator.get_state(),
        "rng": rng_state(),
        "history": run.history,
        "best_score": run.best,
        "best_epoch": run.best_epoch,
    }
    save_checkpoint(run.out / "last.pt", {**meta, "model": weights, **state})
    # a run killed before its first epoch ends leaves no config.json
    _write_records(run, config=epoch == run.start)


def _write_records(run: Run, config: bool) -> None:
    """``config.json`` (when ``config``), metrics.csv and curves.png, from the run's history."""
    if config:
        write_json(run.out / "config.json", run.info)
    write_csv(run.out / "metrics.csv", run.history, METRIC_COLUMNS)
    plot_curves(run.out / "curves.png", run.history, run.best_epoch)


def _run_epochs(run: Run, progress: bool) -> None:
    """Step 2: train, validate and checkpoint each remaining epoch."""
    for epoch in range(run.start, run.cfg.epochs):
        t0 = time.perf_counter()
        train_loss = _train_epoch(run, epoch, progress)
        val_loss, frames = _validate(run)
        row: dict[str, Any] = {
            "epoch": epoch + 1,
            "train_loss": train_loss,
            "val_loss": val_loss,
            "lr": float(run.sched.get_last_lr()[0]),
            **summarise(frames),
            "seconds": time.perf_counter() - t0,
        }
        run.history.append(row)
        _save_epoch(run, epoch, row)
        if progress:
            tqdm.write(_format_row(row), file=sys.stderr)  # progress; stdout: the summary


def _finish(run: Run) -> dict[str, Any]:
    """Step 3: ``best.pt`` on the validation fingers → val_bins.csv and the summary."""
    run.scored.load_state_dict(load_checkpoint(run.out / "best.pt")["model"])
    _, frames = _validate(run)
    bins = bin_table(frames)
    write_csv(run.out / "val_bins.csv", bins, list(bins[0]) if bins else ["method", "bin_kpa"])
    return {
        "out_dir": str(run.out),
        "best_epoch": run.best_epoch,
        "best_score": run.best,
        "epochs_run": run.cfg.epochs - run.start,
        "parameters": count_parameters(run.model),  # the average's are frozen, not counted
        "train_frames": len(run.train_set),
        "val_frames": len(run.val_set),
        "val": summarise(frames),
    }


def train(
    data_dirs: Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str],
    config: TrainConfig | None = None,
    resume: bool = False,
    progress: bool = True,
) -> dict[str, Any]:
    """Train (or resume) a run: prepare → run the epochs → finish.

    Args:
        data_dirs: dataset folders (``index.csv`` layout).
        out_dir: run folder, new or empty (or the run's, with ``resume``); receives
            ``config.json``, ``last.pt``, ``best.pt``, ``metrics.csv``, ``curves.png`` and
            ``val_bins.csv``.
        config: run settings (None: the defaults); with ``resume`` it must equal the run's
            saved config.
        resume: continue from ``out_dir/last.pt`` (model, optimizer, scheduler, epoch, RNGs)
            with the run's data and split; a finished run (one holding ``val_bins.csv``) is
            checked alike (config, data, split) and left as it is: nothing is written.
        progress: tqdm bars.

    Returns:
        Summary: ``best_epoch``, ``best_score`` (val IoU, or -train loss without validation),
        ``parameters``, ``epochs_run``, ``out_dir``, and the final ``val`` summary; for a
        finished run resumed, :func:`~contactcal.train.resume.finished_summary`'s.

    Raises:
        ValueError: bad dataset, config, or resume request, or an ``out_dir`` that is not new,
            empty or (with ``resume``) a run holding ``last.pt``.
    """
    cfg = (config or TrainConfig()).resolved()
    dirs = [Path(d) for d in data_dirs]
    if resume and is_finished(Path(out_dir)):  # checked as any run, then left as it is
        ckpt = resume_checkpoint(Path(out_dir), cfg, *run_data(cfg, dirs)[2:])
        return finished_summary(Path(out_dir), ckpt)
    run = _prepare(dirs, Path(out_dir), cfg, resume, progress)
    if run.start == cfg.epochs:  # killed after its last last.pt: complete what follows it
        _write_records(run, config=True)
    _run_epochs(run, progress)
    return _finish(run)


def _format_row(row: dict[str, Any]) -> str:
    parts = [f"epoch {row['epoch']}"]
    for key in ("train_loss", "val_loss", "val_iou", "rel_area_err_ge5", "no_contact_acc"):
        v = row.get(key)
        parts.append(f"{key}={'-' if v is None else f'{v:.4f}'}")
    return "  ".join(parts)

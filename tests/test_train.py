"""Training package: model shapes/size, augmentation, data validation and split, loop, CLI."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest
from procedural import write_dataset

torch = pytest.importorskip("torch")
pytest.importorskip("kornia")

import numpy as np  # noqa: E402

from contactcal.infer.bench.dataset import IndexRow, read_datasets  # noqa: E402
from contactcal.infer.cli import main  # noqa: E402
from contactcal.infer.methods.unet.config import PreprocessConfig  # noqa: E402
from contactcal.infer.methods.unet.crop import CropBox  # noqa: E402
from contactcal.infer.methods.unet.prepare import network_to_unit, unit_to_network  # noqa: E402
from contactcal.infer.methods.unet.spec import ModelSpec  # noqa: E402
from contactcal.train.augment import AugmentConfig, Augmenter, blur_kernel_size  # noqa: E402
from contactcal.train.checkpoint import config_from_dict, config_to_dict  # noqa: E402
from contactcal.train.commands import add_parsers, build_config  # noqa: E402
from contactcal.train.config import TrainConfig  # noqa: E402
from contactcal.train.data import build_cache  # noqa: E402
from contactcal.train.loop import train  # noqa: E402
from contactcal.train.metrics import score_frame, segmentation_loss, summarise  # noqa: E402
from contactcal.train.model import UNet, UNetConfig, count_parameters  # noqa: E402
from contactcal.train.split import split_by_finger  # noqa: E402


def tiny_config(**kw: object) -> TrainConfig:
    """A seconds-long run: 32 px inputs, a ~1k-parameter U-Net, no augmentation."""
    base = {
        "epochs": 2,
        "batch_size": 4,
        "input_size": 32,
        "lr": 1e-2,
        "num_threads": 1,
        "device": "cpu",
        "val_fraction": 0.25,
        "min_contact_area_px": 4.0,
        "model": UNetConfig(base=4, levels=2),
        "augment": AugmentConfig(enabled=False),
    }
    base.update(kw)
    return TrainConfig(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize("size", [32, 48, 64])
@pytest.mark.parametrize("channels", [1, 2])
def test_forward_shapes(size: int, channels: int) -> None:
    model = UNet(UNetConfig(in_channels=channels)).eval()
    with torch.no_grad():
        assert model(torch.zeros(2, channels, size, size)).shape == (2, 1, size, size)
        assert model(torch.zeros(2, channels, size + 5, size - 3)).shape == (
            2,
            1,
            size + 5,
            size - 3,
        )


def test_parameter_budget() -> None:
    assert count_parameters(UNet(UNetConfig(in_channels=2))) <= 500_000
    assert count_parameters(UNet(UNetConfig(in_channels=2, base=16, levels=4))) <= 500_000


def _aug_batch() -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(0)
    u = torch.rand((4, 2, 64, 64), generator=g) * 0.2
    u[:, :, 16:40, 10:50] = 0.9
    return unit_to_network(u, PreprocessConfig()), (u[:, :1] > 0.5).float()


def test_augment_keeps_mask_aligned() -> None:
    geometric = AugmentConfig(
        brightness=0.0, contrast=0.0, gamma=(1.0, 1.0), blur_p=0.0, noise_p=0.0, affine_p=1.0
    )
    aug = Augmenter(geometric, PreprocessConfig(), seed=3)
    x, m = _aug_batch()
    xa, ma = aug(x, m)
    bright = network_to_unit(xa[:, :1], PreprocessConfig()) > 0.55
    assert set(ma.unique().tolist()) <= {0.0, 1.0}
    assert (bright == (ma > 0.5)).float().mean() > 0.98  # only resampled edge pixels differ
    assert ((xa[:, 0] > 0.0) == (xa[:, 1] > 0.0)).float().mean() > 0.98  # channels warped alike


def test_augment_deterministic_per_seed() -> None:
    x, m = _aug_batch()
    before = torch.get_rng_state()
    a = Augmenter(AugmentConfig(), PreprocessConfig(), seed=7)(x, m)
    assert torch.equal(torch.get_rng_state(), before)  # the global generator is not used
    torch.manual_seed(123)  # nor read
    b = Augmenter(AugmentConfig(), PreprocessConfig(), seed=7)(x, m)
    c = Augmenter(AugmentConfig(), PreprocessConfig(), seed=8)(x, m)
    assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[1])
    assert not torch.equal(a[0], c[0])
    # the generator advances, and its state resumes the stream exactly
    aug = Augmenter(AugmentConfig(), PreprocessConfig(), seed=7)
    first = aug(x, m)[0]
    state = aug.generator.get_state()
    second = aug(x, m)[0]
    aug.generator.set_state(state)
    assert torch.equal(first, a[0]) and not torch.equal(first, second)
    assert torch.equal(aug(x, m)[0], second)


def _blurred_variance(sigma: float, taps: int) -> float:
    """Variance (px²) along x of kornia's blur of a unit impulse, as the augmentation applies it."""
    import kornia.filters as KF

    impulse = torch.zeros(1, 1, 31, 31)
    impulse[0, 0, 15, 15] = 1.0
    row = KF.gaussian_blur2d(impulse, (taps, taps), (sigma, sigma))[0, 0].sum(0)
    x = torch.arange(31.0) - 15.0
    return float((row * x**2).sum() / row.sum())


def test_blur_kernel_holds_the_gaussian() -> None:
    cfg = AugmentConfig()
    assert blur_kernel_size(cfg) == 9  # 2·⌈3·1.2⌉ + 1
    assert blur_kernel_size(AugmentConfig(blur_sigma=(0.1, 1.8))) == 13
    assert blur_kernel_size(AugmentConfig(blur_kernel_px=5)) == 5
    hi = cfg.blur_sigma[1]
    assert _blurred_variance(hi, blur_kernel_size(cfg)) == pytest.approx(hi**2, rel=0.01)
    wide = AugmentConfig(blur_sigma=(0.1, 1.5))
    assert blur_kernel_size(wide) == 11
    assert _blurred_variance(1.5, 11) == pytest.approx(1.5**2, rel=0.01)
    # the 5 taps of models up to v2.2 blur σ 1.2 like σ ~1.08 (variance 0.81 σ²)
    assert _blurred_variance(hi, 5) < 0.85 * hi**2
    with pytest.raises(ValueError, match="odd >= 3"):
        AugmentConfig(blur_kernel_px=4)


def test_split_is_by_finger(tmp_path: Path) -> None:
    records = read_datasets([write_dataset(tmp_path / "d", fingers=5)])
    tr, va = split_by_finger(records, 0.4, seed=1)
    assert {r.finger_key for r in tr}.isdisjoint({r.finger_key for r in va})
    assert len({r.finger_key for r in va}) == 2 and len(tr) + len(va) == len(records)
    assert split_by_finger(records, 0.4, seed=1) == (tr, va)


def test_bad_dataset_paths(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="expected a dataset folder"):
        train([tmp_path / "nope"], tmp_path / "run", tiny_config(), progress=False)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="missing index.csv"):
        read_datasets([tmp_path / "empty"])
    d = write_dataset(tmp_path / "d", fingers=1)
    text = (d / "index.csv").read_text()
    (d / "index.csv").write_text(text.replace("pressure_kpa", "p"))
    with pytest.raises(ValueError, match="missing column"):
        read_datasets([d])
    (d / "index.csv").write_text(text)
    (d / "finger_0000" / "frames" / "p04.0kpa.png").unlink()
    with pytest.raises(ValueError, match=r"missing file .*p04\.0kpa\.png"):
        read_datasets([d])


def test_cli_train_refuses_inputs_it_cannot_use_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One folder under two spellings (its fingers on both sides of the split), a run folder
    that is or holds a dataset, a single finger (no validation), a negative seed, an input size
    past any budget: one line each, exit 2, nothing written."""
    d = write_dataset(tmp_path / "d", fingers=3)
    one = write_dataset(tmp_path / "one", fingers=1)
    before = (d / "index.csv").read_bytes()
    run = tmp_path / "run"
    tiny = ["--epochs", "1", "--input-size", "32", "--batch-size", "4", "--base", "4"]
    cases = [
        ([str(d), str(tmp_path / "." / "d")], run, [], "given twice (also as"),
        ([str(d)], d, [], "overlaps the dataset folder"),
        ([str(d)], d / "runs" / "r1", [], "overlaps the dataset folder"),
        ([str(d)], tmp_path, [], "overlaps the dataset folder"),
        ([str(one)], run, [], "1 finger(s), none left for validation"),
        ([str(d)], run, ["--seed", "-1"], "--seed must be >= 0, got -1"),
        ([str(d)], run, ["--input-size", "100000"], "--input-size must be 16-1024 px"),
        ([str(d)], run, ["--blur-sigma", "0.1", "100"], "601-tap blur kernel cannot filter a 32"),
    ]
    for data, out, extra, said in cases:
        argv = ["train", "--data", *data, "--out", str(out), *tiny, *extra, "--quiet"]
        assert main(argv) == 2, said
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], (said, err)
    assert not run.exists() and (d / "index.csv").read_bytes() == before
    assert sorted(p.name for p in d.iterdir()) == sorted(
        p.name for p in write_dataset(tmp_path / "again", fingers=3).iterdir()
    )


def test_a_run_stopped_in_its_first_epoch_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """config.json is written with the first last.pt: a run stopped before leaves no stale
    config that a later --resume would find without a checkpoint."""
    from contactcal.train import loop

    def interrupted(*args: object) -> float:
        raise KeyboardInterrupt

    d = write_dataset(tmp_path / "d", fingers=3)
    monkeypatch.setattr(loop, "_train_epoch", interrupted)
    with pytest.raises(KeyboardInterrupt):
        train([d], tmp_path / "run", tiny_config(epochs=1), progress=False)
    assert not (tmp_path / "run" / "config.json").exists()
    monkeypatch.undo()
    train([d], tmp_path / "run", tiny_config(epochs=1), progress=False)
    assert (tmp_path / "run" / "config.json").is_file() and (tmp_path / "run" / "last.pt").is_file()


def test_config_round_trip() -> None:
    cfg = tiny_config().resolved()
    back = config_from_dict(TrainConfig, config_to_dict(cfg))
    assert back == cfg
    with pytest.raises(ValueError, match="unknown"):
        config_from_dict(TrainConfig, {"nope": 1})


@pytest.mark.slow
def test_steps_decrease_loss(tmp_path: Path) -> None:
    cfg = tiny_config().resolved()
    rows = read_datasets([write_dataset(tmp_path / "d")])
    data = build_cache(rows, cfg.preprocess, cfg.model.in_channels)
    assert data.x.shape == (20, 2, 32, 32) and int(data.y.sum()) > 0
    assert data.rows == rows and len(data.boxes) == len(data.shapes) == 20
    torch.manual_seed(0)
    model = UNet(cfg.model)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-2)
    x, y = data.x.float(), data.y.float()
    losses = []
    for _ in range(25):
        loss = segmentation_loss(model(x), y, 1.0, 1.0)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert losses[-1] < 0.7 * losses[0]


@pytest.mark.slow
def test_train_outputs(tmp_path: Path) -> None:
    d = write_dataset(tmp_path / "d")
    cfg = tiny_config(augment=AugmentConfig())
    summary = train([d], tmp_path / "run", cfg, progress=False)
    for name in ("config.json", "last.pt", "best.pt", "metrics.csv", "curves.png", "val_bins.csv"):
        assert (tmp_path / "run" / name).is_file(), name
    assert summary["val_frames"] == 5 and summary["train_frames"] == 15
    lines = (tmp_path / "run" / "metrics.csv").read_text().splitlines()
    assert lines[0].startswith("epoch,train_loss,val_loss") and len(lines) == 3
    bins = (tmp_path / "run" / "val_bins.csv").read_text()
    assert bins.startswith("method,bin_kpa,frames,") and "nan" not in bins.lower()
    assert summary["val"]["val_iou"] is not None
    with pytest.raises(ValueError, match="already holds a run"):
        train([d], tmp_path / "run", cfg, progress=False)
    done = train([d], tmp_path / "run", cfg, resume=True, progress=False)
    assert done["finished"] and done["epochs_run"] == 0 and done["best_epoch"] >= 1
    (tmp_path / "run" / "val_bins.csv").unlink()  # killed after its last epoch's checkpoint
    with pytest.raises(ValueError, match="different config"):
        train([d], tmp_path / "run", tiny_config(seed=3), resume=True, progress=False)
    again = train([d], tmp_path / "run", tiny_config(augment=AugmentConfig(), device="auto"), True)
    assert again["epochs_run"] == 0  # device/threads may change on resume
    assert (tmp_path / "run" / "val_bins.csv").read_text() == bins


@pytest.mark.slow
@pytest.mark.parametrize(("ema_decay", "floor"), [(0.0, 0.0), (0.9, 0.0), (0.0, 1.0)])
def test_resume_is_exact(tmp_path: Path, ema_decay: float, floor: float) -> None:
    """A run cut after its first epoch and resumed ends as the whole run (with a dark floor
    too: the camera augmentation then reads each sample's cached levels)."""
    d = write_dataset(tmp_path / "d", fingers=3)
    pre = PreprocessConfig(norm_floor_percentile=floor)
    cfg = tiny_config(augment=AugmentConfig(), epochs=2, ema_decay=ema_decay, preprocess=pre)
    summary = train([d], tmp_path / "full", cfg, progress=False)
    assert summary["parameters"] == count_parameters(UNet(cfg.resolved().model)) > 0
    # interrupt the second run right after its first epoch's checkpoint, then resume it
    import contactcal.train.loop as loop

    class Stop(Exception):
        pass

    original = loop.plot_curves

    def stop_after_first(*args: object) -> None:
        original(*args)  # type: ignore[arg-type]
        raise Stop

    loop.plot_curves = stop_after_first  # type: ignore[assignment]
    try:
        with pytest.raises(Stop):
            train([d], tmp_path / "cut", cfg, progress=False)
    finally:
        loop.plot_curves = original  # type: ignore[assignment]
    train([d], tmp_path / "cut", cfg, resume=True, progress=False)
    a = torch.load(tmp_path / "full" / "last.pt", weights_only=True)
    b = torch.load(tmp_path / "cut" / "last.pt", weights_only=True)
    for key in ("model", "trained_model"):  # the average and the trained weights
        assert all(torch.equal(a[key][k], b[key][k]) for k in a[key])
    averaged = any(not torch.equal(a["model"][k], a["trained_model"][k]) for k in a["model"])
    assert averaged == (ema_decay > 0)
    assert len(b["history"]) == 2


def test_cli_parsers(tmp_path: Path) -> None:
    parser = argparse.ArgumentParser(prog="contactcal")
    add_parsers(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(
        [
            "train",
            "--data",
            "a",
            "b",
            "--out",
            "r",
            "--epochs",
            "3",
            "--no-reference",
            "--input-size",
            "64",
            "--threads",
            "2",
            "--ema",
            "0.99",
        ]
    )
    cfg = build_config(args)
    assert args.data == [Path("a"), Path("b")] and cfg.epochs == 3 and not cfg.use_reference
    assert cfg.input_size == 64 and cfg.batch_size == TrainConfig().batch_size
    assert cfg.num_threads == 2 and cfg.ema_decay == 0.99
    args = parser.parse_args(["train", "--data", "a", "--out", "r"])
    assert build_config(args).num_threads == TrainConfig().num_threads
    assert build_config(args).ema_decay == 0.0  # off unless asked
    args = parser.parse_args(["train", "--data", str(tmp_path / "missing"), "--out", "r"])
    with pytest.raises(ValueError, match=r"^--data .*missing: does not exist; expected a data"):
        args.func(args)
    (tmp_path / "empty").mkdir()
    args = parser.parse_args(["train", "--data", str(tmp_path / "empty"), "--out", "r"])
    with pytest.raises(ValueError, match=r"^--data .*empty: missing index\.csv; expected a"):
        args.func(args)
    args = parser.parse_args(["export", "run", "--out", "models/m.onnx"])
    assert args.run_dir == Path("run") and args.out == Path("models/m.onnx")


def test_commands_import_is_light() -> None:
    code = "import sys, contactcal.train.commands; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.slow
def test_cli_train_without_threads(tmp_path: Path) -> None:
    """Regression: `contactcal train` without --threads died with a TypeError in cli.main."""
    d = write_dataset(tmp_path / "d", fingers=3)
    argv = ["train", "--data", str(d), "--out", str(tmp_path / "run"), "--epochs", "1"]
    argv += ["--input-size", "32", "--batch-size", "4", "--base", "4", "--levels", "2"]
    assert main([*argv, "--device", "cpu", "--quiet"]) == 0
    assert (tmp_path / "run" / "best.pt").is_file()


def _row(pressure_kpa: float) -> IndexRow:
    d = Path("data")
    return IndexRow(d, 0, "s", d / "f.png", d / "m.png", pressure_kpa, True, 1.0, 0.1, 3.0, False)


def test_validation_uses_the_deployed_decision() -> None:
    spec = ModelSpec(2, PreprocessConfig(input_size=32), 0.5, 20.0)
    box = CropBox(0, 0, 64)  # 2 input px per network px: areas × 4
    big = np.zeros((32, 32), np.float32)
    big[22:28, 4:10] = 0.9  # 36 network px
    small = np.zeros((32, 32), np.float32)
    small[4:7, 20:23] = 0.9  # 9 network px < min area
    prob = np.maximum(big, small)
    target = (big > 0).astype(np.uint8)
    f = score_frame(prob, target, box, (64, 64), _row(8.0), 144.0, spec)
    assert f.contact and f.area_px == 36 * 4 and f.iou == 1.0  # only the largest region counts
    assert f.method == "unet" and f.session == "data#s" and f.rel_error == 0.0
    f = score_frame(small, target * 0, box, (64, 64), _row(1.0), 0.0, spec)
    assert not f.contact and f.area_px == 0.0  # below the minimum area: no contact
    # rows 22-27 lie outside a 40 px high image: masked, so only the small blob remains
    f = score_frame(prob, target, box, (40, 64), _row(8.0), 144.0, spec)
    assert not f.contact and f.area_px == 0.0 and f.iou == 0.0
    s = summarise([score_frame(prob, target, box, (64, 64), _row(8.0), 144.0, spec), f])
    assert s["contact_recall"] == 0.5 and s["rel_area_err_ge5"] == 0.5
    assert s["no_contact_acc"] is None and s["val_iou"] == 0.5

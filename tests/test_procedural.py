"""The procedural cross-check generator (``contactcal procedural``) and ``bench --crosscheck``."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.crosscheck import SIDE_KEYS
from contactcal.infer.bench.dataset import read_index
from contactcal.infer.bench.run import run_bench
from contactcal.infer.cli import main
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL
from contactcal.infer.pipeline.manifest import read_manifest
from contactcal.infer.pipeline.scale import load_rig_config
from contactcal.synth.layout import parse_pressures
from contactcal.synth.procedural.config import GeneratorConfig
from contactcal.synth.procedural.contact import area_law_mm2
from contactcal.synth.procedural.dataset import build_dataset
from contactcal.synth.procedural.frame import session_frames
from contactcal.synth.procedural.session import finger_params
from contactcal.train import change_gate, interval

PACKAGE = Path(__file__).resolve().parents[1] / "synth" / "procedural"
PRESSURES = (0.0, 2.0, 4.0, 8.0, 14.0)
SMALL = GeneratorConfig(fingers=3, pressures_kpa=PRESSURES, seed=7, width=96, height=72)
TINY_BENCH = BenchConfig(repeats=1, timing_frames=1, full_size=(128, 96), threads=(1,))


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small procedural set (3 sessions × 5 frames, 96×72)."""
    out = tmp_path_factory.mktemp("procedural") / "set"
    build_dataset(out, SMALL)
    return out


def test_layout_and_exact_masks(dataset: Path) -> None:
    rows = read_index(dataset)  # every column `bench` and training need, every file present
    assert len(rows) == 15 and {r.session for r in rows} == {f"finger_{f:04d}" for f in range(3)}
    assert json.loads((dataset / "config.json").read_text())["seed"] == 7
    for r in rows:
        mask = cv2.imread(str(r.mask), cv2.IMREAD_UNCHANGED)
        frame = cv2.imread(str(r.frame), cv2.IMREAD_UNCHANGED)
        assert mask.shape == (72, 96) and frame.shape == (72, 96, 3)
        assert set(np.unique(mask)) <= {0, 255}
        assert r.area_px == int((mask == 255).sum()) and r.contact == (r.area_px > 0)
        assert r.contact == (r.pressure_kpa > r.onset_kpa)  # onset 1.5-5 kPa: 4 kPa may be either
    for session in {r.session for r in rows}:
        frames = read_manifest(dataset / session / "manifest.csv")
        assert [f.pressure_kpa for f in frames] == list(PRESSURES)
        scale = load_rig_config(dataset / session / "rig.json")
        mine = [r.mm_per_px for r in rows if r.session == session]
        assert scale.at_width(96) == pytest.approx(mine[0]) and len(set(mine)) == 1


def test_deterministic_per_seed(dataset: Path, tmp_path: Path) -> None:
    again = tmp_path / "again"
    build_dataset(again, SMALL)
    for path in sorted(dataset.rglob("*.png")):
        assert (again / path.relative_to(dataset)).read_bytes() == path.read_bytes()
    assert (again / "index.csv").read_text() == (dataset / "index.csv").read_text()
    other = tmp_path / "other"
    build_dataset(other, GeneratorConfig(**{**SMALL.__dict__, "seed": 8}))
    frame = "finger_0000/frames/p08.0kpa.png"
    assert (other / frame).read_bytes() != (dataset / frame).read_bytes()


def test_area_law_reference_figures() -> None:
    finger = finger_params(SMALL, 0)
    values = {**finger.values, "onset_kpa": 3.0, "area_exponent": 0.3, "area20_mm2": 190.0}
    typical = type(finger)(**{**finger.__dict__, "values": values})
    areas = [area_law_mm2(typical, p) for p in (3.0, 5.0, 10.0, 20.0)]
    assert areas[0] == 0.0
    assert areas[1:] == pytest.approx([100.0, 145.0, 190.0], rel=0.05)


def test_rings_and_contact_appearance() -> None:
    config = GeneratorConfig(fingers=1, pressures_kpa=(0.0, 20.0), seed=3, hard_fraction=0.0)
    finger = finger_params(config, 0)
    flat, pressed = session_frames(config, 0, finger, config.pressures_kpa)
    gray = cv2.cvtColor(flat.rgb, cv2.COLOR_RGB2GRAY).astype(float)
    yy, xx = np.mgrid[0:300, 0:400]
    r_mm = np.hypot(xx + 0.5 - 200, yy + 0.5 - 150) * finger.mm_per_px(400)
    ring = np.abs(r_mm - finger.values["window_radius_mm"]) < 0.3
    # At 0 kPa the window ring is the brightest structure (saturated) and nothing is inside.
    assert np.percentile(gray[ring], 90) >= 250
    assert not flat.mask.any() and flat.area_mm2 == 0.0
    inside = r_mm < 0.7 * finger.values["window_radius_mm"]
    assert np.percentile(gray[inside], 99.0) < 200
    # At 20 kPa the patch is about the reference size; its mask area matches the true area.
    mm2_px = finger.mm_per_px(400) ** 2
    assert 100.0 < pressed.area_mm2 < 260.0
    assert pressed.mask.sum() * mm2_px == pytest.approx(pressed.area_mm2, rel=0.02)


def test_independent_of_the_renderer() -> None:
    """The generator imports none of the renderer's modules (only numpy, OpenCV, infer, itself,
    and the dataset layout shared by both generators)."""
    for path in PACKAGE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            for name in names:
                if name.startswith("contactcal.synth"):
                    shared = ("contactcal.synth.procedural", "contactcal.synth.layout")
                    assert name.startswith(shared), f"{path}: {name}"
                elif name.startswith("contactcal"):
                    assert name.startswith("contactcal.infer."), f"{path}: {name}"


def test_refuses_existing_out_and_cleans_killed_runs(tmp_path: Path) -> None:
    out = tmp_path / "set"
    out.mkdir()
    with pytest.raises(ValueError, match="already exists"):
        build_dataset(out, SMALL)
    assert list(out.iterdir()) == []
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        check=True,
        capture_output=True,
        text=True,
    )
    stale = tmp_path / f".new.{int(dead.stdout)}.abc123.tmp"
    stale.mkdir()
    (stale / "half.png").write_bytes(b"\x89PNG")
    config = GeneratorConfig(fingers=1, pressures_kpa=(0.0, 6.0), seed=1, width=32, height=24)
    stats = build_dataset(tmp_path / "new", config)
    assert not stale.exists() and stats["frames"] == 2 and stats["frames_per_s"] > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new", "set"]


def test_bad_arguments() -> None:
    assert parse_pressures("0:4:2") == (0.0, 2.0, 4.0)
    assert parse_pressures("4,0") == (4.0, 0.0)  # as given; the generator sorts them
    for bad in ("0:20", "a,b", "-1,2", "1.01,1.02", "nan", "0:300:50"):
        with pytest.raises(ValueError, match="--pressures"):
            parse_pressures(bad)
    with pytest.raises(ValueError, match="--fingers"):
        GeneratorConfig(fingers=0, pressures_kpa=(0.0,), seed=0)
    with pytest.raises(ValueError, match="--size: frames must be 4:3"):
        GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=0, width=64, height=12)
    for w, h in ((2600, 1950), (40000, 30000)):  # once a MemoryError after minutes
        with pytest.raises(ValueError, match=r"--size: .* at most 2592x1944 px .* got"):
            GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=0, width=w, height=h)
    GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=0, width=2592, height=1944)
    # 16x12 frames were generated, then refused by every method ("not a rig frame")
    with pytest.raises(ValueError, match=r"--size: .* at least 21x16 .* got 16x12"):
        GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=0, width=16, height=12)
    GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=0, width=21, height=16)
    with pytest.raises(ValueError, match="--seed must be >= 0"):
        GeneratorConfig(fingers=1, pressures_kpa=(0.0,), seed=-1)


def test_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "set"
    args = ["procedural", "--fingers", "1", "--pressures", "0,6", "--size", "64x48"]
    assert main([*args, "--out", str(out)]) == 0
    assert "frames/s" in capsys.readouterr().out
    assert len(read_index(out)) == 2
    assert main([*args, "--out", str(out)]) == 2  # exists: refused, nothing replaced
    assert "already exists" in capsys.readouterr().err
    assert main([*args[:-2], "--size", "64y48", "--out", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()
    afile = tmp_path / "afile"
    afile.write_text("kept")
    capsys.readouterr()
    assert main([*args, "--out", str(afile / "x")]) == 2  # once a raw "[Errno 17] File exists"
    (err,) = capsys.readouterr().err.strip().splitlines()
    said = f"--out {afile / 'x'}: {afile}: is not a folder; cannot write outputs into it"
    assert err == f"contactcal: error: {said}", err
    assert afile.read_text() == "kept"


def test_never_trained_or_tuned_on(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """train, quantize and the restating tools refuse a procedural set (bench scores it)."""
    model, out = str(DEFAULT_MODEL), tmp_path / "out.onnx"
    runs = {
        "train": lambda d: main(["train", "--data", d, "--out", str(tmp_path / "run")]),
        "quantize": lambda d: main(["quantize", model, "--data", d, "--out", str(out)]),
        "interval": lambda d: interval.main([model, "--data", d, "--out", str(out)]),
        "change_gate": lambda d: change_gate.main([model, "--data", d, "--out", str(out)]),
    }
    for name, run in runs.items():
        assert run(str(dataset)) == 2, name
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert f"--data {dataset}: a cross-check set written by `contactcal procedural`" in err
        assert "expected a dataset written by `contactcal synth`" in err, name
    assert not out.exists() and not (tmp_path / "run").exists()


def test_bench_crosscheck(dataset: Path, tmp_path: Path) -> None:
    other = tmp_path / "other"
    build_dataset(other, GeneratorConfig(**{**SMALL.__dict__, "fingers": 2, "seed": 9}))
    single = run_bench(dataset, tmp_path / "single", config=TINY_BENCH)
    both = run_bench(dataset, tmp_path / "both", config=TINY_BENCH, crosscheck=[other])
    assert "crosscheck" not in single and "side_by_side" not in single
    for key in ("data", "sessions", "frames", "records", "onset", "bins", "hard", "coverage"):
        assert both[key] == single[key]  # the main dataset's keys are unchanged
    (cross,) = both["crosscheck"]
    assert cross["label"] == "other" and cross["sessions"] == 2 and cross["frames"] == 10
    assert len(cross["records"]) == 4 * 10  # classical, unet, its soft area and session rule
    row = next(r for r in both["side_by_side"] if r["method"] == "unet" and r["bin_kpa"] == "≥5")
    own = [r for r in cross["records"] if r["method"] == "unet" and r["pressure_kpa"] >= 5]
    errs = sorted(abs(r["area_px"] - r["true_area_px"]) / r["true_area_px"] for r in own)
    assert row["median_abs_rel_error@other"] == pytest.approx(float(np.median(errs)))
    assert set(row) >= {"median_abs_rel_error@set", "no_contact_accuracy@other"}
    report = (tmp_path / "both" / "report.md").read_text(encoding="utf-8")
    assert "## Datasets side by side" in report and "## Cross-check `other`" in report
    for key, header, pct in SIDE_KEYS:  # one table per quantity, one column per dataset
        table = report.split(f"### {header}\n\n", 1)[1].split("\n\n", 1)[0]
        assert table.startswith("| method | kPa | set | other |\n")
        values = [row[f"{key}@{name}"] for name in ("set", "other")]
        cells = ["–" if v is None else f"{100 * v:.1f} %" for v in values]  # all shown as %
        assert pct
        assert f"| unet | ≥5 | {cells[0]} | {cells[1]} |" in table.splitlines()
    saved = json.loads((tmp_path / "both" / "results.json").read_text())
    assert saved["side_by_side"] == json.loads(json.dumps(both["side_by_side"]))
    with pytest.raises(ValueError, match="index.csv"):
        run_bench(dataset, tmp_path / "bad", config=TINY_BENCH, crosscheck=[tmp_path])
    assert not (tmp_path / "bad").exists()

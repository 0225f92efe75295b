"""``contactcal synth``: tiny renders end to end (determinism, truth, resume, shards, errors)."""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("mitsuba")

from contactcal.infer.cli import main
from contactcal.synth.dataset import DatasetConfig, build_dataset, parse_shard, shard_fingers
from contactcal.synth.dataset_finger import render_finger, stop_if_orphaned
from contactcal.synth.dataset_folder import check_config_matches
from contactcal.synth.layout import parse_pressures, parse_size
from contactcal.synth.session import RenderConfig
from contactcal.synth.variant import VARIANTS, choose_variant

pytestmark = pytest.mark.slow

TINY = RenderConfig(
    width=48, height=36, spp=1, n_rings=24, n_sectors=48, weight_size=128, normal_map_size=128
)
CONFIG = DatasetConfig(fingers=2, pressures_kpa=(0.0, 6.0, 14.0), seed=5, render=TINY)


def _files(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and not p.name.startswith("run_shard")
    }


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("ds")
    build_dataset(root, CONFIG, workers=2, progress=False)
    return root


def _rows(root: Path) -> list[dict[str, str]]:
    with open(root / "index.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_layout_and_truth(dataset: Path) -> None:
    rows = _rows(dataset)
    assert len(rows) == 6
    for finger in ("finger_0000", "finger_0001"):
        folder = dataset / finger
        assert (folder / "manifest.csv").read_text().startswith("file,pressure_kpa\n")
        assert (folder / "rig.json").is_file()
        frame = cv2.imread(str(folder / "frames" / "p06.0kpa.png"), cv2.IMREAD_UNCHANGED)
        assert frame.shape == (36, 48, 3) and frame.dtype == np.uint8
    for r in rows:
        mask = cv2.imread(str(dataset / r["mask"]), cv2.IMREAD_UNCHANGED)
        assert mask.shape == (36, 48) and set(np.unique(mask)) <= {0, 255}
        assert int(r["area_px"]) == int((mask > 0).sum())
        if float(r["pressure_kpa"]) == 0.0:
            assert r["contact"] == "0" and int(r["area_px"]) == 0  # empty mask at 0 kPa
    for finger in ("0", "1"):
        areas = [int(r["area_px"]) for r in rows if r["finger"] == finger]
        assert areas[0] == 0 < areas[1] < areas[2], f"area must grow with pressure: {areas}"


def test_same_seed_is_byte_identical(dataset: Path, tmp_path: Path) -> None:
    build_dataset(tmp_path, CONFIG, workers=1, progress=False)
    assert _files(tmp_path) == _files(dataset)


def test_resume_after_interruption(dataset: Path, tmp_path: Path) -> None:
    build_dataset(tmp_path, CONFIG, workers=1, progress=False)
    killed = tmp_path / "finger_0001" / "frames"
    (killed / "p14.0kpa.json").unlink()  # frame written, truth not yet: as if killed
    (killed / "p06.0kpa.json").unlink()
    (killed / "p06.0kpa.png").unlink()
    stats = build_dataset(tmp_path, CONFIG, workers=1, progress=False)
    assert stats["frames_rendered"] == 2
    assert _files(tmp_path) == _files(dataset)
    assert not list(tmp_path.rglob("*.tmp*")), "temporary files left behind"


def test_shards_cover_exactly_once(tmp_path: Path) -> None:
    parts = [set(shard_fingers(10, (i, 3))) for i in range(3)]
    assert set().union(*parts) == set(range(10)) and sum(map(len, parts)) == 10
    config = dataclasses.replace(CONFIG, pressures_kpa=(0.0, 8.0))
    for i in range(2):
        build_dataset(tmp_path, config, shard=(i, 2), progress=False)
    assert sorted({r["finger"] for r in _rows(tmp_path)}) == ["0", "1"]


def test_calibrate_reads_a_session_as_is(dataset: Path, tmp_path: Path) -> None:
    manifest = dataset / "finger_0000" / "manifest.csv"
    code = main(
        ["calibrate", str(manifest), "--method", "classical", "--out", str(tmp_path / "cal")]
    )
    assert code in (0, 1)  # 48 px frames may show no contact to the classical routine


def test_bad_arguments(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ValueError, match="start:stop:step"):
        parse_pressures("0:20")
    with pytest.raises(ValueError, match="WxH"):
        parse_size("big")
    with pytest.raises(ValueError, match="i/n"):
        parse_shard("3/2")
    with pytest.raises(ValueError, match="4:3"):
        RenderConfig(width=64, height=64)
    with pytest.raises(ValueError, match="fingers"):
        DatasetConfig(fingers=0, pressures_kpa=(0.0,), seed=0)
    assert main(["synth", "--fingers", "1", "--out", str(tmp_path), "--shard", "2/2"]) == 2
    assert "--shard" in capsys.readouterr().err
    empty = tmp_path / "empty"  # a shard without a finger: refused, not an empty dataset
    assert main(["synth", "--fingers", "1", "--out", str(empty), "--shard", "1/2"]) == 2
    err = capsys.readouterr().err
    assert "--shard 1/2: of 1 finger(s) this shard holds none" in err and "fewer shards" in err
    assert len(err.strip().splitlines()) == 1 and not empty.exists()
    out = tmp_path / "neg"  # refused before config.json is written: the folder stays usable
    assert main(["synth", "--fingers", "1", "--seed", "-1", "--out", str(out)]) == 2
    assert "--seed must be >= 0, got -1" in capsys.readouterr().err and not out.exists()
    build_dataset(tmp_path / "a", dataclasses.replace(CONFIG, fingers=1), progress=False)
    with pytest.raises(ValueError, match=r"different config \(seed: 5 → 9\); use a new"):
        build_dataset(
            tmp_path / "a", dataclasses.replace(CONFIG, fingers=1, seed=9), progress=False
        )
    with pytest.raises(ValueError, match="smooth-fraction"):
        dataclasses.replace(CONFIG, smooth_fraction=1.5)
    with pytest.raises(ValueError, match="speck-fraction"):
        dataclasses.replace(CONFIG, speck_fraction=-0.1)
    with pytest.raises(ValueError, match="departure-fraction"):
        dataclasses.replace(CONFIG, departure_fraction=1.1)
    specky = dataclasses.replace(CONFIG, fingers=1, speck_fraction=1.0)
    with pytest.raises(ValueError, match=r"different config \(speck_fraction: 0.0 → 1.0\)"):
        build_dataset(tmp_path / "a", specky, progress=False)
    speck_arg = ["synth", "--fingers", "1", "--speck-fraction", "2", "--out", str(tmp_path / "b")]
    assert main(speck_arg) == 2  # the flag reaches DatasetConfig's check; nothing rendered
    assert "--speck-fraction must be in [0, 1], got 2.0" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()
    smooth = dataclasses.replace(CONFIG, fingers=1, smooth_fraction=0.5)
    with pytest.raises(ValueError, match="different config"):
        build_dataset(tmp_path / "a", smooth, progress=False)
    cfg = tmp_path / "a" / "config.json"  # a folder rendered before the option existed
    old = json.loads(cfg.read_text())
    del old["smooth_fraction"], old["speck_fraction"], old["departure_fraction"]
    cfg.write_text(json.dumps(old))
    build_dataset(tmp_path / "a", dataclasses.replace(CONFIG, fingers=1), progress=False)
    del old["synth_revision"]  # a folder of the first v2 revision: its frames would differ
    cfg.write_text(json.dumps(old))
    with pytest.raises(ValueError, match="synth revision 1"):
        build_dataset(tmp_path / "a", dataclasses.replace(CONFIG, fingers=1), progress=False)


def test_the_variant_rendered_with_is_recorded_and_held(dataset: Path, tmp_path: Path) -> None:
    """config.json names the variant used, not 'auto': a resume that would render with another
    variant (other bytes) is refused; so are a config.json of another tool and a file as --out."""
    used = json.loads((dataset / "config.json").read_text())["render"]["variant"]
    assert used in VARIANTS
    one = dataclasses.replace(CONFIG, fingers=1)
    build_dataset(tmp_path / "a", one, progress=False)
    explicit = dataclasses.replace(one, render=dataclasses.replace(TINY, variant=used))
    build_dataset(tmp_path / "a", explicit, progress=False)  # the same variant, named: resumes
    cfg = tmp_path / "a" / "config.json"
    old = json.loads(cfg.read_text())
    other = next(v for v in VARIANTS if v != used)  # as if rendered on another machine
    cfg.write_text(json.dumps({**old, "render": {**old["render"], "variant": other}}))
    with pytest.raises(ValueError, match=f"rendered with the Mitsuba variant {other}, and this"):
        build_dataset(tmp_path / "a", one, progress=False)
    cfg.write_text(json.dumps({**old, "render": {**old["render"], "variant": "auto"}}))
    with pytest.raises(ValueError, match=r"variant was recorded \('auto'\)"):
        build_dataset(tmp_path / "a", one, progress=False)
    run = tmp_path / "run"  # a training run's folder given as --out
    run.mkdir()
    (run / "config.json").write_text(json.dumps({"train": {}, "data_dirs": []}))
    with pytest.raises(ValueError, match="is not the config of a `contactcal synth` dataset"):
        build_dataset(run, one, progress=False)
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match="afile: is a file; expected a dataset folder"):
        build_dataset(tmp_path / "afile", one, progress=False)


def test_pressures_that_share_a_frame_name_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "ds"
    argv = ["synth", "--fingers", "1", "--pressures", "0,0.04,5", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "p00.0kpa" in err and "0.04" in err and len(err.strip().splitlines()) == 1
    assert not out.exists(), "nothing may be rendered or written"
    with pytest.raises(ValueError, match="given twice"):
        DatasetConfig(fingers=1, pressures_kpa=(0.0, 0.0), seed=0)
    with pytest.raises(ValueError, match="finite"):
        DatasetConfig(fingers=1, pressures_kpa=(0.0, float("nan")), seed=0)
    DatasetConfig(fingers=1, pressures_kpa=(0.0, 0.06, 5.0), seed=0)  # p00.0 / p00.1: distinct


def test_worker_stops_when_its_run_is_gone(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    stop_if_orphaned(None)
    stop_if_orphaned(os.getppid())
    with pytest.raises(SystemExit):
        stop_if_orphaned(os.getppid() + 1)
    rendered = []

    def fake_render(*args: object, **kwargs: object) -> object:
        rendered.append(1)
        yield object()  # a rendered frame, never to be written

    monkeypatch.setattr("contactcal.synth.dataset_finger.render_session", fake_render)
    with pytest.raises(SystemExit):
        render_finger(str(tmp_path), CONFIG, 0, parent_pid=os.getppid() + 1)
    assert rendered and not list(tmp_path.rglob("*.png")) and not list(tmp_path.rglob("*.json"))


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def test_resume_removes_stale_temporaries(tmp_path: Path) -> None:
    config = dataclasses.replace(CONFIG, fingers=1, pressures_kpa=(0.0, 6.0))
    frames = tmp_path / "finger_0000" / "frames"
    frames.mkdir(parents=True)
    variant = choose_variant(config.render.variant)  # config.json as the killed run wrote it
    check_config_matches(
        tmp_path,
        dataclasses.replace(config, render=dataclasses.replace(config.render, variant=variant)),
    )
    for p in config.pressures_kpa:  # every frame done: the resumed run renders nothing
        truth = {"finger": 0, "pressure_kpa": p, "contact": int(p > 0), "mm_per_px": 0.1}
        (frames / f"p{p:04.1f}kpa.json").write_text(json.dumps(truth))
    pid = _dead_pid()
    stale = [
        frames / f".p06.0kpa.png.{pid}.abc123.tmp",
        tmp_path / "finger_0000" / "masks" / f".p06.0kpa.png.{pid}.def456.tmp",
        tmp_path / f".index.csv.{pid}.ghi789.tmp",
    ]
    for path in stale:
        path.mkdir(parents=True)
        (path / "half_written").write_bytes(b"x")
    assert build_dataset(tmp_path, config, workers=1, progress=False)["frames_rendered"] == 0
    assert not [p for p in stale if p.exists()], "stale temporaries of a killed run left"

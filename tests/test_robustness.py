"""``contactcal bench --robustness``: the perturbations, the sampling, the report and the CLI."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from procedural import draw_frame, write_dataset

from contactcal.infer.bench import command as bench_command
from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.bench.perturb import SPECK_DISC, offset, resolution, speck
from contactcal.infer.bench.plots import plot_robustness
from contactcal.infer.bench.robustness import (
    Sample,
    load_samples,
    measure_suite,
    perturbed,
    sample_rows,
)
from contactcal.infer.bench.robustness_summary import ratio_interval
from contactcal.infer.bench.run import run_bench
from contactcal.infer.bench.scoring import ScoredFrame
from contactcal.infer.bench.suite import PERTURBATIONS, Perturbation
from contactcal.infer.cli import main
from contactcal.infer.methods.base import AreaResult
from contactcal.infer.methods.unet.ring import RingFit, locate_ring

TINY = BenchConfig(
    repeats=1, timing_frames=1, full_size=(128, 96), threads=(1,), robustness_frames=4
)
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def frame() -> np.ndarray:
    """A drawn frame at the held-out sets' 400×300 (a blur level is sub-pixel on tiny frames)."""
    return draw_frame(np.random.default_rng(3), 400, 300, (40.0, 30.0)).image


def _apply(p: Perturbation, gray: np.ndarray, level: float, seed: int = 0) -> np.ndarray:
    kw = {"ring": locate_ring(gray)} if p.needs_ring else {}
    return p.apply(gray, level, np.random.default_rng(seed), **kw)


@pytest.mark.parametrize("p", PERTURBATIONS, ids=lambda p: p.name)
def test_perturbation_shape_dtype_determinism(p: Perturbation, frame: np.ndarray) -> None:
    before = frame.copy()
    for level in p.levels:
        out = _apply(p, frame, level)
        assert out.dtype == np.uint8 and out.ndim == 2
        if p.name != "resolution":
            assert out.shape == frame.shape
        np.testing.assert_array_equal(out, _apply(p, frame, level))  # same seed, same image
    np.testing.assert_array_equal(frame, before)  # the input is never modified
    np.testing.assert_array_equal(_apply(p, frame, p.baseline), frame)  # baseline = identity
    assert p.label(p.baseline)  # every level has a label


@pytest.mark.parametrize("p", PERTURBATIONS, ids=lambda p: p.name)
def test_perturbation_changes_the_frame(p: Perturbation, frame: np.ndarray) -> None:
    """Every level but the baseline does something (except "no reference": the reference)."""
    for level in p.levels:
        if level != p.baseline and p.name not in ("no reference", "resolution"):
            assert not np.array_equal(_apply(p, frame, level), frame), (p.name, level)


def test_resolution_sizes(frame: np.ndarray) -> None:
    rng = np.random.default_rng(0)
    assert resolution(frame, 2592, rng).shape == (1944, 2592)
    assert resolution(frame, 64, rng).shape == (48, 64)
    with pytest.raises(ValueError, match="resolution level"):
        resolution(frame, 4, rng)


def test_offset_shifts_by_whole_pixels() -> None:
    mask = np.zeros((40, 60), np.uint8)
    mask[10:20, 20:30] = 255
    ring = RingFit(30.0, 20.0, 50.0)
    out = offset(mask, 0.2, np.random.default_rng(1), ring=ring)  # 10 px in some direction
    assert np.count_nonzero(out) == 100  # the patch stays inside: the area is kept
    ys, xs = np.nonzero(out)
    assert np.hypot(ys.min() - 10, xs.min() - 20) == pytest.approx(10, abs=0.75)
    edge = offset(mask, 1.0, np.random.default_rng(1), ring=ring)  # 50 px: pushed out
    assert edge.shape == mask.shape and np.count_nonzero(edge) < 100


def test_speck_bright_near_the_centre_and_in_the_reference_too(
    frame: np.ndarray, tmp_path: Path
) -> None:
    """The speck only brightens, inside the central disc; stronger levels brighten more at the
    same place; the reference gets the same speck; levels outside [0, 1] are errors."""
    ring = locate_ring(frame)
    peaks = []
    for level in (0.1, 0.2, 0.4):
        out = speck(frame, level, np.random.default_rng(5), ring=ring)
        diff = out.astype(int) - frame.astype(int)
        assert diff.min() >= 0 and diff.max() > 0
        ys, xs = np.nonzero(diff)
        centre = np.hypot(ys.mean() - ring.cy, xs.mean() - ring.cx)
        assert centre <= SPECK_DISC * ring.radius + 1.0
        peaks.append((diff.max(), (ys.mean(), xs.mean())))
    assert peaks[0][0] < peaks[1][0] < peaks[2][0]
    assert peaks[0][1] == pytest.approx(peaks[2][1], abs=0.5)
    # On a black frame the peak is the level itself (255 · level^(1/2.2)), up to the blob's
    # sampling: its centre falls between pixels.
    black = np.zeros((300, 400), np.uint8)
    top = int(speck(black, 0.4, np.random.default_rng(5), ring=ring).max())
    assert 0.85 * 255 * 0.4 ** (1 / 2.2) <= top <= round(255 * 0.4 ** (1 / 2.2))
    with pytest.raises(ValueError, match="window speck level"):
        speck(frame, 1.5, np.random.default_rng(0), ring=ring)
    data = write_dataset(tmp_path / "d", fingers=1)
    row, ref = sample_rows(sessions_of(read_index(data)), 5)[2]
    s = load_samples([(row, ref)])[0]
    s = Sample(s.row, s.reference.copy(), s.reference, s.mask, s.ring)  # frame == reference
    by_name = {p.name: p for p in PERTURBATIONS}
    f, r, true = perturbed(by_name["window speck"], 0.4, s, (0, 0, 0, 0))
    np.testing.assert_array_equal(f, r)
    assert not np.array_equal(f, s.frame) and true == row.area_px


class _Recorder:
    """A method stub that records every frame it is given (and finds no contact)."""

    name = "recorder"

    def __init__(self) -> None:
        self.frames: list[np.ndarray] = []

    def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
        pass

    def measure(self, image: np.ndarray) -> AreaResult:
        self.frames.append(image)
        return AreaResult(False, 0.0, "no contact", None)


def test_suite_draws_the_same_speck_at_every_level(tmp_path: Path) -> None:
    """Paired draws: the speck's levels differ in strength, not in place; the dimmed sector (not
    paired) draws its sector anew at each level."""
    data = write_dataset(tmp_path / "d", fingers=1)
    row, ref = sample_rows(sessions_of(read_index(data)), 5)[2]
    recorder = _Recorder()
    measure_suite([load_samples([(row, ref)])[0]], [recorder], seed=4)
    frames = iter(recorder.frames)
    changed: dict[tuple[str, float], np.ndarray] = {}
    for p in PERTURBATIONS:
        for level in p.levels:
            frame = next(frames)
            if p.name in ("window speck", "dimmed sector") and level != p.baseline:
                changed[(p.name, level)] = frame.astype(int) != load_samples([(row, ref)])[0].frame
    specks = [changed[("window speck", lv)] for lv in (0.1, 0.2, 0.4)]
    assert all(m.any() for m in specks)
    for weak, strong in itertools.pairwise(specks):
        assert not (weak & ~strong).any()  # the weaker speck lies inside the stronger one
    sectors = [changed[("dimmed sector", lv)] for lv in (0.3, 0.9)]
    assert (sectors[0] != sectors[1]).any()


def test_noise_reference_independent_others_same(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "d", fingers=1)
    row, ref = sample_rows(sessions_of(read_index(data)), 5)[2]  # the 8 kPa frame
    s = load_samples([(row, ref)])[0]
    s = Sample(s.row, s.reference.copy(), s.reference, s.mask, s.ring)  # frame == reference
    by_name = {p.name: p for p in PERTURBATIONS}
    frame, reference, _ = perturbed(by_name["noise"], 12.0, s, (0, 0, 0, 0))
    assert not np.array_equal(frame, reference)
    frame, reference, _ = perturbed(by_name["dimmed sector"], 0.9, s, (0, 0, 0, 0))
    np.testing.assert_array_equal(frame, reference)
    _, reference, true = perturbed(by_name["no reference"], 1.0, s, (0, 0, 0, 0))
    assert reference is None and true == row.area_px
    frame, _, true = perturbed(by_name["resolution"], 128.0, s, (0, 0, 0, 0))
    assert frame.shape == (96, 128) and true == pytest.approx(4 * row.area_px)


def test_sampling_spread_and_deterministic(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "d", fingers=4)
    sessions = sessions_of(read_index(data))
    # 7 of the 16 frames past the references (8 would step by 2 over 4 sessions: 2 sessions)
    pairs = sample_rows(sessions, 7)
    assert pairs == sample_rows(sessions, 7) and len(pairs) == 7
    assert {r.pressure_kpa for r, _ in pairs} == {2.0, 4.0, 8.0, 14.0}
    assert len({r.session for r, _ in pairs}) == 4
    assert all(ref == sessions[r.session_key][0] for r, ref in pairs)
    every = sample_rows(sessions, 100)  # all 20 frames but the 4 references: a reference would
    assert len(every) == 16 and all(r != ref for r, ref in every)  # be its own ("same") one
    with pytest.raises(ValueError, match=">= 1 frame"):
        sample_rows(sessions, 0)
    only = {k: v[:1] for k, v in sessions.items()}
    with pytest.raises(ValueError, match="index.csv: every session holds its reference frame only"):
        sample_rows(only, 4)


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    root = tmp_path_factory.mktemp("rob")
    data = write_dataset(root / "data")
    return root / "out", run_bench(data, root / "out", config=TINY)


def test_report_figure_and_results(bench: tuple[Path, dict[str, Any]]) -> None:
    out, results = bench
    assert (out / "robustness.png").read_bytes().startswith(PNG_MAGIC)
    assert (out / "robustness_no_contact.png").read_bytes().startswith(PNG_MAGIC)
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "## Robustness to perturbed frames" in report and "](robustness.png)" in report
    assert "](robustness_no_contact.png)" in report
    assert (
        report.count("worst ratio inside the randomised ranges")
        + report.count("no randomised level with a defined error ratio")
        == 2
    )  # one line per method
    assert "| randomised |" in report
    rob = json.loads((out / "results.json").read_text())["robustness"]
    assert rob == json.loads(json.dumps(results["robustness"]))
    assert len(rob["frames"]) == 4 and rob["seed"] == 0
    assert [p["name"] for p in rob["perturbations"]] == [p.name for p in PERTURBATIONS]
    n_levels = sum(len(p.levels) for p in PERTURBATIONS)
    assert len(rob["rows"]) == 2 * n_levels  # both methods at every level
    for r in rob["rows"]:
        assert r["method"] in ("unet", "classical")
        err, ratio = r["median_abs_rel_error_ge5"], r["error_ratio"]
        base = next(
            b
            for b in rob["rows"]
            if b["baseline"]
            and b["perturbation"] == r["perturbation"]
            and b["method"] == r["method"]
        )
        if r["baseline"] and ratio is not None:
            assert ratio == 1.0
        if ratio is not None:
            assert ratio == pytest.approx(err / base["median_abs_rel_error_ge5"])
        interval = r["error_ratio_interval"]
        if r["baseline"] and interval is not None:
            assert interval == [1.0, 1.0]  # the same frames at both "levels"
        assert f"| {r['perturbation']} | {r['label']} |" in report


def test_the_error_change_in_points_beside_each_ratio(bench: tuple[Path, dict[str, Any]]) -> None:
    """A ratio alone read large on a small baseline error; the change in points says how much."""
    out, results = bench
    rows = results["robustness"]["rows"]
    base_of = {(b["perturbation"], b["method"]): b for b in rows if b["baseline"]}
    for r in rows:
        base = base_of[(r["perturbation"], r["method"])]["median_abs_rel_error_ge5"]
        err = r["median_abs_rel_error_ge5"]
        if err is None or base is None:
            assert r["error_change_points"] is None
        else:
            assert r["error_change_points"] == pytest.approx(100 * (err - base))
    assert any(r["error_change_points"] for r in rows)  # the tiny set has defined changes
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "| − base, points |" in report
    assert "applied on top of the\nheld-out renders' own randomised degradation" in report
    r = next(r for r in rows if r["error_change_points"] and not r["baseline"])
    assert f"| {r['error_change_points']:+.2f} |" in report


def test_robustness_figure_of_an_unknown_metric_is_an_error(
    bench: tuple[Path, dict[str, Any]], tmp_path: Path
) -> None:
    with pytest.raises(ValueError, match="metric must be one of"):
        plot_robustness(tmp_path / "x.png", bench[1]["robustness"], "iou")
    assert not (tmp_path / "x.png").exists()


def test_baselines_agree(bench: tuple[Path, dict[str, Any]]) -> None:
    """Every perturbation's baseline measures the same unperturbed frames: equal numbers."""
    _, results = bench
    keys = ("median_abs_rel_error_ge5", "no_contact_accuracy", "contact_frames_ge5")
    for method in ("unet", "classical"):
        base = [r for r in results["robustness"]["rows"] if r["baseline"] and r["method"] == method]
        assert len({tuple(r[k] for k in keys) for r in base}) == 1


def test_off_by_default_and_cli(
    tmp_path: Path, small_bench_cli: None, capsys: pytest.CaptureFixture[str]
) -> None:
    data = write_dataset(tmp_path / "data", fingers=2)
    args = ["bench", "--data", str(data), "--repeats", "1", "--timing-frames", "1"]
    assert main([*args, "--out", str(tmp_path / "plain")]) == 0
    assert "robustness" not in json.loads((tmp_path / "plain" / "results.json").read_text())
    assert not (tmp_path / "plain" / "robustness.png").exists()
    assert not (tmp_path / "plain" / "robustness_no_contact.png").exists()
    out = tmp_path / "rob"
    assert main([*args, "--out", str(out), "--robustness", "--robustness-frames", "2"]) == 0
    rob = json.loads((out / "results.json").read_text())["robustness"]
    assert len(rob["frames"]) == 2
    first = rob["rows"][0]
    line = capsys.readouterr().out
    assert "robustness: 2 frames sampled, " in line
    assert f"{first['no_contact_frames']} without contact score no-contact accuracy" in line
    assert main([*args, "--out", str(out)]) == 0  # the same folder, without the suite
    said = capsys.readouterr().out
    assert f"note: robustness.png, robustness_no_contact.png in {out} are an earlier run's" in said
    assert "## Robustness" not in (out / "report.md").read_text(encoding="utf-8")
    assert main([*args, "--out", str(out), "--robustness-frames", "2"]) == 2
    assert "--robustness-frames needs --robustness" in capsys.readouterr().err
    assert main([*args, "--out", str(out), "--robustness", "--robustness-frames", "0"]) == 2
    with pytest.raises(ValueError, match="robustness_frames"):
        BenchConfig(robustness_frames=-1)


def test_variants_left_out_of_the_suite_are_said(
    tmp_path: Path, small_bench_cli: None, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --variant was silently left out of the robustness suite."""
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    data = write_dataset(tmp_path / "data", fingers=1)
    args = ["bench", "--data", str(data), "--repeats", "1", "--timing-frames", "1"]
    args += ["--robustness", "--robustness-frames", "1"]
    out, other = tmp_path / "v", tmp_path / "other.onnx"
    # the shipped model with a doc_string field appended: loadable, and not the model itself
    # (bench refuses a variant identical to the one it scores without --model)
    other.write_bytes(DEFAULT_MODEL.read_bytes() + b"\x32\x01x")
    assert main([*args, "--out", str(out), "--variant", f"copy={other}"]) == 0
    said = "--robustness measures --model and the classical routine only; variants unet[copy] "
    said += "were not perturbed"
    assert capsys.readouterr().err.splitlines().count(f"note: {said}") == 1
    assert f"{said}." in (out / "report.md").read_text(encoding="utf-8")
    rob = json.loads((out / "results.json").read_text())["robustness"]
    assert rob["not_perturbed"] == ["unet[copy]"]
    assert {r["method"] for r in rob["rows"]} == {"unet", "classical"}
    assert main([*args, "--out", str(tmp_path / "plain")]) == 0
    assert "not perturbed" not in capsys.readouterr().err
    assert "not perturbed" not in (tmp_path / "plain" / "report.md").read_text(encoding="utf-8")


def test_randomised_ranges_mark_the_levels_where_the_target_applies() -> None:
    """Baselines are always in range; the documented ranges include the levels they name and
    exclude the extremes beyond them; offset is not randomised at all."""
    by_name = {p.name: p for p in PERTURBATIONS}
    assert all(p.in_range(p.baseline) for p in PERTURBATIONS)
    assert by_name["exposure"].in_range(-2.0) and by_name["exposure"].in_range(2.0)
    assert not by_name["contrast"].in_range(2.0) and by_name["contrast"].in_range(0.75)
    assert by_name["JPEG"].in_range(50.0) and not by_name["JPEG"].in_range(25.0)
    assert not by_name["offset"].in_range(0.02)
    assert not by_name["no reference"].in_range(1.0)


def _scored(errors: list[float], pressure: float = 10.0) -> list[ScoredFrame]:
    """Frames of 1000 px true area with the given relative errors, named f0, f1, ..."""
    return [
        ScoredFrame("unet", "s", f"f{i}", pressure, 1000.0, 1000.0 * (1 + e), True)
        for i, e in enumerate(errors)
    ]


def test_ratio_interval_reference_values() -> None:
    base = [0.01, -0.02, 0.03, 0.015, -0.025, 0.02]
    rng = np.random.default_rng(0)
    assert ratio_interval(_scored(base), _scored(base), rng) == (1.0, 1.0)
    doubled = ratio_interval(_scored([2 * e for e in base]), _scored(base), rng)
    assert doubled == pytest.approx((2.0, 2.0))  # every frame's error doubles: no spread
    mixed = [0.01, -0.06, 0.03, 0.015, -0.075, 0.02]  # two frames get much worse
    low, high = ratio_interval(_scored(mixed), _scored(base), np.random.default_rng(0))
    assert 0.5 < low < high and high > 2.0
    again = ratio_interval(_scored(mixed), _scored(base), np.random.default_rng(0))
    assert again == (low, high)  # seeded: reproducible


def test_ratio_interval_undefined_and_bad_input() -> None:
    rng = np.random.default_rng(0)
    below = _scored([0.1, 0.2, 0.3], pressure=3.0)  # no frame at >= 5 kPa
    assert ratio_interval(below, below, rng) is None
    assert ratio_interval(_scored([0.1, 0.2]), _scored([0.0, 0.0]), rng) is None  # zero baseline
    with pytest.raises(ValueError, match="frames differ"):
        ratio_interval(_scored([0.1, 0.2]), _scored([0.1, 0.2, 0.3]), rng)


def test_the_cli_line_says_when_no_frame_scores_an_error_row() -> None:
    """One sampled frame without contact at >= 5 kPa: the line says so, in the singular."""
    rob = {"frames": ["a.png"], "rows": [{"contact_frames_ge5": 0, "no_contact_frames": 1}]}
    line = bench_command._robustness_line(rob, Path("r/robustness.png"))
    assert line.startswith("robustness: 1 frame sampled, none with true contact at >= 5 kPa")
    assert "no error rows (sample more frames)" in line
    rob = {"frames": ["a", "b", "c"], "rows": [{"contact_frames_ge5": 2, "no_contact_frames": 1}]}
    line = bench_command._robustness_line(rob, Path("r/robustness.png"))
    assert "3 frames sampled, 2 with true contact at >= 5 kPa score the error rows" in line

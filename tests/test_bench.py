"""``contactcal bench``: outputs, the tables against hand-computed values, bad folders, the CLI."""

from __future__ import annotations

import csv
import hashlib
import json
import math
import shutil
from dataclasses import replace as dataclasses_replace
from pathlib import Path
from typing import Any

import pytest
from procedural import write_dataset

from contactcal.infer.bench import run as bench_run
from contactcal.infer.bench.accuracy import from_record, to_record
from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.crosscheck import labels
from contactcal.infer.bench.onset import onset_errors, onset_table
from contactcal.infer.bench.plots import pareto_points
from contactcal.infer.bench.report import _timed_frames, md_table, report_text
from contactcal.infer.bench.run import run_bench
from contactcal.infer.bench.scoring import (
    PRESSURE_BINS,
    ScoredFrame,
    bin_table,
    covering_bins,
    not_references,
)
from contactcal.infer.bench.tables import accuracy_tables, coverage_table, hard_table
from contactcal.infer.cli import main
from contactcal.infer.image.read import load_image

#: A benchmark small enough for a unit test (timing numbers are not checked).
TINY = BenchConfig(repeats=1, timing_frames=1, full_size=(128, 96), threads=(1,))
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, Any]]:
    """A tiny procedural dataset (4 sessions × 5 frames) benchmarked once for the module."""
    root = tmp_path_factory.mktemp("bench")
    data = write_dataset(root / "data")
    out = root / "out"
    return data, out, run_bench(data, out, config=TINY)


def test_outputs_written(bench: tuple[Path, Path, dict[str, Any]]) -> None:
    _, out, results = bench
    names = {"report.md", "results.json", "error_vs_pressure.png", "pareto.png"}
    assert {p.name for p in out.iterdir()} == names  # no temporary files left behind
    for png in ("error_vs_pressure.png", "pareto.png"):
        assert (out / png).read_bytes().startswith(PNG_MAGIC)
    report = (out / "report.md").read_text(encoding="utf-8")
    for heading in ("## Area error per pressure bin", "## Speed", "## Contact onset", "## Hard"):
        assert heading in report
    assert "](error_vs_pressure.png)" in report and "](pareto.png)" in report
    assert "Bins are `[lo, hi)` kPa" in report
    assert "each median leaves out\none untimed warm-up run of its configuration" in report
    few = [b for b in results["bins"] if 0 < b["contact_frames"] < 5]  # the tiny set's bins
    assert few, "expected bins of 1-4 contact frames in the tiny set"
    for b in few:
        assert f"{b['method']} {b['bin_kpa']} kPa ({b['contact_frames']})" in report
    assert json.loads((out / "results.json").read_text()) == json.loads(json.dumps(results))


def test_results_keys(bench: tuple[Path, Path, dict[str, Any]]) -> None:
    _, out, _ = bench
    res = json.loads((out / "results.json").read_text())
    assert {"data", "model", "sessions", "frames", "config", "records", "onset", "timing"} <= set(
        res
    )
    assert {"bins", "hard"} <= set(res)
    assert res["model"] == "shipped" and res["sessions"] == 4 and res["frames"] == 20
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    shipped = hashlib.sha256(DEFAULT_MODEL.read_bytes()).hexdigest()
    assert res["models"] == {"unet": {"path": str(DEFAULT_MODEL), "sha256": shipped}}
    assert f"(unet sha256 {shipped[:12]}…)" in (out / "report.md").read_text(encoding="utf-8")
    assert res["config"] == {"repeats": 1, "timing_frames": 1, "full_size": [128, 96]}
    methods = {r["method"] for r in res["records"]}
    assert methods == {"classical", "unet", "unet (soft area)", "unet (session rule)"}
    assert len(res["records"]) == 4 * 20
    for r in res["records"]:
        assert r["true_contact"] == (r["true_area_px"] > 0)
        assert r["contact"] or r["area_px"] == 0.0
        # an IoU for every frame with true contact, but for the soft area (no outline of its own)
        has_iou = r["true_contact"] and not r["method"].endswith("(soft area)")
        assert (r["iou"] is not None) == has_iou, r
        assert r["iou"] is None or (0.0 <= r["iou"] <= 1.0 and (r["iou"] > 0) <= r["contact"])
    configs = [t["config"] for t in res["timing"]]
    assert configs[:3] == ["classical", "classical@0.25", "unet"]
    assert configs[-1] == "unet network only"
    for t in res["timing"]:
        assert t["ms_compute"] > 0 and "ms_end_to_end_jpg" in t and "ms_end_to_end_png" in t
    # 4 methods × 4 sessions of onsets; hard sessions are the odd fingers (2 of 4).
    assert len(res["onset"]) == 16
    assert {(h["sessions"], h["n"]) for h in res["hard"]} == {("normal", 2), ("hard", 2)}


def test_bins_recomputed_from_records(bench: tuple[Path, Path, dict[str, Any]]) -> None:
    _, out, _ = bench
    res = json.loads((out / "results.json").read_text())
    frames = [from_record(r) for r in res["records"]]
    assert [to_record(f) for f in frames] == res["records"]
    assert json.loads(json.dumps(bin_table(not_references(frames), PRESSURE_BINS))) == res["bins"]
    assert json.loads(json.dumps(onset_errors(frames))) == res["onset"]
    # One bin by hand: median |relative error| of the U-Net's contact frames at 5-10 kPa.
    rel = sorted(
        abs(r["area_px"] - r["true_area_px"]) / r["true_area_px"]
        for r in res["records"]
        if r["method"] == "unet" and 5 <= r["pressure_kpa"] < 10 and r["true_area_px"] > 0
    )
    assert len(rel) == 4  # the 8 kPa frame of each finger
    row = next(b for b in res["bins"] if b["method"] == "unet" and b["bin_kpa"] == "5-10")
    assert row["contact_frames"] == 4
    assert row["median_abs_rel_error"] == pytest.approx((rel[1] + rel[2]) / 2)
    # Below 3 kPa no frame has contact: only the no-contact accuracy is defined, over the 2 kPa
    # frames (the 0 kPa ones are the sessions' references, not scored).
    low = next(b for b in res["bins"] if b["method"] == "classical" and b["bin_kpa"] == "0-3")
    none = [
        r
        for r in res["records"]
        if r["method"] == "classical" and r["pressure_kpa"] < 3 and not r["reference"]
    ]
    assert low["median_abs_rel_error"] is None and low["no_contact_frames"] == len(none) == 4
    expected = sum(not r["contact"] for r in none) / 4
    assert low["no_contact_accuracy"] == pytest.approx(expected)


def test_interval_coverage(bench: tuple[Path, Path, dict[str, Any]]) -> None:
    _, out, _ = bench
    res = json.loads((out / "results.json").read_text())
    for r in res["records"]:
        iv = r["area_interval_px"]
        if r["method"].startswith("unet") and "soft" not in r["method"]:  # the U-Net states
            # one on every frame; it holds the estimate (also a frame the session rule revised)
            assert iv[0] <= r["area_px"] <= iv[1]
            assert r["covered"] == (iv[0] <= r["true_area_px"] <= iv[1])
        else:  # the classical routine and the soft area state none
            assert iv is None and r["covered"] is None
    rows = [c for c in res["coverage"] if c["method"] == "unet"]
    assert [c["bin_kpa"] for c in rows] == ["0-3", "3-5", "5-10", "10-20", "all"]
    unet = [r for r in res["records"] if r["method"] == "unet" and not r["reference"]]
    assert rows[-1]["frames"] == 16  # 20 frames less the 4 sessions' references
    assert rows[-1]["coverage"] == pytest.approx(sum(r["covered"] for r in unet) / 16)
    assert {"method": "classical", "bin_kpa": "no interval"} in res["coverage"]
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "## Coverage of the stated area interval" in report
    assert "| classical | no interval |" in report and "| unet | all | 16 |" in report


def test_reference_frames_are_marked_and_not_scored(
    bench: tuple[Path, Path, dict[str, Any]],
) -> None:
    """Each session's reference frame, measured against itself, once landed in the 0-3 kPa bin
    and the no-contact accuracy unsaid; its record stays, marked."""
    _, out, res = bench
    pairs = {(r["method"], r["session"]) for r in res["records"]}
    refs = [r for r in res["records"] if r["reference"]]
    assert len(refs) == len(pairs) == 16 and {(r["method"], r["session"]) for r in refs} == pairs
    for r in refs:  # the record h15_rule.py drops: its (method, session)'s lowest pressure
        same = [
            x for x in res["records"] if (x["method"], x["session"]) == (r["method"], r["session"])
        ]
        assert r["pressure_kpa"] == min(x["pressure_kpa"] for x in same) == 0.0
    assert sum(b["frames"] for b in res["bins"]) == len(res["records"]) - 16
    report = (out / "report.md").read_text(encoding="utf-8")
    assert report.count("reference frame is not scored") == 1


def test_coverage_table_by_hand() -> None:
    frames = [
        _frame(1.0, 0.0, 0.0, area_interval_px=(0.0, 0.0)),  # covered (no contact)
        _frame(6.0, 100.0, 110.0, area_interval_px=(95.0, 120.0)),  # covered, width 25 %
        _frame(7.0, 200.0, 150.0, area_interval_px=(140.0, 160.0)),  # missed, width 10 %
        _frame(12.0, 400.0, 404.0, area_interval_px=(380.0, 420.0)),  # covered, width 10 %
        _frame(12.0, 400.0, 404.0, method="c"),  # states none
    ]
    rows = {(r["method"], r["bin_kpa"]): r for r in coverage_table(frames, PRESSURE_BINS)}
    assert rows[("c", "no interval")] == {"method": "c", "bin_kpa": "no interval"}
    assert rows[("m", "0-3")]["coverage"] == 1.0 and rows[("m", "0-3")]["contact_frames"] == 0
    assert rows[("m", "3-5")]["frames"] == 0 and rows[("m", "3-5")]["coverage"] is None
    assert rows[("m", "5-10")]["coverage"] == pytest.approx(0.5)
    assert rows[("m", "5-10")]["median_rel_width"] == pytest.approx(0.175)
    every = rows[("m", "all")]
    assert every["frames"] == 4 and every["coverage"] == pytest.approx(0.75)
    assert every["contact_coverage"] == pytest.approx(2 / 3)
    assert every["median_rel_width"] == pytest.approx(0.1)


def _frame(p: float, true: float, area: float, session: str = "s0", **kw: Any) -> ScoredFrame:
    return ScoredFrame(
        method=kw.pop("method", "m"),
        session=session,
        frame=f"{session}/{p}.png",
        pressure_kpa=p,
        true_area_px=true,
        area_px=area,
        contact=area > 0,
        mm_per_px=0.1,
        onset_kpa=3.0,
        **kw,
    )


def test_tables_by_hand() -> None:
    frames = [
        _frame(1.0, 0.0, 0.0),  # correct no-contact
        _frame(2.0, 0.0, 30.0),  # false contact
        _frame(6.0, 100.0, 110.0),  # +10 %
        _frame(7.0, 200.0, 150.0),  # -25 %
        _frame(8.0, 50.0, 0.0),  # missed: -100 %
        _frame(12.0, 400.0, 404.0, session="s1", hard=True),  # +1 %, a hard session
    ]
    rows = {r["bin_kpa"]: r for r in bin_table(frames, PRESSURE_BINS)}
    assert list(rows) == ["0-3", "3-5", "5-10", "10-20"]
    assert rows["0-3"]["no_contact_frames"] == 2
    assert rows["0-3"]["no_contact_accuracy"] == pytest.approx(0.5)
    assert rows["0-3"]["median_abs_rel_error"] is None
    assert rows["3-5"]["frames"] == 0 and rows["3-5"]["contact_recall"] is None
    five = rows["5-10"]
    assert five["contact_frames"] == 3
    assert five["median_abs_rel_error"] == pytest.approx(0.25)
    assert five["mean_rel_error"] == pytest.approx((0.1 - 0.25 - 1.0) / 3)
    assert five["contact_recall"] == pytest.approx(2 / 3)
    assert five["median_abs_error_mm2"] == pytest.approx(0.5)  # |10|, |50|, |50| px × 0.01 mm²
    assert rows["10-20"]["median_abs_rel_error"] == pytest.approx(0.01)

    onset = [
        {"method": "m", "session": "s0", "onset_kpa": 5.0, "error_kpa": 2.0, "outcome": "found"},
        {"method": "m", "session": "s1", "onset_kpa": None, "error_kpa": None, "outcome": "missed"},
    ]
    hard = {h["sessions"]: h for h in hard_table(frames, onset)}
    assert hard["normal"]["n"] == 1 and hard["hard"]["n"] == 1
    assert hard["normal"]["median_abs_rel_error_ge5"] == pytest.approx(0.25)
    assert hard["normal"]["median_abs_rel_error_3to5"] is None
    assert hard["normal"]["no_contact_accuracy"] == pytest.approx(0.5)
    assert hard["normal"]["median_abs_onset_error_kpa"] == pytest.approx(2.0)
    assert hard["hard"]["median_abs_rel_error_ge5"] == pytest.approx(0.01)
    assert hard["hard"]["onset_missing"] == 1
    (row,) = onset_table(onset)
    assert row["median_abs_error_kpa_found"] == row["max_abs_error_kpa_found"] == 2.0
    table = md_table([five], [("bin_kpa", "kPa", False), ("median_abs_rel_error", "err", True)])
    assert table.splitlines() == ["| kPa | err |", "|---|---|", "| 5-10 | 25.0 % |"]


def test_a_frame_past_the_last_bin_opens_it() -> None:
    """A dataset past 20 kPa: its frames are in the tables (last bin ">=10"), not dropped."""
    frames = [_frame(4.0, 100.0, 100.0), _frame(25.0, 400.0, 420.0), _frame(30.0, 400.0, 440.0)]
    bins = covering_bins([f.pressure_kpa for f in frames], PRESSURE_BINS)
    assert bins[:-1] == PRESSURE_BINS[:-1] and bins[-1] == (10.0, math.inf)
    assert covering_bins([4.0, 20.0], PRESSURE_BINS) == PRESSURE_BINS
    rows = {r["bin_kpa"]: r for r in accuracy_tables(frames, [], PRESSURE_BINS)["bins"]}
    assert list(rows) == ["0-3", "3-5", "5-10", ">=10"]
    assert rows[">=10"]["contact_frames"] == 2
    assert rows[">=10"]["median_abs_rel_error"] == pytest.approx(0.075)


def test_onset_errors_by_hand() -> None:
    # Contact from 4 kPa on, areas growing linearly from 3 kPa: the onset extrapolates to 3.
    frames = [_frame(p, 10.0 * max(p - 3.0, 0.0), 10.0 * max(p - 3.0, 0.0)) for p in (2, 4, 5, 6)]
    (row,) = onset_errors(frames)
    assert row["onset_kpa"] == pytest.approx(3.0)
    assert row["truth_masks_onset_kpa"] == pytest.approx(3.0)
    assert row["mechanics_onset_kpa"] == 3.0 and row["error_kpa"] == pytest.approx(0.0)


def test_the_onset_table_counts_every_session() -> None:
    """A missed onset (true contact, none found) once dropped its session from the onset table's
    median and max, and a correct "no contact" counted as "no onset found"."""
    onset_at = {4.0: 40.0, 8.0: 80.0}  # true contact from 4 kPa on (onset 3 kPa)
    frames = []
    for session, contact, seen in (
        ("found", True, True),
        ("missed", True, False),
        ("false", False, True),
        ("none", False, False),
    ):
        for p in (0.0, 2.0, 4.0, 8.0):
            true = onset_at.get(p, 0.0) if contact else 0.0
            area = (onset_at.get(p, 0.0) or (30.0 if not contact and p else 0.0)) if seen else 0.0
            frames.append(_frame(p, true, area, session=session))
    onset = onset_errors(frames)
    assert [o["outcome"] for o in onset] == ["false onset", "found", "missed", "no contact"]
    (row,) = onset_table(onset)
    assert {k: row[k] for k in ("sessions", "contact_sessions", "found", "missed")} == {
        "sessions": 4,
        "contact_sessions": 2,
        "found": 1,
        "missed": 1,
    }
    assert row["false_onsets"] == 1
    found = next(o for o in onset if o["outcome"] == "found")
    assert row["max_abs_error_kpa_found"] == pytest.approx(abs(found["error_kpa"]))
    hard = hard_table(frames, onset)
    assert [(h["onset_missing"], h["false_onsets"]) for h in hard] == [(1, 1)]
    text = report_text(
        {
            "config": {"full_size": [8, 6], "repeats": 1, "timing_frames": 1},
            "data": "d",
            "sessions": 4,
            "frames": 16,
            "model": "shipped",
            "reference": "none",
            "timing": [],
            "bins": [],
            "coverage": [],
            "hard": hard,
            "onset_table": [row],
        }
    )
    assert "| m | 4 | 2 | 1 |" in text and "| missed | 1 | 1 |" in text


def test_pareto_points() -> None:
    bins = [
        {"method": "unet", "bin_kpa": "5-10", "median_abs_rel_error": 0.02},
        {"method": "classical", "bin_kpa": "5-10", "median_abs_rel_error": 0.8},
        {"method": "unet", "bin_kpa": "3-5", "median_abs_rel_error": 0.5},
    ]
    timing = [
        {"config": "classical@0.25", "threads": 1, "ms_compute": 1.0, "ms_end_to_end_jpg": 9.0},
        {
            "config": "unet+reduced-decode 1/8",
            "threads": 2,
            "ms_compute": 6.0,
            "ms_end_to_end_jpg": 12.0,
        },
        {"config": "unet network only", "threads": 1, "ms_compute": 6.0, "ms_end_to_end_jpg": None},
    ]
    assert pareto_points(bins, timing) == [
        ("classical@0.25, 1 thread", 1.0, 9.0, pytest.approx(80.0)),
        ("unet+reduced-decode 1/8, 2 threads", 6.0, 12.0, pytest.approx(2.0)),
    ]


def test_bad_dataset_folder(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="index.csv"):
        run_bench(tmp_path, tmp_path / "out", config=TINY)
    data = write_dataset(tmp_path / "data", fingers=1)
    index = data / "index.csv"
    with open(index, newline="") as fh:
        rows = list(csv.DictReader(fh))
    with open(index, "w", newline="") as fh:
        cols = [c for c in rows[0] if c != "mm_per_px"]
        writer = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    with pytest.raises(ValueError, match="mm_per_px") as err:
        run_bench(data, tmp_path / "out", config=TINY)
    assert str(index) in str(err.value)
    assert not (tmp_path / "out").exists()


def test_cli(
    bench: tuple[Path, Path, dict[str, Any]],
    tmp_path: Path,
    small_bench_cli: None,
    capsys: pytest.CaptureFixture[str],
) -> None:
    data, _, _ = bench
    out = tmp_path / "report"
    args = ["bench", "--data", str(data), "--out", str(out), "--repeats", "1"]
    assert main([*args, "--timing-frames", "1"]) == 0
    assert (out / "report.md").is_file() and (out / "results.json").is_file()
    printed = capsys.readouterr().out
    assert "unet" in printed and "report.md" in printed and "replaced" not in printed
    (out / "robustness.png").write_bytes(b"an earlier --robustness run's")
    assert main([*args, "--timing-frames", "1"]) == 0  # again: replaced without a word before
    printed = capsys.readouterr().out
    assert f"note: replaced the report that {out} held (results.json, " in printed
    replaced = printed.split("replaced the report")[1].splitlines()[0]
    assert "robustness" not in replaced  # this run, without --robustness, wrote none
    inside = ["bench", "--data", str(data), "--out", str(data / "report"), "--repeats", "1"]
    assert main(inside) == 2  # the report would mix with the dataset's frames
    assert f"--out {data / 'report'}: inside the dataset folder {data}" in capsys.readouterr().err
    assert not (data / "report").exists()
    assert main(["bench", "--data", str(tmp_path / "none"), "--out", str(out)]) == 2
    assert f"--data {tmp_path / 'none'}: does not exist; expected a dataset folder" in (
        capsys.readouterr().err
    )
    (tmp_path / "empty").mkdir()
    assert main([*args, "--crosscheck", str(tmp_path / "empty")]) == 2
    assert f"--crosscheck {tmp_path / 'empty'}: missing index.csv" in capsys.readouterr().err
    assert main([*args, "--timing-frames", "0"]) == 2


def test_no_reference_mode(bench: tuple[Path, Path, dict[str, Any]], tmp_path: Path) -> None:
    """``use_reference=False``: same frames, measured without the zero-pressure frames."""
    data, _, with_ref = bench
    cfg = BenchConfig(repeats=1, timing_frames=1, full_size=(128, 96), threads=(1,))
    res = run_bench(data, tmp_path / "out", config=dataclasses_replace(cfg, use_reference=False))
    assert with_ref["reference"] == "session zero-pressure frame" and res["reference"] == "none"
    report = (tmp_path / "out" / "report.md").read_text()
    assert "Reference frame: none." in report and "is not scored" not in report
    # which no-reference mode ran (docs/training.md says bench says it): the model's own
    from contactcal.infer.methods.classical import ClassicalMethod
    from contactcal.infer.methods.unet.method import UnetMethod

    modes = {"unet": UnetMethod().NO_REFERENCE, "classical": ClassicalMethod.NO_REFERENCE}
    assert res["no_reference"] == modes and "no_reference" not in with_ref
    assert "blank placeholder" in modes["unet"]  # the shipped model: reference dropout
    assert "Without reference frames, per method:" in report
    assert all(f"- {m}: {note}." in report for m, note in modes.items())
    assert not any(r["reference"] for r in res["records"])  # every frame is a frame like any
    assert sum(b["frames"] for b in res["bins"]) == len(res["records"])
    key = lambda r: (r["method"], r["frame"])  # noqa: E731
    a = {key(r): r["area_px"] for r in with_ref["records"]}
    b = {key(r): r["area_px"] for r in res["records"]}
    assert a.keys() == b.keys()
    assert any(a[k] != b[k] for k in a if k[0] == "unet")  # the U-Net's input did change


def test_variant_is_scored_and_timed_beside_the_model(
    bench: tuple[Path, Path, dict[str, Any]], tmp_path: Path
) -> None:
    """A variant (here the shipped model again) gets its own rows, identical to ``unet``'s."""
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    data, _, _ = bench
    cfg = dataclasses_replace(TINY, variants=(("copy", str(DEFAULT_MODEL)),))
    res = run_bench(data, tmp_path / "out", config=cfg)
    rows = {(r["method"], r["frame"]): r["area_px"] for r in res["records"]}
    unet = {f: a for (m, f), a in rows.items() if m == "unet"}
    copy = {f: a for (m, f), a in rows.items() if m == "unet[copy]"}
    assert unet and copy == unet
    assert res["models"]["unet[copy]"] == res["models"]["unet"]  # the same file, recorded
    assert any(t["config"] == "unet[copy]" for t in res["timing"])
    assert any(b["method"] == "unet[copy]" for b in res["bins"])
    assert any(
        label.startswith("unet[copy]") for label, *_ in pareto_points(res["bins"], res["timing"])
    )


def test_cli_rejects_a_bad_variant(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = write_dataset(tmp_path / "data")
    for bad in ("int8", "=x.onnx", f"int8={tmp_path / 'missing.onnx'}"):
        argv = ["bench", "--data", str(data), "--out", str(tmp_path / "o"), "--variant", bad]
        assert main(argv) == 2
    for label in ("a|b", "int 8"):  # a | split the report's Markdown table rows
        argv = ["bench", "--data", str(data), "--out", str(tmp_path / "o")]
        assert main([*argv, "--variant", f"{label}=x.onnx"]) == 2
        assert f"label {label!r} may hold letters" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_cli_names_the_option_of_an_unusable_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A missing or unloadable --model or --variant model is named with its option, before the
    work; a variant labelled as a method (rows ``unet[unet]``) is refused."""
    data = write_dataset(tmp_path / "data")
    index, missing = data / "index.csv", tmp_path / "missing.onnx"
    argv = ["bench", "--data", str(data), "--out", str(tmp_path / "o")]
    cases = (
        (["--model", str(missing)], f"--model {missing}: no such model file"),
        (["--model", str(data)], f"--model {data}: is a folder; expected the ONNX model file"),
        (["--model", str(index)], f"--model {index}: not a loadable ONNX model ("),
        (["--variant", f"x={missing}"], f"--variant x={missing}: no such model file"),
        (["--variant", f"x={data}"], f"--variant x={data}: is a folder; expected the ONNX model"),
        (["--variant", f"x={index}"], f"--variant x={index}: not a loadable ONNX model ("),
        (["--variant", f"unet={index}"], f"--variant unet={index}: label 'unet' is a method's"),
        (["--variant", f"classical={index}"], f"--variant classical={index}: label 'classical'"),
    )
    for extra, says in cases:
        assert main([*argv, *extra]) == 2
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert err.startswith(f"contactcal: error: {says}"), err
    assert f"unet[classical]); expected a label naming the variant, e.g. int8={index}" in err
    assert not (tmp_path / "o").exists()


def test_cli_rejects_a_variant_that_is_the_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --variant with --model's content (or another variant's) would score it twice."""
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    data, copy = write_dataset(tmp_path / "data"), tmp_path / "copy.onnx"
    shutil.copyfile(DEFAULT_MODEL, copy)
    argv = ["bench", "--data", str(data), "--out", str(tmp_path / "o")]
    cases = (
        ([f"x={copy}"], f"x={copy}: the same model as the shipped model {DEFAULT_MODEL}, which"),
        (["--model", str(copy), f"x={DEFAULT_MODEL}"], f"as --model {copy} (identical"),
    )
    for extra, says in cases:
        model, variant = extra[:-1], extra[-1]
        assert main([*argv, *model, "--variant", variant]) == 2
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert says in err and "expected another model" in err, err
    int8 = tmp_path / "int8.onnx"
    # other content, a loadable model: a doc_string (field 6) appended, the last value wins
    int8.write_bytes(copy.read_bytes() + b"\x32\x01x")
    assert main([*argv, "--variant", f"a={int8}", "--variant", f"b={int8}"]) == 2
    assert f"--variant b={int8}: the same model as --variant a={int8}" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def _rewrite_index(index: Path, edit: Any) -> None:
    """Rewrite ``index`` with ``edit(rows) -> rows`` (rows as lists of cells, header first)."""
    with open(index, newline="") as fh:
        rows = list(csv.reader(fh))
    with open(index, "w", newline="") as fh:
        csv.writer(fh).writerows(edit(rows))


def test_index_rows_that_cannot_be_scored_are_named(tmp_path: Path) -> None:
    from contactcal.infer.bench.dataset import read_index

    data = write_dataset(tmp_path / "data", fingers=1)
    index = data / "index.csv"
    original = index.read_bytes()

    def column(name: str, value: str) -> Any:
        def edit(rows: list[list[str]]) -> list[list[str]]:
            i = rows[0].index(name)
            return [rows[0]] + [[*r[:i], value, *r[i + 1 :]] for r in rows[1:]]

        return edit

    cases = (
        (lambda rows: [*rows, rows[-1][:3]], r"line \d+: no value in column"),  # a short row
        (column("onset_kpa", "nan"), "onset_kpa is nan; expected a finite number"),
        (column("onset_kpa", "inf"), "onset_kpa is inf"),
        (column("pressure_kpa", "-2"), r"line 2: pressure_kpa is -2; expected >= 0 kPa"),
        (column("mm_per_px", "0"), r"line 2: mm_per_px is 0; expected a scale > 0 mm/px"),
        (column("mm_per_px", "-0.1"), "mm_per_px is -0.1"),
        (column("finger", "inf"), "unparsable value"),  # int(inf): OverflowError once escaped
        (lambda rows: [*rows, rows[-1]], "has a frame at .* kPa already"),  # a repeated frame
    )
    for edit, says in cases:
        index.write_bytes(original)
        _rewrite_index(index, edit)
        with pytest.raises(ValueError, match=says) as err:
            read_index(data)
        assert str(index) in str(err.value)
    index.write_bytes(b"\xff\xfe" + original)
    with pytest.raises(ValueError, match="not UTF-8 text") as err:
        read_index(data)
    assert str(index) in str(err.value)


def test_cli_refuses_a_report_folder_it_cannot_write_before_the_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = write_dataset(tmp_path / "data", fingers=1)
    afile = tmp_path / "afile"
    afile.write_text("kept")
    blocked = tmp_path / "blocked"
    (blocked / "pareto.png").mkdir(parents=True)  # once: results.json written, report.md not
    link = tmp_path / "link"
    link.symlink_to(blocked)
    model = str(tmp_path / "m.onnx")
    (tmp_path / "m.onnx").write_bytes(b"x")
    for out, more, says in (
        (afile, [], "is not a folder"),
        (blocked, [], "not a regular file"),
        (link, [], "symbolic link"),
        (Path("-"), [], "writes a folder of files"),
        (afile / "sub", [], "is not a folder"),  # its receiving folder is a file
        (link / "sub", [], "symbolic link to a folder"),  # ... or a link
        (tmp_path / "o", ["--variant", f"a={model}", "--variant", f"a={model}"], "given twice"),
    ):
        argv = ["bench", "--data", str(data), "--out", str(out), "--repeats", "1", *more]
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0], err
    assert afile.read_text() == "kept" and sorted(p.name for p in blocked.iterdir()) == [
        "pareto.png"
    ]
    assert not (tmp_path / "o").exists()


def test_timing_medians_leave_out_a_warm_up_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """The first run of a configuration (onnxruntime's first call) was among the timed ones."""
    from types import SimpleNamespace

    from contactcal.infer.bench import timing

    clock = iter(range(10**6))  # one tick per perf_counter() call
    cost = iter([1000, 1, 1])  # ticks each fn() call takes: the first is the cold one
    monkeypatch.setattr(timing, "time", SimpleNamespace(perf_counter=lambda: float(next(clock))))

    def fn() -> None:
        for _ in range(next(cost)):
            next(clock)

    # Each timed run spans 2 ticks (its own and the clock's second read), 1 tick = 1000 ms.
    assert timing.median_ms(fn, 2) == pytest.approx(2000.0)
    assert next(cost, None) is None  # three calls: one warm-up, two timed


def test_the_report_says_how_many_frames_were_timed() -> None:
    """Fewer frames than asked (a small set) are said as such; the network-only row (one
    prepared input) does not count."""
    timing = [
        {"config": "unet jpeg", "frames": 2},
        {"config": "classical jpeg", "frames": 2},
        {"config": "unet network only", "frames": 1},
    ]
    few = {"timing": timing, "config": {"timing_frames": 6}}
    assert _timed_frames(few) == "2 (of 6 asked: all the set has at 6-16 kPa, or at all pressures)"
    assert _timed_frames({**few, "config": {"timing_frames": 2}}) == "2"


def test_a_mask_that_contradicts_the_index_is_named(tmp_path: Path) -> None:
    """A damaged dataset (a contact frame's mask emptied) once scored a 0/0 IoU: NaN in JSON."""
    import cv2
    import numpy as np

    from contactcal.infer.bench import accuracy
    from contactcal.infer.bench.dataset import read_index

    row = next(r for r in read_index(write_dataset(tmp_path / "d", fingers=1)) if r.contact)
    frame_shape = load_image(row.frame).shape
    assert accuracy._truth(row, frame_shape) is not None  # as written: mask and index agree
    shape = cv2.imread(str(row.mask), cv2.IMREAD_GRAYSCALE).shape
    cv2.imwrite(str(row.mask), np.zeros(shape, np.uint8))
    with pytest.raises(ValueError, match=rf"{row.mask.name}: holds 0 contact px but index.csv"):
        accuracy._truth(row, frame_shape)


def test_cli_refuses_a_crosscheck_that_is_the_data_or_another_crosscheck(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Once scored again as ``<name>#2`` beside itself."""
    data = write_dataset(tmp_path / "d", fingers=1)
    (tmp_path / "link").symlink_to(data)
    other = write_dataset(tmp_path / "o", fingers=1)
    for cross, says in (
        ([data], f"--crosscheck {data}: dataset folder given twice (also as --data {data})"),
        ([f"{data}/./"], "also as --data"),
        ([tmp_path / "link"], "also as --data"),
        ([other, f"{other}/"], f"(also as --crosscheck {other})"),
    ):
        argv = ["bench", "--data", str(data), "--out", str(tmp_path / "out")]
        assert main([*argv, *(a for c in cross for a in ("--crosscheck", str(c)))]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0], err
    assert not (tmp_path / "out").exists()


def test_crosscheck_labels_are_distinct(tmp_path: Path) -> None:
    """``--data a/set#2 --crosscheck b/set`` once labelled both ``set#2``: the side-by-side
    table showed the cross-check's numbers under the main dataset's name."""
    assert labels(["a/set#2", "b/set", "c/set", "d/set#2"]) == ["set#2", "set", "set#3", "set#2#2"]
    assert labels(["x/set", "y/set", "z/set"]) == ["set", "set#2", "set#3"]
    main_set = write_dataset(tmp_path / "a" / "set#2", fingers=1)
    other = write_dataset(tmp_path / "b" / "set", fingers=1, seed=3)
    res = run_bench(main_set, tmp_path / "out", None, TINY, [other])
    assert res["crosscheck"][0]["label"] == "set"
    row = next(r for r in res["side_by_side"] if r["method"] == "unet" and r["bin_kpa"] == "5-10")
    main_row = next(b for b in res["bins"] if b["method"] == "unet" and b["bin_kpa"] == "5-10")
    other_row = next(
        b for b in res["crosscheck"][0]["bins"] if b["method"] == "unet" and b["bin_kpa"] == "5-10"
    )
    assert row["median_abs_rel_error@set#2"] == main_row["median_abs_rel_error"]
    assert row["median_abs_rel_error@set"] == other_row["median_abs_rel_error"]


def test_a_session_without_a_zero_pressure_frame_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its lowest (contact) frame was the reference while the report said "zero-pressure"."""
    data = write_dataset(tmp_path / "d", fingers=1)
    index = data / "index.csv"
    _rewrite_index(index, lambda rows: [rows[0], *(r for r in rows[1:] if float(r[4]) >= 4)])
    argv = ["bench", "--data", str(data), "--out", str(tmp_path / "out"), "--repeats", "1"]
    assert main(argv) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert f"{index}: session finger_0000 has no 0 kPa frame (its lowest pressure is 4 kPa)" in err
    assert "--no-reference" in err and not (tmp_path / "out").exists()
    assert main([*argv, "--no-reference", "--robustness", "--robustness-frames", "2"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()  # advice that fits what was asked
    assert "for the robustness suite: add one, or run without --robustness" in err
    with pytest.raises(ValueError, match="no 0 kPa frame"):  # a cross-check set too
        run_bench(write_dataset(tmp_path / "ok", fingers=1), tmp_path / "o", None, TINY, [data])
    res = run_bench(data, tmp_path / "out", config=dataclasses_replace(TINY, use_reference=False))
    assert res["reference"] == "none" and res["frames"] == 3


def test_a_broken_crosscheck_set_fails_before_any_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cross-check set's unreadable frame or mismatched mask was found only when the set was
    scored, after the main dataset's scoring, timing and robustness suite."""
    import cv2
    import numpy as np

    from contactcal.infer.bench.dataset import read_index

    def work(*_: Any, **__: Any) -> None:
        raise AssertionError("scored or timed before every dataset was checked")

    for name in ("evaluate", "timing", "run_robustness"):
        monkeypatch.setattr(bench_run, name, work)
    data = write_dataset(tmp_path / "d", fingers=1)
    other = write_dataset(tmp_path / "o", fingers=2, seed=2)
    rows = read_index(other)
    rows[3].frame.write_bytes(b"not an image")
    with pytest.raises(ValueError, match=f"{rows[3].frame}: not a PNG file"):
        run_bench(data, tmp_path / "out", None, TINY, [other])
    cv2.imwrite(str(rows[3].frame), load_image(rows[2].frame))  # readable again
    mask = np.zeros((50, 70), np.uint8)  # a no-contact frame's mask of another size
    cv2.imwrite(str(rows[0].mask), mask)
    with pytest.raises(ValueError, match=f"{rows[0].mask}: 70x50 px but its frame"):
        run_bench(data, tmp_path / "out", None, TINY, [other])
    cv2.imwrite(str(rows[0].mask), np.zeros(load_image(rows[0].frame).shape, np.uint8))
    _damage_pixels(rows[4].frame)  # its header, CRCs and IEND intact: found only by decoding
    with pytest.raises(ValueError, match=f"{rows[4].frame}: corrupt image data"):
        run_bench(data, tmp_path / "out", None, TINY, [other])
    assert not (tmp_path / "out").exists()


def _damage_pixels(png: Path) -> None:
    """Zero 16 bytes in the middle of a PNG's first IDAT chunk and restate its CRC."""
    import zlib

    b = bytearray(png.read_bytes())
    at = b.index(b"IDAT") - 4
    n = int.from_bytes(b[at : at + 4], "big")
    b[at + 8 + n // 2 : at + 24 + n // 2] = bytes(16)
    b[at + 8 + n : at + 12 + n] = zlib.crc32(b[at + 4 : at + 8 + n]).to_bytes(4, "big")
    png.write_bytes(bytes(b))


def test_a_frame_of_another_size_than_its_reference_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Once ``reference frame size 64×48 differs from the frame size 128×96``: no file named."""
    import cv2

    from contactcal.infer.bench.dataset import read_index

    data = write_dataset(tmp_path / "d", fingers=1)
    ref, big = read_index(data)[:2]  # 0 and 2 kPa: no contact, so an empty mask at any size
    for path in (big.frame, big.mask):
        cv2.imwrite(str(path), cv2.resize(load_image(path), (128, 96)))
    argv = ["bench", "--data", str(data), "--out", str(tmp_path / "out"), "--repeats", "1"]
    assert main([*argv, "--timing-frames", "1"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert f"{big.frame}: 128x96 px but the reference frame of its session finger_0000, " in err
    assert f"{ref.frame}, is 64x48 px" in err and not (tmp_path / "out").exists()
    res = run_bench(data, tmp_path / "o", config=dataclasses_replace(TINY, use_reference=False))
    assert res["frames"] == 5  # without references the sizes need not agree


def test_a_mask_of_another_size_than_its_frame_is_named(tmp_path: Path) -> None:
    """Once scored when its pixel count matched the index, else blamed on the count."""
    import cv2
    import numpy as np

    from contactcal.infer.bench import accuracy
    from contactcal.infer.bench.dataset import read_index

    row = next(r for r in read_index(write_dataset(tmp_path / "d", fingers=1)) if r.contact)
    mask = cv2.imread(str(row.mask), cv2.IMREAD_GRAYSCALE)
    for pad in (0, 255):  # the same contact pixel count, then another one
        cv2.imwrite(str(row.mask), np.pad(mask, ((0, 3), (0, 4)), constant_values=pad))
        with pytest.raises(ValueError) as err:
            accuracy._truth(row, load_image(row.frame).shape)
        assert str(err.value).startswith(f"{row.mask}: 68x51 px but its frame {row.frame} is 64x48")

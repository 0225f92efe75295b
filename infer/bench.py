"""``contactcal bench``: accuracy and speed of every method on held-out rendered sessions.

Accuracy is measured on the dataset's frames at their native size against the exact masks
(areas in input pixels; mm² through the frame's true pixel scale). Speed is measured end to end
on the same frames upscaled to the rig's 2592×1944 (decode excluded and included, JPEG and PNG),
as the median of several runs in one process, so ratios compare like with like.
"""

from __future__ import annotations

import csv
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from contactcal.infer.classical import ClassicalConfig
from contactcal.infer.curve import estimate_onset
from contactcal.infer.io import load_image
from contactcal.infer.methods import ClassicalMethod, Method, UnetMethod
from contactcal.infer.session import decode_reduction

PRESSURE_BINS = ((0.0, 3.0), (3.0, 5.0), (5.0, 10.0), (10.0, 20.0001))  # kPa, [lo, hi)


@dataclass(frozen=True)
class BenchConfig:
    """What the benchmark measures."""

    repeats: int = 5  # timing runs per configuration; the median is reported
    timing_frames: int = 6  # frames timed per run (mid-range pressures, several fingers)
    full_size: tuple[int, int] = (2592, 1944)  # rig resolution for the speed comparison, px
    threads: tuple[int, ...] = (1, 2)  # onnxruntime intra-op threads timed
    classical_scales: tuple[float, ...] = (1.0, 0.25)  # full and reduced-resolution baseline
    bins: tuple[tuple[float, float], ...] = field(default=PRESSURE_BINS)


@dataclass(frozen=True)
class Row:
    """One frame of the dataset."""

    session: str
    frame: Path
    pressure_kpa: float
    area_px: float  # truth (mask pixel count)
    mm_per_px: float
    onset_kpa: float
    hard: bool


def read_rows(data: str | os.PathLike[str]) -> dict[str, list[Row]]:
    """Sessions of a dataset folder (``index.csv``), each sorted by pressure.

    Raises:
        ValueError: no folder, no ``index.csv``, missing columns or files.
    """
    root = Path(data)
    index = root / "index.csv"
    if not index.is_file():
        raise ValueError(f"{index}: no such file; expected a dataset written by `contactcal synth`")
    need = {"session", "frame", "pressure_kpa", "area_px", "mm_per_px", "onset_kpa", "hard"}
    with open(index, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = need - set(reader.fieldnames or ())
        if missing:
            raise ValueError(f"{index}: missing columns {sorted(missing)}")
        sessions: dict[str, list[Row]] = {}
        for r in reader:
            path = root / r["frame"]
            if not path.is_file():
                raise ValueError(f"{index}: frame {path} listed but missing")
            sessions.setdefault(r["session"], []).append(
                Row(r["session"], path, float(r["pressure_kpa"]), float(r["area_px"]),
                    float(r["mm_per_px"]), float(r["onset_kpa"]), r["hard"] == "1")
            )  # fmt: skip
    if not sessions:
        raise ValueError(f"{index}: no frames")
    return {k: sorted(v, key=lambda r: r.pressure_kpa) for k, v in sorted(sessions.items())}


def _methods(model: str | None) -> dict[str, Callable[[], Method]]:
    """Methods whose accuracy is measured at the dataset's native resolution.

    Rendered frames (e.g. 400×300) are already ~1/6 of the rig's 2592 px; the classical
    routine's kernels scale with the width, so its accuracy here *is* its reduced-resolution
    accuracy, and the speed table times it at full and reduced resolution of 2592×1944 frames.
    """
    return {"unet": lambda: UnetMethod(model, threads=1), "classical": ClassicalMethod}


def evaluate(sessions: dict[str, list[Row]], model: str | None) -> list[dict[str, Any]]:
    """Measure every frame with every method.

    Returns:
        One record per (method, frame): truth and prediction, areas in input pixels.
    """
    records: list[dict[str, Any]] = []
    for name, make in _methods(model).items():
        method = make()
        for session, rows in sessions.items():
            method.prepare(load_image(rows[0].frame))
            for r in rows:
                res = method.measure(load_image(r.frame))
                rec = {
                    "method": name, "session": session, "frame": str(r.frame),
                    "pressure_kpa": r.pressure_kpa, "hard": r.hard, "onset_kpa": r.onset_kpa,
                    "true_area_px": r.area_px, "true_contact": r.area_px > 0,
                    "area_px": float(res.area_px), "contact": bool(res.contact),
                    "mm_per_px": r.mm_per_px,
                }  # fmt: skip
                records.append(rec)
                if res.soft_area_px is not None or name == "unet":
                    # The same prediction measured by its probability mass (sub-pixel area).
                    soft = res.soft_area_px if res.soft_area_px is not None else 0.0
                    records.append({**rec, "method": f"{name} (soft area)", "area_px": soft})
    return records


def onset_errors(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (method, session): estimated onset vs the truth masks' and the mechanics' onset."""
    out = []
    keys = sorted({(r["method"], r["session"]) for r in records})
    for method, session in keys:
        rs = [r for r in records if r["method"] == method and r["session"] == session]
        p = [r["pressure_kpa"] for r in rs]
        est = estimate_onset(p, [r["area_px"] for r in rs], [r["contact"] for r in rs])
        truth = estimate_onset(p, [r["true_area_px"] for r in rs], [r["true_contact"] for r in rs])
        out.append({"method": method, "session": session, "onset_kpa": est,
                    "truth_masks_onset_kpa": truth, "mechanics_onset_kpa": rs[0]["onset_kpa"],
                    "error_kpa": None if est is None else est - rs[0]["onset_kpa"]})  # fmt: skip
    return out


def _median_ms(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(1000.0 * (time.perf_counter() - t0))
    return statistics.median(times)


def timing(
    sessions: dict[str, list[Row]], model: str | None, config: BenchConfig
) -> list[dict[str, Any]]:
    """Median ms/frame at the rig's resolution, decode excluded and included, per configuration."""
    rows = [r for rs in sessions.values() for r in rs if 6.0 <= r.pressure_kpa <= 16.0]
    step = max(1, len(rows) // config.timing_frames)
    picks = rows[::step][: config.timing_frames]
    ref_rows = [sessions[r.session][0] for r in picks]
    w, h = config.full_size
    out: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        files: dict[str, list[Path]] = {".jpg": [], ".png": []}
        grays, refs = [], []
        for k, (r, ref) in enumerate(zip(picks, ref_rows, strict=True)):
            big = cv2.resize(load_image(r.frame), (w, h), interpolation=cv2.INTER_CUBIC)
            grays.append(big)
            refs.append(cv2.resize(load_image(ref.frame), (w, h), interpolation=cv2.INTER_CUBIC))
            for ext in files:
                path = Path(tmp) / f"f{k}{ext}"
                params = [cv2.IMWRITE_JPEG_QUALITY, 95] if ext == ".jpg" else []
                if not cv2.imwrite(str(path), big, params):
                    raise OSError(f"{path}: could not write a timing frame")
                files[ext].append(path)
        n = len(grays)
        configs: list[tuple[str, int, Method, int]] = []
        for s in config.classical_scales:
            name = "classical" if s == 1.0 else f"classical@{s:g}"
            configs.append((name, 1, ClassicalMethod(ClassicalConfig(work_scale=s)), 1))
        # The reduction `measure`/`calibrate` would choose for these files (crop >= input).
        reduce_k = decode_reduction(UnetMethod(model), files[".jpg"], None)
        for t in config.threads:
            configs.append(("unet", t, UnetMethod(model, threads=t), 1))
            configs.append((f"unet+reduced-decode 1/{reduce_k}", t, UnetMethod(model, threads=t),
                            reduce_k))  # fmt: skip
        for name, threads, method, reduce in configs:
            # Reduced decoding: the frame arrives at 1/reduce size; areas then scale by reduce².
            jpgs = files[".jpg"]
            inputs = grays if reduce == 1 else [load_image(p, reduce=reduce) for p in jpgs]
            method.prepare(
                refs[0]
                if reduce == 1
                else cv2.resize(refs[0], inputs[0].shape[::-1], interpolation=cv2.INTER_AREA)
            )

            def compute(method: Method = method, inputs: list[np.ndarray] = inputs) -> None:
                for g in inputs:
                    method.measure(g)

            rec: dict[str, Any] = {
                "config": name,
                "threads": threads,
                "frames": n,
                "ms_compute": _median_ms(compute, config.repeats) / n,
            }
            for ext, paths in files.items():
                if reduce > 1 and ext != ".jpg":
                    continue

                def end_to_end(
                    method: Method = method, paths: list[Path] = paths, reduce: int = reduce
                ) -> None:
                    for p in paths:
                        method.measure(load_image(p, reduce=reduce))

                key = f"ms_end_to_end{ext.replace('.', '_')}"
                rec[key] = _median_ms(end_to_end, config.repeats) / n
            out.append(rec)
        net = UnetMethod(model, threads=1).segmenter
        x = np.zeros((1, net.spec.channels, net.spec.preprocess.input_size,
                      net.spec.preprocess.input_size), np.float32)  # fmt: skip
        run = lambda: net.session.run(None, {net.input_name: x})  # noqa: E731
        run()
        out.append({"config": "unet network only", "threads": 1, "frames": 1,
                    "ms_compute": _median_ms(run, 20 * config.repeats)})  # fmt: skip
    return out


def run_bench(
    data: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    model: str | None = None,
    config: BenchConfig | None = None,
) -> dict[str, Any]:
    """Run accuracy and speed benchmarks and write ``report.md``, ``results.json`` and plots."""
    from contactcal.infer.bench_report import write_report

    config = config or BenchConfig()
    sessions = read_rows(data)
    records = evaluate(sessions, model)
    results = {
        "data": str(Path(data).resolve()), "model": model or "shipped",
        "sessions": len(sessions), "frames": sum(len(v) for v in sessions.values()),
        "config": {"repeats": config.repeats, "timing_frames": config.timing_frames,
                   "full_size": list(config.full_size)},
        "records": records, "onset": onset_errors(records),
        "timing": timing(sessions, model, config),
    }  # fmt: skip
    write_report(out_dir, results, config.bins)
    return results

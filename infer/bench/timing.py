"""Speed of every method at the rig's resolution (``contactcal bench``'s speed table).

Frames of the dataset are upscaled to ``BenchConfig.full_size`` (2592×1944) and timed end to
end: on decoded arrays, and including the JPEG or PNG decode from a file. Each number is the
median of several runs in one process after one untimed warm-up run, so ratios compare like
with like. A configuration's thread count holds for onnxruntime and OpenCV alike (OpenCV would
otherwise spread the classical routine's full-resolution filters over every core).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from contactcal.infer.bench.config import BenchConfig
from contactcal.infer.bench.dataset import IndexRow, spread
from contactcal.infer.bench.models import BenchModel
from contactcal.infer.image.cv_threads import opencv_threads
from contactcal.infer.image.read import load_image
from contactcal.infer.image.write import write_image
from contactcal.infer.methods.base import Method
from contactcal.infer.methods.classical import ClassicalConfig, ClassicalMethod
from contactcal.infer.methods.unet.runner import OnnxSegmenter

#: Pressures of the timed frames, kPa (mid-range: a contact patch of typical size).
TIMED_KPA = (6.0, 16.0)
#: File formats timed end to end, with their encoder parameters.
FORMATS: dict[str, tuple[int, ...]] = {".jpg": (cv2.IMWRITE_JPEG_QUALITY, 95), ".png": ()}


@dataclass(frozen=True)
class TimingFrames:
    """The timed frames at full size: decoded, and written as files per format."""

    grays: list[np.ndarray]  # (H, W) uint8 each
    files: dict[str, list[Path]]  # per suffix (".jpg", ".png"), same frames
    reference: np.ndarray  # (H, W) uint8, a session's zero-pressure frame
    reference_jpg: Path  # the same reference as a JPEG


@dataclass(frozen=True)
class Timed:
    """One timed configuration."""

    name: str
    threads: int
    method: Method
    reduction: int  # JPEG decode reduction (1: full decode)


def median_ms(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``fn()`` over ``repeats`` runs after one untimed warm-up run (first-call
    costs: onnxruntime's first run, OpenCV's buffers, the files' page cache), ms."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(1000.0 * (time.perf_counter() - t0))
    return statistics.median(times)


def pick_frames(
    sessions: Mapping[str, Sequence[IndexRow]], count: int
) -> tuple[list[IndexRow], IndexRow]:
    """Up to ``count`` mid-pressure frames spread over the sessions, and a reference frame."""
    rows = [r for rs in sessions.values() for r in rs]
    mid = [r for r in rows if TIMED_KPA[0] <= r.pressure_kpa <= TIMED_KPA[1]]
    pool = mid or rows  # a dataset without mid-range pressures still gets timed
    picks = [pool[i] for i in spread(len(pool), count)]
    return picks, sessions[picks[0].session_key][0]


def write_timing_frames(
    folder: Path, picks: Sequence[IndexRow], reference: IndexRow, size: tuple[int, int]
) -> TimingFrames:
    """Upscale the frames to ``size`` (width, height) and write them in every timed format."""

    def upscaled(path: Path) -> np.ndarray:
        return cv2.resize(load_image(path), size, interpolation=cv2.INTER_CUBIC)

    grays = [upscaled(r.frame) for r in picks]
    files: dict[str, list[Path]] = {ext: [] for ext in FORMATS}
    for i, gray in enumerate(grays):
        for ext, params in FORMATS.items():
            files[ext].append(write_image(folder / f"f{i}{ext}", gray, params))
    ref = upscaled(reference.frame)
    ref_jpg = write_image(folder / "reference.jpg", ref, FORMATS[".jpg"])
    return TimingFrames(grays, files, ref, ref_jpg)


def timed_configs(
    models: Sequence[BenchModel], frames: TimingFrames, config: BenchConfig
) -> list[Timed]:
    """The classical routine at each work scale, then each U-Net model (:func:`unet_configs`):
    ``models[0]`` at each of ``config.threads``, the variants ``models[1:]`` at one thread, like
    the error table's scoring."""
    out = []
    for s in config.classical_scales:
        name = "classical" if s == 1.0 else f"classical@{s:g}"
        out.append(Timed(name, 1, ClassicalMethod(ClassicalConfig(work_scale=s)), 1))
    for i, model in enumerate(models):
        out += unet_configs(model, config.threads if i == 0 else (1,), frames)
    return out


def unet_configs(model: BenchModel, threads: Sequence[int], frames: TimingFrames) -> list[Timed]:
    """``model``'s U-Net at each thread count: full decode and, where ``start`` chooses one for
    these files, the reduced JPEG decode of ``measure``/``calibrate``.

    One method per thread count, built from the content read once, times both of its
    configurations (:func:`time_config` sets the reference first, which resets what the other
    left; each median leaves out a warm-up run) and, at one thread, finds that reduction.
    """
    methods = {t: model.method(threads=t) for t in {1, *threads}}
    k = methods[1].start(frames.files[".jpg"], None).reduction
    out = []
    for t in threads:
        out.append(Timed(model.name, t, methods[t], 1))
        if k > 1:
            out.append(Timed(f"{model.name}+reduced-decode 1/{k}", t, methods[t], k))
    return out


def time_config(c: Timed, frames: TimingFrames, repeats: int) -> dict[str, Any]:
    """Median ms/frame of one configuration: decoded, and including each file decode."""
    k = c.reduction
    if k == 1:
        inputs = frames.grays
        c.method.set_reference(frames.reference)
    else:  # the frames arrive at 1/k size; areas come back in file pixels
        inputs = [load_image(p, reduce=k) for p in frames.files[".jpg"]]
        c.method.set_reference(load_image(frames.reference_jpg, reduce=k), k)
    n = len(inputs)

    def compute() -> None:
        for g in inputs:
            c.method.measure(g)

    rec: dict[str, Any] = {
        "config": c.name,
        "threads": c.threads,
        "frames": n,
        "ms_compute": median_ms(compute, repeats) / n,
    }
    for ext, paths in frames.files.items():
        key = f"ms_end_to_end_{ext.lstrip('.')}"
        if k > 1 and ext != ".jpg":
            rec[key] = None  # reduced decoding is a JPEG feature
            continue

        def end_to_end(paths: Sequence[Path] = paths) -> None:
            for p in paths:
                c.method.measure(load_image(p, reduce=k))

        rec[key] = median_ms(end_to_end, repeats) / n
    return rec


def time_network(model: BenchModel, repeats: int) -> dict[str, Any]:
    """Median ms of the U-Net's network alone (onnxruntime, one thread) on a zero input."""
    net = OnnxSegmenter(model.path, content=model.content)
    side = net.spec.preprocess.input_size
    x = np.zeros((1, net.spec.channels, side, side), np.float32)

    def run() -> None:
        net.ort_session.run(None, {net.input_name: x})

    return {
        "config": "unet network only",
        "threads": 1,
        "frames": 1,
        "ms_compute": median_ms(run, 20 * repeats),
        **{f"ms_end_to_end_{ext.lstrip('.')}": None for ext in FORMATS},
    }


def timing(
    sessions: Mapping[str, Sequence[IndexRow]],
    models: Sequence[BenchModel],
    config: BenchConfig,
) -> list[dict[str, Any]]:
    """Median ms/frame at ``config.full_size`` per configuration (see :func:`time_config`), the
    U-Nets built from ``models`` as read once (:func:`~contactcal.infer.bench.models.load_models`);
    then the network alone of ``models[0]`` (:func:`time_network`)."""
    picks, reference = pick_frames(sessions, config.timing_frames)
    with tempfile.TemporaryDirectory() as tmp:
        frames = write_timing_frames(Path(tmp), picks, reference, config.full_size)
        out = []
        for c in timed_configs(models, frames, config):
            with opencv_threads(c.threads):  # OpenCV's threads too, not only onnxruntime's
                out.append(time_config(c, frames, config.repeats))
    out.append(time_network(models[0], config.repeats))
    return out

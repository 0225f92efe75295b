"""Where the U-Net's time goes in one ``measure`` session, phase by phase, in one fresh process.

The example session upscaled to 2592×1944 (as ``cli_speed.py`` writes it: JPEG q95 or PNG, grey
or ``--colour``) is measured the way ``contactcal measure`` does it (``measure_files``'s steps,
timed one by one on one thread): the process's imports, the method's construction (onnxruntime's
import, the model's sessions), ``start`` (headers, the reference's decode, its ring), then per
frame the decode, the ring-position check, the shrink, ``prepare`` (crop, normalisation, ridge
channel), the network, ``postprocess``. Minor page faults are counted beside each phase (a fresh
array of a few hundred kB costs a few µs per 4 kB page on this host). Run on an idle machine:

    .venv/bin/python docs/scripts/unet_phases.py [--format .jpg|.png] [--colour]
"""

from __future__ import annotations

import time

T_START = time.perf_counter()

import argparse  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from pathlib import Path  # noqa: E402

from contactcal.infer.image.cv_threads import opencv_threads  # noqa: E402
from contactcal.infer.image.read import load_image  # noqa: E402
from contactcal.infer.methods.unet.method import UnetMethod  # noqa: E402
from contactcal.infer.methods.unet.postprocess import postprocess  # noqa: E402
from contactcal.infer.methods.unet.prepare import prepare  # noqa: E402
from contactcal.infer.pipeline import measure  # noqa: E402

T_IMPORTED = time.perf_counter()
sys.path.insert(0, str(Path(__file__).resolve().parent))
from cli_speed import _session  # noqa: E402


def _faults() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


@contextmanager
def _phase(log: dict[str, list[tuple[float, int]]], name: str) -> Iterator[None]:
    """Append the block's (ms, minor page faults) to ``log[name]``."""
    f0, t0 = _faults(), time.perf_counter()
    yield
    log.setdefault(name, []).append((1000.0 * (time.perf_counter() - t0), _faults() - f0))


def _session_phases(paths: list[Path]) -> dict[str, list[tuple[float, int]]]:
    """Every phase of one session, timed (reference first in ``paths``)."""
    log: dict[str, list[tuple[float, int]]] = {}
    with _phase(log, "construct (onnxruntime, sessions)"):
        m = UnetMethod(threads=1)
    seg, ref_path, frames = m.segmenter, paths[0], paths[1:]
    cfg, channels = seg.spec.preprocess, seg.spec.channels
    with _phase(log, "start (headers, reference)"):
        started = m.start(frames, ref_path)
        k, img = started.reduction, started.reference
        ring = measure._coarse_ring(img)
    ref = measure._Reference(ref_path, measure._file_size(img, k), ring)
    for p in frames:
        with _phase(log, "decode"):
            img = load_image(p, reduce=k)
        with _phase(log, "ring check"):
            measure._check_frame(ref, p, img, measure._file_size(img, k))
        with _phase(log, "shrink"):
            gray, _ = m._shrunk(img)
        with _phase(log, "prepare"):
            prep = prepare(gray, m.reference, cfg, channels)
        with _phase(log, "network"):
            prob = seg.probabilities(prep.x)
        with _phase(log, "postprocess"):
            postprocess(prob, prep.box, gray.shape[:2], seg.spec)
    return log


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--format", choices=(".jpg", ".png"), default=".jpg")
    ap.add_argument("--colour", action="store_true", help="colour frames (default: grey)")
    args = ap.parse_args()
    print(f"imports (numpy, OpenCV, contactcal): {1000 * (T_IMPORTED - T_START):.0f} ms")
    with tempfile.TemporaryDirectory() as tmp, opencv_threads(1):
        paths = _session(Path(tmp), args.format, args.colour)
        log = _session_phases(paths)
    n = len(paths) - 1
    print(f"{n} frames + reference, {args.format}, {'colour' if args.colour else 'grey'}")
    print(f"{'phase':36s} {'calls':>5s} {'median ms':>10s} {'total ms':>9s} {'faults/call':>12s}")
    for name, runs in log.items():
        ms = [t for t, _ in runs]
        faults = statistics.median(f for _, f in runs)
        print(
            f"{name:36s} {len(ms):5d} {statistics.median(ms):10.2f} {sum(ms):9.1f} {faults:12.0f}"
        )


if __name__ == "__main__":
    main()

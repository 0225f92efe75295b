"""Where the U-Net's time goes in one ``measure`` session, phase by phase, in one fresh process.

The example session upscaled to 2592×1944 (as ``cli_speed.py`` writes it: JPEG q95 or PNG, grey
or ``--colour``) is measured by ``measure_files`` itself, one thread, with timers wrapped around
the functions it calls: the method's construction (onnxruntime's import, the model's sessions),
``start`` (headers, the reference's decode, its ring), then per frame the decode, the
ring-position check, the shrink, ``prepare`` (crop, normalisation, ridge channel), the network and
``postprocess``. Minor page faults are counted beside each phase (a fresh array of a few hundred
kB costs a few µs per 4 kB page on this host). Not timed here, but in ``contactcal measure``: the
interpreter's start, the command's other imports, writing the results and the exit (together
~0.1-0.15 s on this host; ``cli_speed.py`` times the whole command). Run on an idle machine:

    .venv/bin/python docs/scripts/unet_phases.py [--format .jpg|.png] [--colour]
"""

from __future__ import annotations

import time

T_START = time.perf_counter()

import argparse  # noqa: E402
import functools  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

from contactcal.infer.image.cv_threads import opencv_threads  # noqa: E402
from contactcal.infer.methods.unet import method, runner  # noqa: E402
from contactcal.infer.pipeline import measure  # noqa: E402

T_IMPORTED = time.perf_counter()
sys.path.insert(0, str(Path(__file__).resolve().parent))
from cli_speed import _session  # noqa: E402

#: Phase name → (owner, attribute) of the function timed as that phase.
PHASES: dict[str, tuple[Any, str]] = {
    "construct (onnxruntime, sessions)": (runner.OnnxSegmenter, "__init__"),
    "start (headers, reference)": (method.UnetMethod, "start"),
    "decode": (measure, "_decoded"),
    "ring check": (measure, "check_frame"),
    "shrink": (method.UnetMethod, "_shrunk"),
    "prepare": (runner, "prepare"),
    "network": (runner.OnnxSegmenter, "probabilities"),
    "postprocess": (runner, "postprocess"),
}


def _faults() -> int:
    """Minor page faults of this process so far."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def _timer(log: list[tuple[float, int]], fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` that appends (ms, minor page faults) of each call to ``log``."""

    @functools.wraps(fn)
    def timed(*args: Any, **kwargs: Any) -> Any:
        f0, t0 = _faults(), time.perf_counter()
        out = fn(*args, **kwargs)
        log.append((1000.0 * (time.perf_counter() - t0), _faults() - f0))
        return out

    return timed


def _session_phases(paths: list[Path]) -> dict[str, list[tuple[float, int]]]:
    """``measure_files`` on one session (reference first in ``paths``), every phase timed."""
    log: dict[str, list[tuple[float, int]]] = {name: [] for name in PHASES}
    originals = {name: getattr(owner, attr) for name, (owner, attr) in PHASES.items()}
    try:
        for name, (owner, attr) in PHASES.items():
            setattr(owner, attr, _timer(log[name], originals[name]))
        unet = method.UnetMethod(threads=1)
        measure.measure_files(paths[1:], unet, paths[0])
    finally:
        for name, (owner, attr) in PHASES.items():
            setattr(owner, attr, originals[name])
    return log


def main() -> None:
    """Print each phase's calls, median and total ms and median page faults per call."""
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

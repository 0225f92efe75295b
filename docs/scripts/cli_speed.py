"""Time ``contactcal measure`` end to end, process start-up included, U-Net against classical.

The example session (20 frames + its 0 kPa reference) is upscaled to the rig's 2592×1944 and
written as JPEG q95 and as PNG into a temporary folder; each method measures the session through
the CLI, the two methods alternating, ``--runs`` times per format; the medians and their ratio
are printed (issue target: JPEG ≤ 0.6×, PNG ≤ 1.0×). ``--colour`` writes the frames as colour
images (the rig paper's camera images are RGB, converted to grey by the routine, Figures 5b and
6b; both methods read them as grey). ``--cli PATH`` times another ``contactcal`` executable, e.g.
one installed from the wheel (``bash .ci/wheel-smoke DIR`` leaves it in ``DIR/venv/bin``): a
wheel install carries compiled bytecode, while an editable install under
``PYTHONDONTWRITEBYTECODE=1`` compiles every imported module at each start. Run on an idle
machine:

    .venv/bin/python docs/scripts/cli_speed.py [--runs 5] [--colour] [--cli PATH]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

from contactcal.infer.image.read import load_image

ROOT = Path(__file__).resolve().parents[2]
SIZE = (2592, 1944)
FORMATS = {".jpg": [cv2.IMWRITE_JPEG_QUALITY, 95], ".png": []}


def _session(folder: Path, ext: str, colour: bool) -> list[Path]:
    """The example frames upscaled to :data:`SIZE` (grey, or colour), reference first."""
    out = []
    for src in sorted((ROOT / "examples" / "session").glob("p*.jpg")):
        img = cv2.imread(str(src), cv2.IMREAD_COLOR) if colour else load_image(src)
        img = cv2.resize(img, SIZE, interpolation=cv2.INTER_CUBIC)
        dst = folder / (src.stem + ext)
        cv2.imwrite(str(dst), img, FORMATS[ext])
        out.append(dst)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--colour", action="store_true", help="colour frames (default: grey)")
    ap.add_argument("--cli", type=Path, help="contactcal executable (default: this venv's)")
    args = ap.parse_args()
    cli = args.cli or Path(sys.executable).with_name("contactcal")
    with tempfile.TemporaryDirectory() as tmp:
        for ext in FORMATS:
            paths = _session(Path(tmp), ext, args.colour)
            times: dict[str, list[float]] = {"unet": [], "classical": []}
            for _ in range(args.runs):
                for method, runs in times.items():
                    out = Path(tmp) / f"{method}{ext}.json"
                    out.unlink(missing_ok=True)
                    cmd = [str(cli), "measure", "--method", method, "--reference", str(paths[0])]
                    t0 = time.perf_counter()
                    subprocess.run(
                        [*cmd, "--out", str(out), *map(str, paths[1:])],
                        check=True,
                        capture_output=True,
                    )
                    runs.append(time.perf_counter() - t0)
            u, c = (statistics.median(times[m]) for m in ("unet", "classical"))
            print(
                f"{ext} ({'colour' if args.colour else 'grey'}): {len(paths) - 1} frames + "
                f"reference, median of {args.runs}: "
                f"unet {u:.2f} s, classical {c:.2f} s, ratio {u / c:.2f}"
            )


if __name__ == "__main__":
    main()

"""What the robustness suite's blur leaves of the ridge evidence the U-Net's third channel sees.

For each blur level of ``contactcal bench``'s suite (σ in px of a 2592-px-wide frame, scaled to
the frame's width: :func:`contactcal.infer.bench.perturb.blur`), over a session's frames at
≥ 5 kPa with their exact masks (the reference frame, the session's lowest pressure, is blurred
alike), the model's ridge-energy channel (``prepare``, the one deployment path):

* **inside**: its median over the true contact (network grid);
* **outside**: its median over a 12-network-px band around the contact (the inner ring and the
  free membrane: what the ridges must be told apart from);
* **inside / outside**: the median over frames of their ratio (1: no ridge evidence left);
* **sinusoid**: what that blur leaves of a ridge of period 28 px at 2592 wide (4.3 px at 400),
  ``exp(-2π² σ² / T²)``.

Report only: nothing is chosen on it.

    .venv/bin/python docs/scripts/ridge_blur.py [examples/session] [--model M.onnx]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import cv2
import numpy as np
import onnxruntime as ort

from contactcal.infer.bench.perturb import RIG_WIDTH_PX, blur
from contactcal.infer.methods.unet.crop import crop_resize
from contactcal.infer.methods.unet.prepare import prepare, session_reference
from contactcal.infer.methods.unet.spec import read_spec

LEVELS = (0.0, 3.0, 6.0, 12.0, 24.0)  # the suite's blur levels, px at 2592 wide
RIDGE_PERIOD_PX = 28.0  # px at 2592 wide (docs/synth.md)
BAND_PX = 12  # network px around the contact


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("session", nargs="?", default="examples/session", type=Path)
    ap.add_argument("--model", default="models/contact_unet.onnx")
    args = ap.parse_args()
    spec = read_spec(
        ort.InferenceSession(args.model).get_modelmeta().custom_metadata_map, args.model
    )
    cfg = spec.preprocess
    if cfg.ridge_work_px <= 0:
        raise SystemExit(f"{args.model}: no ridge channel (ridge_work_px 0)")
    with open(args.session / "manifest.csv", newline="") as f:
        rows = sorted((float(r["pressure_kpa"]), r["file"]) for r in csv.DictReader(f))
    ref = cv2.imread(str(args.session / rows[0][1]), cv2.IMREAD_GRAYSCALE)
    frames = [(f, Path(f).with_suffix(".png").name) for p, f in rows if p >= 5.0]
    kernel = np.ones((2 * BAND_PX + 1,) * 2, np.uint8)
    print(
        f"{args.session}: {len(frames)} frames at >= 5 kPa; ridge channel at {cfg.ridge_work_px} px"
    )
    print("| blur σ (px at 2592) | inside | outside | inside / outside | sinusoid |")
    print("|---|---|---|---|---|")
    for level in LEVELS:
        rng = np.random.default_rng(0)  # blur draws nothing; the suite's signature needs one
        reference = session_reference(blur(ref, level, rng), cfg)
        inside, outside = [], []
        for file, mask_name in frames:
            gray = cv2.imread(str(args.session / file), cv2.IMREAD_GRAYSCALE)
            mask = cv2.imread(str(args.session / "masks" / mask_name), cv2.IMREAD_GRAYSCALE) > 0
            prepared = prepare(blur(gray, level, rng), reference, cfg, spec.channels)
            ridge = prepared.x[-1]
            held = crop_resize(mask.astype(np.float32), prepared.box, cfg.input_size) > 0.5
            band = cv2.dilate(held.astype(np.uint8), kernel).astype(bool) & ~held
            inside.append(float(np.median(ridge[held])))
            outside.append(float(np.median(ridge[band])))
        ratio = np.median(np.divide(inside, outside))
        sine = math.exp(-2 * math.pi**2 * level**2 / RIDGE_PERIOD_PX**2)
        print(
            f"| {level:g} | {np.median(inside):.3f} | {np.median(outside):.3f} | {ratio:.2f} "
            f"| {sine:.3f} |"
        )
    print(f"(frame width {ref.shape[1]} px; levels scale by {ref.shape[1] / RIG_WIDTH_PX:.3f})")


if __name__ == "__main__":
    main()

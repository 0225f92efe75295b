"""Make ``docs/ablation_smooth.jpg``: the same session with its drawn coating and a smooth one.

One nominal bench session (``data/v2_check``'s seed 13000, finger 2) rendered at 1, 2, 3 and
6 kPa (400×300, 16 spp, same frame seeds): top row as drawn (flake tilt 0.5-1.5°, GGX α
0.02-0.06: the inner ring is a halo before contact), bottom row with the smooth coating of
``ranges.SMOOTH_DRAWS`` at its sharp end (tilt 0.2°, α 0.01: a thin sharp ring). The contact,
the mask and everything else are the same. Takes about a minute.

    .venv/bin/python docs/scripts/smooth_ablation.py
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.image.write import write_image
from contactcal.synth.dataset import DatasetConfig
from contactcal.synth.dataset_finger import session_params
from contactcal.synth.session import RenderConfig, render_session

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs/ablation_smooth.jpg"
PRESSURES = (1.0, 2.0, 3.0, 6.0)  # kPa: before contact (1-2), onset, contact
SEED, FINGER = 13000, 2  # the bench set's seed; finger 2 is nominal, onset about 3 kPa


def main() -> None:
    render = RenderConfig(400, 300, spp=16)
    base = session_params(
        DatasetConfig(fingers=12, pressures_kpa=(0.0,), seed=SEED, hard_fraction=0.5), FINGER
    )
    smooth = replace(base, optics=replace(base.optics, particle_tilt_deg=0.2, roughness_alpha=0.01))
    rows = []
    for label, session in (("as drawn", base), ("smooth coating", smooth)):
        frames = [f.frame for f in render_session(session, PRESSURES, render, (SEED, FINGER))]
        row = np.hstack([cv2.cvtColor(f, cv2.COLOR_RGB2BGR)[:, 50:350] for f in frames])
        cv2.putText(row, label, (6, 290), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
        rows.append(row)
    strip = np.vstack(rows)
    for k, p in enumerate(PRESSURES):
        cv2.putText(strip, f"{p:g} kPa", (k * 300 + 6, 18), 0, 0.5, (255, 255, 255), 1)
    write_image(OUT, strip, (cv2.IMWRITE_JPEG_QUALITY, 85))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()

"""Write the procedural stand-in example session (used until rendered frames replace it).

Run from the repository root: ``python examples/make_standin.py``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from procedural import draw_frame, write_png

from contactcal.infer.atomic import write_json, write_text

OUT = Path(__file__).resolve().parent / "session"
MM_PER_PX = 0.045  # at 648 px width: 27.5 mm cylinder ≈ 610 px


def main() -> None:
    rng = np.random.default_rng(20261122)
    rows = ["file,pressure_kpa"]
    for p in range(0, 21, 2):
        area_mm2 = 0.0 if p < 3 else 200.0 * (1 - math.exp(-(p - 3) / 5.0))
        if area_mm2 > 0:
            b = math.sqrt(area_mm2 / (math.pi * 1.35)) / MM_PER_PX
            axes: tuple[float, float] | None = (1.35 * b, b)
        else:
            axes = None
        frame = draw_frame(rng, semi_axes_px=axes, angle_deg=80.0, centre_offset_px=(6.0, -4.0))
        name = f"p{p:04.1f}kpa.jpg"
        write_png(str(OUT / name), frame.image)
        rows.append(f"{name},{p:.1f}")
    write_text(OUT / "manifest.csv", "\n".join(rows) + "\n")
    write_json(OUT / "rig.json", {"mm_per_px": MM_PER_PX, "image_width_px": 648})


if __name__ == "__main__":
    main()

"""Make ``docs/ablation_skin.jpg``: one fingerprint's contact texture under each skin condition.

No Mitsuba: the panels are the ridge-coupling texture the renderer receives (1 = skin touching,
bright), inside a 6 mm disc of contact, for each element of ``synth/skin.py`` alone at its hard
extreme. In the frame, this texture blends the coating with the skin (``coating.py``).

    .venv/bin/python docs/scripts/skin_ablation.py
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from contactcal.synth.fingerprint import make_fingerprint
from contactcal.synth.skin import SkinCondition, apply_skin

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs/ablation_skin.jpg"
SIZE, HALF_MM = 300, 7.0  # texels, half side (mm)

PANELS = [
    ("clean (nominal)", SkinCondition()),
    ("inverted polarity", SkinCondition(polarity=-1)),
    ("dry 60 %", SkinCondition(dryness=0.6, seed=3)),
    ("wet 0.8", SkinCondition(wetness=0.8)),
    ("3 scars", SkinCondition(scars=3, seed=5)),
]


def main() -> None:
    fp = make_fingerprint(np.random.default_rng(24))
    c = (np.arange(SIZE) + 0.5) * (2 * HALF_MM / SIZE) - HALF_MM
    x, y = np.meshgrid(c, c)
    ridges = fp.sample(x, y).astype(np.float32)
    inside = np.hypot(x, y) <= 6.0
    texel = 2 * HALF_MM / SIZE
    tiles = []
    for label, skin in PANELS:
        w = apply_skin(ridges, texel, (SIZE / 2, SIZE / 2), skin) * inside
        tile = cv2.cvtColor(np.rint(w * 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)
        cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 200, 255), 1)
        tiles.append(tile)
    cv2.imwrite(str(OUT), np.hstack(tiles), [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()

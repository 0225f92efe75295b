"""README montage: the example session at 0, 2, 4, 8, 14, 20 kPa with the true contact outline.

Run from the repository root: ``python docs/scripts/montage.py`` (writes docs/montage.jpg).
"""

from pathlib import Path

import cv2

from contactcal.infer.image.read import load_image
from contactcal.infer.image.write import write_image
from contactcal.infer.pipeline.overlay import draw_overlay, montage

ROOT = Path(__file__).resolve().parents[2]
SESSION = ROOT / "examples" / "session"


def main() -> None:
    """Write docs/montage.jpg from the example session and its masks."""
    tiles = []
    for kpa in (0, 2, 4, 8, 14, 20):
        stem = f"p{kpa:04.1f}kpa"
        mask = cv2.imread(str(SESSION / "masks" / f"{stem}.png"), cv2.IMREAD_GRAYSCALE)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        outline = max(contours, key=cv2.contourArea) if contours else None
        tiles.append(
            draw_overlay(load_image(SESSION / f"{stem}.jpg"), {"truth": outline}, f"{kpa} kPa")
        )
    write_image(ROOT / "docs" / "montage.jpg", montage(tiles, columns=3, width=400))


if __name__ == "__main__":
    main()

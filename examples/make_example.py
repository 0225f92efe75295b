"""Render the bundled example session: one finger, 0-20 kPa in 1 kPa steps, 400×300 px.

Frames are stored as JPEG (quality 75, a typical camera setting) to keep the repository small;
masks (exact truth) as PNG.
Run from the repository root (needs the ``synth`` extra): ``python examples/make_example.py``.
"""

from __future__ import annotations

import csv
import shutil
import tempfile
from pathlib import Path

import cv2

from contactcal.infer.files.atomic import write_text
from contactcal.synth.dataset import DatasetConfig, build_dataset
from contactcal.synth.layout import parse_pressures
from contactcal.synth.session import RenderConfig

OUT = Path(__file__).resolve().parent / "session"
SEED = 24  # dataset seed of the example (finger 0); not used by any training set
JPEG_QUALITY = 75  # the frames as a rig camera saves them; keeps the session ~0.6 MB
CONFIG = DatasetConfig(
    fingers=1,
    pressures_kpa=parse_pressures("0:20:1"),
    seed=SEED,
    hard_fraction=0.0,
    render=RenderConfig(width=400, height=300, spp=16),
)


def main() -> None:
    """Render into a temporary folder, then copy a compact session into ``examples/session``."""
    with tempfile.TemporaryDirectory() as tmp:
        build_dataset(tmp, CONFIG, workers=1, progress=True)
        src = Path(tmp) / "finger_0000"
        if OUT.exists():
            shutil.rmtree(OUT)
        (OUT / "masks").mkdir(parents=True)
        with open(Path(tmp) / "index.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        manifest, truth = ["file,pressure_kpa"], ["file,pressure_kpa,contact,area_px,area_mm2"]
        for r in rows:
            stem = Path(r["frame"]).stem
            img = cv2.imread(str(Path(tmp) / r["frame"]), cv2.IMREAD_COLOR)
            cv2.imwrite(str(OUT / f"{stem}.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            shutil.copy(Path(tmp) / r["mask"], OUT / "masks" / f"{stem}.png")
            manifest.append(f"{stem}.jpg,{r['pressure_kpa']}")
            cells = (f"{stem}.jpg", r["pressure_kpa"], r["contact"], r["area_px"], r["area_mm2"])
            truth.append(",".join(str(c) for c in cells))
        write_text(OUT / "manifest.csv", "\n".join(manifest) + "\n")
        write_text(OUT / "truth.csv", "\n".join(truth) + "\n")
        shutil.copy(src / "rig.json", OUT / "rig.json")
        shutil.copy(src / "session.json", OUT / "session.json")


if __name__ == "__main__":
    main()

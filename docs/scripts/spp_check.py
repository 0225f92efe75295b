"""Does the network see a difference between 8 and 16 samples per pixel? (docs/synth.md)

Renders the same frames (the bench set's seed 13000, fingers 0-5, half of them hard; 0, 3, 5,
10 and 20 kPa; 400×300; same frame seeds, so the same camera noise draws) at 8, 16 and 64 spp
and compares them with the 64-spp frame, the converged reference: the RMS grey-level difference,
the ridge-energy channel inside the contact (the evidence the model needs), and the shipped
model's area (each session with its own 0 kPa frame as reference, at the same spp). Takes a few
minutes on 2 cores.

    .venv/bin/python docs/scripts/spp_check.py
"""

from __future__ import annotations

import numpy as np

from contactcal.infer.image.gray import to_gray_u8
from contactcal.infer.methods.unet.crop import crop_resize
from contactcal.infer.methods.unet.prepare import prepare, session_reference
from contactcal.infer.methods.unet.runner import OnnxSegmenter
from contactcal.synth.dataset import DatasetConfig
from contactcal.synth.dataset_finger import session_params
from contactcal.synth.session import RenderConfig, render_session

SEED, FINGERS = 13000, range(6)
PRESSURES = (0.0, 3.0, 5.0, 10.0, 20.0)  # kPa; the first is the session reference
SPPS = (8, 16, 64)  # 64 = reference


def _measure(seg: OnnxSegmenter, frames: list, ref_grey: np.ndarray) -> list[tuple]:
    """(grey, area_px, ridge energy median inside the truth mask, truth area) per contact frame."""
    cfg = seg.spec.preprocess
    ref = session_reference(ref_grey, cfg)
    out = []
    for f in frames[1:]:
        g = to_gray_u8(f.frame)
        area = seg.segment(g, ref).area_px
        prep = prepare(g, ref, cfg, seg.spec.channels)
        inside = crop_resize(f.mask.astype(np.float32), prep.box, cfg.input_size) > 0.5
        ridge = float(np.median(prep.x[-1][inside])) if inside.any() else float("nan")
        out.append((g, area, ridge, float(f.mask.sum())))
    return out


def main() -> None:
    seg = OnnxSegmenter()
    config = DatasetConfig(fingers=12, pressures_kpa=(0.0,), seed=SEED, hard_fraction=0.5)
    res: dict[int, list[tuple]] = {s: [] for s in SPPS}
    for finger in FINGERS:
        session = session_params(config, finger)
        for spp in SPPS:
            frames = list(
                render_session(session, PRESSURES, RenderConfig(400, 300, spp=spp), (SEED, finger))
            )
            res[spp] += _measure(seg, frames, to_gray_u8(frames[0].frame))
    ref = res[SPPS[-1]]
    print(f"{len(ref)} frames (fingers {list(FINGERS)}, {PRESSURES[1:]} kPa), vs {SPPS[-1]} spp:")
    print(
        "spp | RMS grey diff | ridge energy in contact, median | area vs 64 spp, median |d| "
        "| area vs truth, median |err| (contact frames)"
    )
    for spp in SPPS:
        rows = res[spp]
        diffs = [a[0].astype(float) - b[0] for a, b in zip(rows, ref, strict=True)]
        rms = np.median([np.sqrt(np.mean(d**2)) for d in diffs])
        ridge = np.nanmedian([r[2] for r in rows])
        pairs = [(a[1], b[1]) for a, b in zip(rows, ref, strict=True) if b[1] > 0]
        d64 = np.median([abs(a - b) / b for a, b in pairs]) * 100
        err = np.median([abs(r[1] - r[3]) / r[3] for r in rows if r[3] > 0]) * 100
        print(f"{spp} | {rms:.2f} | {ridge:.3f} | {d64:.2f} % | {err:.2f} %")


if __name__ == "__main__":
    main()

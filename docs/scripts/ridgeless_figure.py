"""Make ``docs/ridgeless.jpg``: what the ridgeless augmentation does to a training frame.

Four contact frames of a rendered dataset (default ``data/v2_train``, the shipped recipe's
training set: ``models/MODEL_CARD.md``) go through the deployment preprocessing of the shipped
model's spec, then through :func:`contactcal.train.ridgeless.ridgeless` with ``p = 1`` (fixed
seed). Columns: frame channel as rendered, after erasure, ridge-energy channel as rendered,
after erasure (÷ 2 for display). A frame whose ridges are not visible (hard session) is left as
it is and keeps its label; the others become "no contact". Takes a few seconds.

    .venv/bin/python docs/scripts/ridgeless_figure.py [DATA_DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
import torch

from contactcal.infer.bench.dataset import read_datasets, sessions_of
from contactcal.infer.image.read import load_image
from contactcal.infer.image.write import write_image
from contactcal.infer.methods.unet.crop import crop_resize
from contactcal.infer.methods.unet.prepare import network_to_unit, prepare, session_reference
from contactcal.infer.methods.unet.runner import OnnxSegmenter
from contactcal.train.ridgeless import RidgelessConfig, ridgeless

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs/ridgeless.jpg"
PICKS = ((0, 4.0), (0, 10.0), (1, 10.0), (5, 10.0))  # (session index, kPa)


def _inputs(data: Path, config, channels: int) -> tuple[np.ndarray, np.ndarray]:
    """``(N, C, S, S)`` prepared frames and ``(N, 1, S, S)`` masks of :data:`PICKS`."""
    sessions = list(sessions_of(read_datasets([data])).values())
    xs, ms = [], []
    for index, kpa in PICKS:
        rows = sessions[index]
        ref = session_reference(load_image(rows[0].frame), config)
        row = next(r for r in rows if abs(r.pressure_kpa - kpa) < 1e-6)
        prep = prepare(load_image(row.frame), ref, config, channels)
        mask = load_image(row.mask) > 0
        xs.append(prep.x)
        ms.append(crop_resize(mask.astype(np.float32), prep.box, config.input_size) > 0.5)
    return np.stack(xs), np.stack(ms)[:, None].astype(np.float32)


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "data/v2_train"
    spec = OnnxSegmenter().spec
    cfg = spec.preprocess
    x, m = _inputs(data, cfg, spec.channels)
    xt, mt = torch.from_numpy(x), torch.from_numpy(m)
    u = torch.cat([network_to_unit(xt[:, :-1], cfg).clamp(0, 1), xt[:, -1:]], 1)
    gen = torch.Generator().manual_seed(0)
    out, m_out = ridgeless(u, mt, RidgelessConfig(p=1.0), gen, cfg.crop_factor)

    def grey(a: torch.Tensor) -> np.ndarray:
        return cv2.cvtColor((a.clamp(0, 1).numpy() * 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)

    rows = []
    for i in range(len(PICKS)):
        tiles = [grey(u[i, 0]), grey(out[i, 0]), grey(u[i, -1] / 2), grey(out[i, -1] / 2)]
        label = "no contact" if float(m_out[i].sum()) == 0 else "contact (ridges not visible)"
        cv2.putText(tiles[1], label, (4, 186), 0, 0.4, (0, 255, 255), 1)
        rows.append(np.hstack(tiles))
    sheet = np.vstack(rows)
    for k, name in enumerate(("frame", "erased", "ridge energy", "erased")):
        cv2.putText(sheet, name, (k * cfg.input_size + 4, 14), 0, 0.45, (255, 255, 255), 1)
    write_image(OUT, sheet, (cv2.IMWRITE_JPEG_QUALITY, 85))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()

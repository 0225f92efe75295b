"""Resolution chain check (docs/synth.md, "Resolution chain"): does the network see the same
ridges from a 400×300 training render as from a 2592×1944 rig frame decoded the way deployment
decodes it?

For a few nominal sessions and pressures the same frame is rendered three times (same session,
same seed): at 2592×1944 (saved as JPEG q90 like the rig's camera, decoded by ``contactcal`` at
the reduction deployment picks for the network input), and at 1296×972 and 400×300 (the two
sizes of training frames; PNG, shrunk by the factor deployment and training pick). Both go
through the one preprocessing (`prepare`) to the network input; the script prints, per input
size, the ridge contrast inside the contact (RMS of a band-pass at the ridge frequency, in network
units), and for the ridge-energy channel (192² input, measured at 288 px) its median inside the
eroded contact and on the membrane around it.

Run from the repository root (slow: one 5 MP render takes about a minute, a 1296×972 one ~8 s):
``python docs/scripts/resolution_chain.py [--sessions 2] [--spp 8] [--full-from DIR]``;
``--full-from`` reads the 2592×1944 frames of those sessions from a dataset rendered with
``contactcal synth --fingers 2 --pressures 0:20:5 --size 2592x1944 --spp 8 --seed 9000
--hard-fraction 0`` instead of rendering them again.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np

from contactcal.infer.image.gray import reduce_area
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import crop_resize
from contactcal.infer.methods.unet.prepare import prepare, session_reference
from contactcal.infer.methods.unet.shrink import deployed_shrink
from contactcal.synth.dataset import DatasetConfig
from contactcal.synth.dataset_finger import session_params
from contactcal.synth.session import RenderConfig, render_session

PRESSURES = (0.0, 10.0, 20.0)
FULL = (2592, 1944)
SMALL = (400, 300)
MID = (1296, 972)


def _ridge_contrast(x: np.ndarray, mask: np.ndarray) -> float:
    """RMS of a difference of Gaussians (σ 0.6 / 2 px) inside the eroded contact mask."""
    dog = cv2.GaussianBlur(x, (0, 0), 0.6) - cv2.GaussianBlur(x, (0, 0), 2.0)
    inner = cv2.erode(mask.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    return float(np.sqrt(np.mean(dog[inner] ** 2))) if inner.any() else float("nan")


def _ridge_channel(x: np.ndarray, mask: np.ndarray) -> str:
    """Median ridge energy inside the eroded contact / on the membrane ring around it."""
    m = mask.astype(np.uint8)
    inner = cv2.erode(m, np.ones((5, 5), np.uint8)) > 0
    around = (cv2.dilate(m, np.ones((25, 25), np.uint8)) > 0) & ~(
        cv2.dilate(m, np.ones((7, 7), np.uint8)) > 0
    )
    return f"{np.median(x[inner]):.2f} / {np.median(x[around]):.2f}"


def _network_views(frames, reduce: int, size: int, tmp: Path, tag: str, ridge: int = 0):
    """Save frames, decode, prepare; yield (kPa, x, mask) in network pixels.

    ``reduce`` > 0: JPEG q90 decoded at 1/reduce (the rig's frames). ``reduce`` 0: PNG decoded
    fully and shrunk by the factor deployment and training pick (``deployed_shrink``; the
    training renders)."""
    cfg = PreprocessConfig(input_size=size, ridge_work_px=ridge)
    suffix = ".jpg" if reduce else ".png"
    paths = []
    for f in frames:
        p = tmp / f"{tag}_{f.pressure_kpa:04.1f}{suffix}"
        cv2.imwrite(str(p), f.frame[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 90] if reduce else [])
        paths.append(p)
    k = deployed_shrink(load_image(paths[0]), cfg) if not reduce else 1

    def decoded(path: Path) -> np.ndarray:
        return load_image(path, reduce=reduce) if reduce else reduce_area(load_image(path), k)

    ref = session_reference(decoded(paths[0]), cfg)
    for f, p in zip(frames, paths, strict=True):
        gray = decoded(p)
        x = prepare(gray, ref, cfg, channels=1 + (ridge > 0)).x[-1]
        m = cv2.resize(f.mask.astype(np.float32), gray.shape[::-1], interpolation=cv2.INTER_AREA)
        yield f.pressure_kpa, x, crop_resize(m, ref.box, size) > 0.5


def _from_dataset(folder: Path, finger: int) -> list[SimpleNamespace]:
    """The session's frames at :data:`PRESSURES` from a dataset folder (RGB frame, bool mask)."""
    out = []
    for kpa in PRESSURES:
        name = f"p{kpa:04.1f}kpa.png"
        d = folder / f"finger_{finger:04d}"
        frame = cv2.imread(str(d / "frames" / name), cv2.IMREAD_COLOR)[:, :, ::-1]
        mask = cv2.imread(str(d / "masks" / name), cv2.IMREAD_GRAYSCALE) > 127
        out.append(SimpleNamespace(pressure_kpa=kpa, frame=frame, mask=mask))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sessions", type=int, default=2)
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--full-from", type=Path, default=None, help="dataset of the 2592 frames")
    args = ap.parse_args()
    data = DatasetConfig(fingers=args.sessions, pressures_kpa=PRESSURES, seed=9000, hard_fraction=0)
    print("| session | kPa | input | from | ridge contrast | ")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for finger in range(args.sessions):
            session = session_params(data, finger)
            renders = {}
            for size, weight in ((FULL, 2048), (MID, 1024), (SMALL, 1024)):
                if size == FULL and args.full_from is not None:
                    renders[size] = _from_dataset(args.full_from, finger)
                    continue
                rc = RenderConfig(*size, spp=args.spp, weight_size=weight)
                renders[size] = list(render_session(session, PRESSURES, rc, (9000, finger)))
            for net, reduce, ridge in ((192, 8, 0), (384, 4, 0), (192, 4, 288), (192, 8, 288)):
                full = _network_views(renders[FULL], reduce, net, Path(tmp), "f", ridge)
                mid = _network_views(renders[MID], 0, net, Path(tmp), "m", ridge)
                small = _network_views(renders[SMALL], 0, net, Path(tmp), "s", ridge)
                label = f"{net}²" + (f" ridge channel @{ridge}, 1/{reduce} decode" if ridge else "")
                named = (("2592×1944 JPEG", full), ("1296×972 PNG", mid), ("400×300 PNG", small))
                for name, views in named:
                    for kpa, x, m in views:
                        if kpa > 0:
                            c = _ridge_channel(x, m) if ridge else f"{_ridge_contrast(x, m):.3f}"
                            print(f"| {finger} | {kpa:g} | {label} | {name} | {c} |")


if __name__ == "__main__":
    main()

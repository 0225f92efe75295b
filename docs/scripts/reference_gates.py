"""Could a check against the reference frame veto the U-Net's false contacts? Three candidates.

A bright speck on the window near the centre is taken for contact before contact
(``models/MODEL_CARD.md``, "Limits"), although the session's zero-pressure frame shows the same
speck. Three post-processing vetoes suggest themselves, all measured here on the kept region of
the shipped model (``postprocess``'s ``mask_net``, network pixels) of every frame of a dataset:

* **ridge gain**: the ridge-energy channel's mean inside the region, frame over reference (the
  reference's channel computed the same way in the same crop). Contact brings ridges, a speck
  on the window is in both frames: a gain near 1 would mean "no new evidence".
* **similarity**: the correlation of the frame and reference channels inside the region. Contact
  changes the pattern, a speck leaves it: a correlation near 1 would mean "unchanged".
* **change**: the mean |frame channel − reference channel| inside the region, network input
  units (:func:`~contactcal.infer.methods.unet.postprocess.region_change`): contact changes the
  image where it happens. The deployed change gate (metadata ``min_change``,
  ``python -m contactcal.train.change_gate``) is this statistic; this script measures it with
  the shipped model's gate off.

``--speck LEVEL --draws N`` adds a window speck (``contactcal.infer.bench.perturb.speck``, the
robustness suite's, same speck in the frame and its reference) N times per session, each draw
its own place and size (``default_rng([seed, session, draw])``), so that the vetoes can be read on
validation frames that have the failure; without it the frames are measured as rendered. Prints,
for regions in frames with and without true contact, the range of each statistic and how many
false regions a threshold would remove at the price of how many true ones. Validation renders
only: a veto's threshold read on a test set would be tuned on it.

    .venv/bin/python docs/scripts/reference_gates.py data/val_r3 [--speck 0.2 --draws 3] \
        [--similarity 0.98]... [--seed 0]

``--similarity T`` (repeatable) also prints what a similarity veto at T would remove. The
frames above 0 kPa without contact are counted once per draw (53 frames × 3 draws = 159 on
``data/val_r3``).

``--no-reference`` asks the same of a session measured without its zero-pressure frame, where
the change gate cannot act: is the frame's own ridge evidence a veto? Two statistics of each
kept region (the model given its blank placeholder): **ridge level**, the ridge channel's mean
inside the region (~1 on ridges, ~0 on a smooth membrane), and **ridge contrast**, that mean
over the mean in the 4-network-pixel band just outside the region.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.bench.perturb import speck
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.crop import crop_resize
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.infer.methods.unet.prepare import _to_network, prepare
from contactcal.infer.methods.unet.ridge import ridge_energy
from contactcal.infer.methods.unet.ring import locate_ring

NAMES = ("ridge gain", "similarity", "change")


def region_stats(
    m: UnetMethod, frames: list[np.ndarray]
) -> list[tuple[float, float, float] | None]:
    """The three statistics in each frame's kept region, as the deployed method measures it.

    Args:
        m: the U-Net method (a 3-channel model: frame, reference, ridge energy).
        frames: one session's ``(H, W) uint8`` frames, ``frames[0]`` its reference (0 kPa).

    Returns:
        Per frame ``(ridge gain, similarity, change)`` (dimensionless; change in network input
        units), or None without a kept region.

    The reference's ridge channel is computed in each frame's crop (the session's, or the
    frame's own where the reference's window ring was not found, as ``prepare`` does).
    """
    spec = m.segmenter.spec
    cfg = spec.preprocess
    m.set_reference(frames[0])
    ref = m.reference
    out: list[tuple[float, float, float] | None] = []
    for gray in frames:
        img, _ = m._shrunk(gray)
        prep = prepare(img, ref, cfg, spec.channels)
        seg = postprocess(m.segmenter.probabilities(prep.x), prep.box, img.shape, spec)  # no gate
        ref_work = crop_resize(ref.gray, prep.box, cfg.ridge_work_px)
        ref_ridge = ridge_energy(ref_work, cfg, _to_network(ref.gray, prep.box, cfg)[1])
        keep = seg.mask_net
        if not seg.contact or keep.sum() < 3:
            out.append(None)
            continue
        gain = float(prep.x[-1][keep].mean() / max(ref_ridge[keep].mean(), 1e-6))
        sim = float(np.corrcoef(prep.x[0][keep], prep.x[1][keep])[0, 1])
        change = float(np.abs(prep.x[0][keep] - prep.x[1][keep]).mean())
        out.append((gain, sim, change))
    return out


def own_stats(m: UnetMethod, frames: list[np.ndarray]) -> list[tuple[float, float] | None]:
    """Per frame ``(ridge level, ridge contrast)`` of the kept region without a reference.

    Args:
        m: the U-Net method (a model with a ridge channel, last).
        frames: one session's ``(H, W) uint8`` frames (no reference is given to the method).

    Returns:
        Per frame the two statistics (dimensionless), or None without a kept region.
    """
    spec = m.segmenter.spec
    m.set_reference(None)
    out: list[tuple[float, float] | None] = []
    for gray in frames:
        img, _ = m._shrunk(gray)
        prep = prepare(img, m.reference, spec.preprocess, spec.channels)
        seg = postprocess(m.segmenter.probabilities(prep.x), prep.box, img.shape, spec)
        keep = seg.mask_net
        if not seg.contact or keep.sum() < 3:
            out.append(None)
            continue
        near = cv2.dilate(keep.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
        level = float(prep.x[-1][keep].mean())
        out.append((level, level / max(float(prep.x[-1][near & ~keep].mean()), 1e-6)))
    return out


def main() -> None:
    """Measure the dataset's kept regions and print each statistic's ranges and vetoes."""
    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("--speck", type=float, default=0.0, help="window speck level (0: none)")
    ap.add_argument("--draws", type=int, default=1, help="specks drawn per session")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-reference", action="store_true", help="the frames' own ridge evidence")
    ap.add_argument(
        "--similarity", type=float, action="append", default=[], help="also try this veto"
    )
    args = ap.parse_args()
    m = UnetMethod(change_gate=False)  # every kept region, as the statistics are about them
    true_regions, false_regions, frames_below = [], [], 0
    for s, rows in enumerate(sessions_of(read_index(args.data)).values()):
        rows = sorted(rows, key=lambda r: r.pressure_kpa)
        grays = [load_image(r.frame) for r in rows]
        ring = locate_ring(grays[0], m.segmenter.spec.preprocess)
        for d in range(args.draws if args.speck > 0 else 1):
            seed = [args.seed, s, d]
            frames = [speck(g, args.speck, np.random.default_rng(seed), ring=ring) for g in grays]
            stats = own_stats(m, frames) if args.no_reference else region_stats(m, frames)
            for r, st in zip(rows, stats, strict=True):
                frames_below += not r.contact and r.pressure_kpa > 0
                if st is not None and r.contact:
                    true_regions.append(st)
                elif st is not None and r.pressure_kpa > 0:  # 0 kPa: the reference itself
                    false_regions.append(st)
    print(
        f"{len(true_regions)} regions in contact frames; {len(false_regions)} regions in the "
        f"{frames_below} frames above 0 kPa without contact (false contacts)"
    )
    names = ("ridge level", "ridge contrast") if args.no_reference else NAMES
    for k, name in enumerate(names):
        t = np.array([x[k] for x in true_regions])
        f = np.array([x[k] for x in false_regions])
        span = {
            a: f"{v.min():.3f}-{v.max():.3f}" if v.size else "none" for a, v in (("t", t), ("f", f))
        }
        print(f"{name}: true {span['t']}, false {span['f']}")
        tries = list(np.quantile(f, [0.25, 0.5, 0.75])) if f.size else []
        if name == "similarity":
            tries += args.similarity
        for q in tries:
            veto = (lambda x, q=q: x >= q) if name == "similarity" else (lambda x, q=q: x <= q)
            print(
                f"  veto at {q:.3f}: removes {int(veto(f).sum())} false, "
                f"{int(veto(t).sum())} true regions"
            )


if __name__ == "__main__":
    main()

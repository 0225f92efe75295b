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
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.bench.perturb import speck
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.methods.unet.postprocess import postprocess
from contactcal.infer.methods.unet.prepare import _to_network, crop_resize, prepare
from contactcal.infer.methods.unet.ridge import ridge_energy
from contactcal.infer.methods.unet.ring import locate_ring


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


def main() -> None:
    """Measure the dataset's kept regions and print each statistic's ranges and vetoes."""
    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("--speck", type=float, default=0.0, help="window speck level (0: none)")
    ap.add_argument("--draws", type=int, default=1, help="specks drawn per session")
    ap.add_argument("--seed", type=int, default=0)
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
            for r, st in zip(rows, region_stats(m, frames), strict=True):
                frames_below += not r.contact and r.pressure_kpa > 0
                if st is not None and r.contact:
                    true_regions.append(st)
                elif st is not None and r.pressure_kpa > 0:  # 0 kPa: the reference itself
                    false_regions.append(st)
    print(
        f"{len(true_regions)} regions in contact frames; {len(false_regions)} regions in the "
        f"{frames_below} frames above 0 kPa without contact (false contacts)"
    )
    for k, name in enumerate(("ridge gain", "similarity", "change")):
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
            veto = (lambda x, q=q: x >= q) if k == 1 else (lambda x, q=q: x <= q)
            print(
                f"  veto at {q:.3f}: removes {int(veto(f).sum())} false, "
                f"{int(veto(t).sum())} true regions"
            )


if __name__ == "__main__":
    main()

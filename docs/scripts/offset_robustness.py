"""Is a perturbation's extra error a boundary shift that a rig's measured offset absorbs?

A rig images every session with the same contrast, tone curve and focus. Where one of the
robustness suite's perturbations (``contactcal.infer.bench.perturb``) raises the U-Net's error, it
may do so by moving the region's edge by about the same amount on every frame: then the offset
that ``contactcal evaluate`` measures on a few labelled frames of that rig corrects it. For each
``--perturb NAME=LEVEL`` (and none), every frame of ``--data`` is perturbed (its reference as
the robustness suite does: identically seeded) and measured; the sessions are split in two
halves (even / odd session index); ``--draws`` times, ``--labelled`` frames in contact are drawn
from one half, the offset ``contactcal evaluate`` would give from them (none when its 90 %
interval includes 0) applied to the other half's frames, and the median |area
error| at ≥ 5 kPa taken; and the other way round. Printed per perturbation: the pooled offset,
and per half its error without offset → with the other half's (median and 5-95 % over draws).

    .venv/bin/python docs/scripts/offset_robustness.py --data data/v2_check_r2_17100 \\
        --perturb contrast=0.75 gamma=1.4 blur=12
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from offset_transfer import AREA, MMPX, PERIM, SESSION, TRUE, P, error_at, offsets_mm

from contactcal.infer.bench import perturb
from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.evaluate.offset import resolved_offset
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.registry import make_method


def measure(folder: Path, name: str | None, level: float, seed: int) -> np.ndarray:
    """``(F, 8)`` per frame of ``folder`` in ``offset_transfer``'s columns (interval ends not
    kept: NaN), each frame and its reference perturbed alike."""
    method = make_method("unet")
    fn = getattr(perturb, name) if name else None

    def look(path: Path, k: int) -> np.ndarray:
        """Frame ``path`` of session ``k``, perturbed with the session's seed (as its reference)."""
        gray = load_image(path)
        return fn(gray, level, np.random.default_rng([seed, k])) if fn else gray

    out = []
    for k, rows in enumerate(sessions_of(read_index(folder)).values()):
        method.set_reference(look(rows[0].frame, k))
        for row in rows:
            r = method.measure(look(row.frame, k))
            frame = np.full(8, np.nan)
            frame[[P, TRUE, AREA, MMPX, SESSION]] = (
                row.pressure_kpa,
                row.area_px,
                r.area_px,
                row.mm_per_px,
                k,
            )
            frame[PERIM] = r.perimeter_px if r.contact and r.perimeter_px else 0.0
            out.append(frame)
    return np.array(out, dtype=float)


def transfer(f: np.ndarray, half: int, labelled: int, draws: int, seed: int) -> np.ndarray:
    """Errors (%) of session half ``half`` with offsets drawn from the other half's frames."""
    rng = np.random.default_rng([seed, half])
    pool, apply = offsets_mm(f[f[:, SESSION] % 2 != half]), f[f[:, SESSION] % 2 == half]
    picks = [resolved_offset(rng.choice(pool, labelled, replace=False)) for _ in range(draws)]
    return np.array([error_at(apply, d) for d in picks])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True, help="a rendered held-out dataset")
    ap.add_argument("--perturb", nargs="+", default=[], metavar="NAME=LEVEL")
    ap.add_argument("--labelled", type=int, default=10, help="frames a lab labels (default 10)")
    ap.add_argument("--draws", type=int, default=100, help="draws per half (default 100)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(
        "| perturbation | pooled offset | ≥ 5 kPa, even sessions: without → with the odd ones' "
        "offset, median (5-95 %) | odd sessions: without → with the even ones' |"
    )
    print("|---|---|---|---|")
    for spec in ["none=0", *args.perturb]:
        name, level = spec.split("=")
        f = measure(args.data, None if name == "none" else name, float(level), args.seed)
        cells = []
        for half in (0, 1):
            q = np.percentile(transfer(f, half, args.labelled, args.draws, args.seed), (5, 50, 95))
            base = error_at(f[f[:, SESSION] % 2 == half], 0.0)
            cells.append(f"{base:.2f} → {q[1]:.2f} % ({q[0]:.2f}-{q[2]:.2f})")
        print(f"| {spec} | {np.median(offsets_mm(f)):+.3f} mm | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    main()

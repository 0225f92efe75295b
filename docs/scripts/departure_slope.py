"""Does the U-Net's edge follow the inner ring? Re-render sessions with the membrane leaving the
contact edge at a slope, and measure where the ring and the shipped model's region go.

Our reduced membrane leaves the contact plateau with zero slope (``ContactState.membrane_z``: a
clamped annulus), so the inner ring (the LGP's reflex in the membrane) lies where the annulus has
steepened, ~0.6 mm outside the contact edge (``docs/fidelity.md``). The rig paper sees the
ring's inner edge *at* the contact edge ("the growing fingerprint region was delimited by an
inner ring with an increasingly sharp edge"), as a membrane leaving a curved fingertip at the
finger's own slope would. This script renders chosen sessions of a dataset again, in this
process, with every session's ``MembraneParams.departure_slope`` set to ``--slope`` (0: as they
were, for a set rendered without ``--departure-fraction``), everything else (seeds, finger,
camera, masks) unchanged, so that two runs give paired sets. ``contactcal synth
--departure-fraction`` draws the slope per session instead.

    .venv/bin/python docs/scripts/departure_slope.py --data data/v3_hires2 --fingers 0 3 1 \\
        --pressures 0 4 6 8 10 12 14 16 18 20 --slope 0.15 --out out/departure/s0.15

Then ``docs/scripts/ring_gap.py`` measures the ring and the methods on the re-rendered sets.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict, replace
from pathlib import Path

from contactcal.synth import dataset, dataset_finger
from contactcal.synth.dataset import DatasetConfig, write_index
from contactcal.synth.dataset_finger import render_finger
from contactcal.synth.randomize import SessionParams


def with_slope(slope: float) -> None:
    """Make ``dataset_finger.session_params`` give every session ``slope`` (dz/dr) as its
    departure."""
    drawn = dataset_finger.session_params

    def session_params(config: DatasetConfig, finger: int) -> SessionParams:
        p = drawn(config, finger)
        return replace(p, membrane=replace(p.membrane, departure_slope=slope))

    dataset_finger.session_params = session_params


def main() -> None:
    """Render the chosen fingers of ``--data`` again into ``--out`` with the departure slope."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, required=True, help="a `contactcal synth` dataset")
    ap.add_argument("--fingers", type=int, nargs="+", required=True)
    ap.add_argument("--pressures", type=float, nargs="+", required=True, help="kPa")
    ap.add_argument("--slope", type=float, required=True, help="dz/dr at the contact edge")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    raw = json.loads((args.data / "config.json").read_text())
    if raw.get("synth_revision") != dataset.SYNTH_REVISION:
        raise SystemExit(f"{args.data}: synth revision {raw.get('synth_revision')} is not this one")
    render = dataset.RenderConfig(**raw.pop("render"))
    raw.pop("synth_revision")
    config = DatasetConfig(**{**raw, "pressures_kpa": tuple(raw["pressures_kpa"])}, render=render)
    config = replace(config, pressures_kpa=tuple(sorted(args.pressures)))
    with_slope(args.slope)
    args.out.mkdir(parents=True, exist_ok=False)
    record = {**asdict(config), "departure_slope": args.slope, "source": str(args.data)}
    (args.out / "config.json").write_text(json.dumps(record, indent=2))
    for f in args.fingers:
        render_finger(str(args.out), config, f)
    write_index(args.out)


if __name__ == "__main__":
    main()

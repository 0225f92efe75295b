"""Area vs pressure for the reference users: writes docs/mechanics_curves.png.

Run from the repository root: ``python docs/scripts/mechanics_figure.py``.
"""

import csv
from pathlib import Path

import numpy as np

from contactcal.synth.mechanics import equilibrium_area_mm2, solve_contact, tension_for_onset
from contactcal.synth.mechanics_params import FingerParams, MembraneParams

USERS = {"user1": (9.0, 0.013, 0.9), "user2": (7.75, 0.020, 0.7), "user3": (9.0, 0.019, 0.5)}
ROOT = Path(__file__).resolve().parents[2]
CSV = ROOT.parent / "shared" / "reference" / "fingertip_contact_area.csv"
MEMBRANE = MembraneParams(
    clamp_radius_mm=12.5,
    tension_n_per_mm=tension_for_onset(3.0, 1.5, 12.5),
    gap_mm=1.5,
    onset_ramp_kpa=0.75,
)


def reference_finger(r: float, e0: float, beta: float) -> FingerParams:
    """A centred, untilted 16 x 23 mm pad with one user's Hertz parameters."""
    return FingerParams(
        width_mm=16.0,
        length_mm=23.0,
        radius_mm=r,
        e0_mpa=e0,
        beta_per_n=beta,
        aspect=1.35,
        offset_mm=(0.0, 0.0),
        yaw_rad=0.0,
        tilt_rad=0.0,
    )


def plot(out: Path) -> None:
    """Draw the model, its Hertz fixed point and the PLA force data per user; save to ``out``."""
    import matplotlib.pyplot as plt

    m = MEMBRANE
    lines = [line for line in CSV.read_text().splitlines() if not line.startswith("#")]
    rows = [r for r in csv.DictReader(lines) if r["surface"] == "pla"]
    ps = np.linspace(0, 20, 401)
    fig, ax = plt.subplots(figsize=(10, 4.5), dpi=120)
    for (user, (r, e0, beta)), col in zip(USERS.items(), ["C0", "C1", "C2"], strict=False):
        f = reference_finger(r, e0, beta)
        ax.plot(
            ps,
            [solve_contact(p, f, m).area_mm2 for p in ps],
            col,
            label=f"{user}: model (W=16, L=23 mm)",
        )
        ax.plot(
            ps,
            [equilibrium_area_mm2(p, f) for p in ps],
            col + "--",
            lw=0.8,
            label=f"{user}: Hertz fixed point A=A_h(pA), no ramp/saturation",
        )
        pts = [
            (1000 * float(q["force_n"]) / float(q["area_mm2"]), float(q["area_mm2"]))
            for q in rows
            if q["user"] == user
        ]
        ax.plot(
            *zip(*pts, strict=False),
            col + "o",
            ms=5,
            mfc="none",
            label=f"{user}: rigid-surface force data (PLA) at F/A",
        )
    ax.axvline(3.0, color="grey", lw=0.6, ls=":")
    ax.text(3.2, 205, "onset 3 kPa", color="grey", fontsize=8)
    ax.set_xlabel("inflation pressure p (kPa)   [data: mean contact pressure F/A]")
    ax.set_ylabel("contact area (mm²)")
    ax.set_xlim(0, 29)
    ax.set_ylim(0, 220)
    ax.set_title(
        "Reduced membrane contact model (a=12.5 mm, gap 1.5 mm, tau 0.75 kPa, aspect 1.35)",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


if __name__ == "__main__":
    import matplotlib

    matplotlib.use("Agg")
    plot(ROOT / "docs" / "mechanics_curves.png")

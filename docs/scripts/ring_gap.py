"""Where is the inner ring against the contact edge, and where does the U-Net put the edge?

For each dataset given (e.g. the ``--slope 0`` and ``--slope 0.5`` renders of
``docs/scripts/departure_slope.py``, or a procedural set), per frame in contact at ≥ 5 kPa:

* **ring peak**: the mean grey level as a function of the signed distance from the true contact
  edge (exact mask; 0.02 mm bins, outside > 0), and the distance of its maximum within
  0-3 mm outside the edge, mm (the brightest band around the patch: the inner ring);
* **U-Net offset**: the outward move of the U-Net's region (the shipped model, or ``--model``)
  that gives the true area (Steiner, ``docs/scripts/offset_transfer.py``), mm; < 0: the region
  lies inside the contact;
* the U-Net's and the classical routine's median |relative area error|.

Prints one line per dataset (medians over its frames), and with ``--sessions`` one per session
with its membrane's departure slope (``session.json``). Report only: nothing is chosen on it.

    .venv/bin/python docs/scripts/ring_gap.py out/departure/s0 out/departure/s0.5 [--sessions] \
        [--model M.onnx]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from offset_transfer import MMPX, SESSION, TRUE, P, error_at, measure_dataset, offsets_mm

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.registry import make_method
from contactcal.infer.pipeline.measure import measure_files

BIN_MM = 0.02  # width of a distance bin
SEARCH_MM = 3.0  # the ring peak is searched this far outside the edge


def ring_peak_mm(gray: np.ndarray, mask: np.ndarray, mm_per_px: float) -> float:
    """Distance (mm) outside the contact edge of the brightest band within :data:`SEARCH_MM`.

    Args:
        gray: ``(H, W) uint8`` frame.
        mask: ``(H, W) bool`` exact contact mask (non-empty).
        mm_per_px: scale at the contact plane.
    """
    m = mask.astype(np.uint8)
    outside = cv2.distanceTransform(1 - m, cv2.DIST_L2, 5) * mm_per_px
    sel = (outside > 0) & (outside <= SEARCH_MM)
    bins = (outside[sel] / BIN_MM).astype(int)
    sums = np.bincount(bins, weights=gray[sel].astype(float))
    counts = np.bincount(bins)
    profile = sums / np.maximum(counts, 1)
    profile[counts < 20] = 0.0  # too few pixels to say
    return float((np.argmax(profile) + 0.5) * BIN_MM)


def classical_errors(folder: Path) -> list[list[float]]:
    """Per session (``sessions_of`` order), the classical routine's |relative area error| of its
    frames in contact at ≥ 5 kPa (each session's 0 kPa frame its reference, as in ``bench``)."""
    method, out = make_method("classical"), []
    for rows in sessions_of(read_index(folder)).values():
        measured = measure_files([r.frame for r in rows], method, rows[0].frame)
        errs = [
            abs(m.result.area_px - r.area_px) / r.area_px
            for r, m in zip(rows, measured, strict=True)
            if r.pressure_kpa >= 5 and r.contact
        ]
        out.append(errs)
    return out


def departure_slope(session_folder: Path) -> float:
    """The session's departure slope dz/dr.

    From ``membrane.departure_slope`` in its ``session.json``; where that lacks it, from the
    dataset's ``config.json`` (``departure_slope.py`` re-renders record it there); else 0.
    """
    info = json.loads((session_folder / "session.json").read_text())
    if "departure_slope" in info["membrane"]:
        return float(info["membrane"]["departure_slope"])
    config = session_folder.parent / "config.json"
    if not config.is_file():
        return 0.0
    return float(json.loads(config.read_text()).get("departure_slope", 0.0))


def _line(label: str, peaks: list[float], f: np.ndarray, classical: list[float]) -> str:
    d = offsets_mm(f)
    return (
        f"{label}: {len(f)} frames ≥ 5 kPa; ring peak {np.median(peaks):.2f} mm outside the edge "
        f"({np.min(peaks):.2f}-{np.max(peaks):.2f}); U-Net offset {np.median(d):+.3f} mm "
        f"({np.min(d):+.3f} to {np.max(d):+.3f}); |error| U-Net {error_at(f, 0.0):.1f} %, "
        f"classical {100 * np.median(classical):.1f} % (mm/px {np.median(f[:, MMPX]):.4f})"
    )


def main() -> None:
    """One line per dataset (and with ``--sessions`` per session, with its departure slope)."""
    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path, nargs="+")
    ap.add_argument("--sessions", action="store_true", help="also one line per session")
    ap.add_argument("--model", type=Path, help="U-Net model (default: the shipped one)")
    args = ap.parse_args()
    for folder in args.data:
        sessions = list(sessions_of(read_index(folder)).values())
        peaks = [
            [
                ring_peak_mm(load_image(r.frame), load_image(r.mask) > 127, r.mm_per_px)
                for r in rows
                if r.pressure_kpa >= 5 and r.contact
            ]
            for rows in sessions
        ]
        f = measure_dataset(folder, args.model)
        f = f[(f[:, P] >= 5) & (f[:, TRUE] > 0)]
        classical = classical_errors(folder)
        flat = [x for c in classical for x in c]
        print(_line(str(folder), [x for p in peaks for x in p], f, flat))
        for k, rows in enumerate(sessions if args.sessions else []):
            slope = departure_slope(rows[0].frame.parent.parent)
            label = f"  {rows[0].session} (slope {slope:.2f})"
            print(_line(label, peaks[k], f[f[:, SESSION] == k], classical[k]))


if __name__ == "__main__":
    main()

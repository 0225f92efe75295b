"""Render nominal sessions and summarise them against the paper (``contactcal fidelity``).

Sessions are drawn exactly as ``contactcal synth --hard-fraction 0`` draws them (same seeds),
rendered in a pool of worker processes (Mitsuba leaks across loads; one scene per session),
measured by :func:`fidelity.measure_session`, and summarised per pressure bin beside the paper's
trend (docs/fidelity.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from contactcal.infer.methods.classical import ClassicalConfig, find_roi, measure_classical
from contactcal.synth.dataset import DatasetConfig
from contactcal.synth.dataset_finger import session_params
from contactcal.synth.fidelity import SessionFidelity, measure_session
from contactcal.synth.session import FrameOutput, RenderConfig, render_session

__all__ = ["FidelityConfig", "run_fidelity", "session_strip", "summarise", "summary_markdown"]

PAPER_BINS = ((0.0, 1.0), (1.0, 3.0), (3.0, 5.0), (5.0, 10.0), (10.0, 15.0), (15.0, 20.0))


@dataclass(frozen=True)
class FidelityConfig:
    """What to render for a fidelity check."""

    sessions: int = 12  # nominal sessions; the check wants >= 10
    pressures_kpa: tuple[float, ...] = (0, 1, 2, 3, 4, 5, 7.5, 10, 12.5, 15, 17.5, 20)
    seed: int = 9000  # dataset seed (sessions as `synth --seed` with --hard-fraction 0)
    render: RenderConfig = RenderConfig(width=400, height=300, spp=8)  # noqa: RUF009 (frozen)
    #   8 spp: the camera model adds sensor noise anyway
    workers: int = 1  # processes


def _one(task: tuple[FidelityConfig, int]) -> tuple[SessionFidelity, np.ndarray | None]:
    config, finger = task
    data = DatasetConfig(
        fingers=config.sessions,
        pressures_kpa=config.pressures_kpa,
        seed=config.seed,
        hard_fraction=0.0,
        render=config.render,
    )
    session = session_params(data, finger)
    frames = list(
        render_session(session, config.pressures_kpa, config.render, (config.seed, finger))
    )
    strip = session_strip(frames, ClassicalConfig()) if finger == 0 else None
    return measure_session(session, frames), strip


def run_fidelity(config: FidelityConfig) -> list[tuple[SessionFidelity, np.ndarray | None]]:
    """Render and measure ``config.sessions`` nominal sessions (0 kPa must be first).

    Returns:
        Per session its measurements and, for the first session only, its
        :func:`session_strip` (``(H, W * P, 3) uint8``; None for the others).
    """
    if not config.pressures_kpa or config.pressures_kpa[0] != 0.0:
        raise ValueError("fidelity: the pressures must start at 0 kPa (the ROI's frame)")
    tasks = [(config, k) for k in range(config.sessions)]
    if config.workers <= 1:
        return [_one(t) for t in tasks]
    with ProcessPoolExecutor(config.workers, max_tasks_per_child=1) as pool:
        return list(pool.map(_one, tasks))


def _bin_values(results: Sequence[SessionFidelity], lo: float, hi: float, field: str) -> list:
    out = []
    for r in results:
        for p, v in zip(r.pressures_kpa, getattr(r, field), strict=True):
            if lo <= p <= hi if lo == 0.0 else lo < p <= hi:
                out.append(v)
    return out


def summarise(results: Sequence[SessionFidelity]) -> dict[str, object]:
    """Summary numbers of the fidelity check (JSON-ready; None where nothing was measured)."""
    n = len(results)
    bins = []
    for lo, hi in PAPER_BINS:
        errs = [e for e in _bin_values(results, lo, hi, "classical_error") if e is not None]
        inside = [v for v in _bin_values(results, lo, hi, "patch_in_roi") if v is not None]
        encl = [v for v in _bin_values(results, lo, hi, "blob_encloses") if v is not None]
        false = [v for v in _bin_values(results, lo, hi, "false_contact") if v is not None]
        bins.append(
            {
                "bin_kpa": [lo, hi],
                "frames_with_contact": len(errs),
                "median_error_pct": float(np.median(errs) * 100) if errs else None,
                "q25_error_pct": float(np.percentile(errs, 25) * 100) if errs else None,
                "q75_error_pct": float(np.percentile(errs, 75) * 100) if errs else None,
                "over_30pct": int(sum(abs(e) > 0.30 for e in errs)),
                "patch_in_roi_min": float(min(inside)) if inside else None,
                "blob_encloses_share": float(np.mean(encl)) if encl else None,
                "frames_without_contact": len(false),
                "routine_reports_contact": int(sum(false)),
            }
        )
    high = [_session_high(r) for r in results]
    return {
        "sessions": n,
        "roi_ok": int(sum(r.roi_ok for r in results)),
        "bright_in_ring_min": float(min(r.bright_in_ring for r in results)),
        "sessions_over_30pct_at_15_20": int(sum(h is not None and abs(h) > 0.30 for h in high)),
        "bins": bins,
        "sessions_detail": [asdict(r) | {"roi_ok": r.roi_ok} for r in results],
    }


def _session_high(r: SessionFidelity) -> float | None:
    """A session's median routine error at 15-20 kPa."""
    e = [v for p, v in zip(r.pressures_kpa, r.classical_error, strict=True) if p >= 15.0]
    e = [v for v in e if v is not None]
    return float(np.median(e)) if e else None


def summary_markdown(summary: dict[str, object]) -> str:
    """The per-bin table of docs/fidelity.md."""
    rows = [
        "| pressure (kPa) | frames with contact | routine median error | IQR | off by > 30 % "
        "| patch in ROI (min) | blob encloses contact | no contact, routine says contact |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for b in summary["bins"]:  # type: ignore[union-attr]
        lo, hi = b["bin_kpa"]

        def pct(v: float | None) -> str:
            return "—" if v is None or math.isnan(v) else f"{v:+.1f} %"

        iqr = (
            "—"
            if b["q25_error_pct"] is None
            else f"{b['q25_error_pct']:+.0f} … {b['q75_error_pct']:+.0f} %"
        )
        inside = "—" if b["patch_in_roi_min"] is None else f"{b['patch_in_roi_min']:.3f}"
        encl = "—" if b["blob_encloses_share"] is None else f"{b['blob_encloses_share']:.0%}"
        rows.append(
            f"| {lo:g}–{hi:g} | {b['frames_with_contact']} | {pct(b['median_error_pct'])} "
            f"| {iqr} | {b['over_30pct']} | {inside} | {encl} "
            f"| {b['routine_reports_contact']} of {b['frames_without_contact']} |"
        )
    rows.append("")
    rows.append(
        "Bins are (lo, hi] kPa, the first [0, 1]: a frame at 5 kPa is in 3–5 (as the paper's "
        "steps)."
    )
    return "\n".join(rows) + "\n"


def session_strip(frames: Sequence[FrameOutput], config: ClassicalConfig) -> np.ndarray:
    """Frames side by side with the truth (green) and the published routine's ellipse (blue).

    Returns:
        ``(H, W * len(frames), 3) uint8`` RGB, each frame labelled with its pressure.
    """
    roi = find_roi(frames[0].frame, config)
    tiles = []
    for f in frames:
        tile = np.ascontiguousarray(f.frame.copy())
        contours, _ = cv2.findContours(
            f.mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE
        )
        cv2.drawContours(tile, contours, -1, (0, 230, 0), 1)
        if roi is not None:
            res = measure_classical(f.frame, roi, config)
            if res.ellipse is not None:
                cv2.ellipse(tile, res.ellipse, (60, 120, 255), 1)
            cv2.circle(tile, (round(roi.cx), round(roi.cy)), round(roi.radius), (255, 200, 0), 1)
        label = f"{f.pressure_kpa:g} kPa"
        cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
        tiles.append(tile)
    return np.hstack(tiles)

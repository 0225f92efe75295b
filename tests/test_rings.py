"""The session rule: a region that shrinks beyond its interval at the next pressure: no contact."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from contactcal.infer.bench.accuracy import session_ruled
from contactcal.infer.bench.scoring import SESSION_SUFFIX, ScoredFrame
from contactcal.infer.calibration.calibrate import SessionOptions, calibrate_session
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.rings import (
    BELOW_NOTE,
    NO_RANGE_NOTE,
    frame_revisions,
    revise_points,
    session_revisions,
    shrinking_steps,
)
from contactcal.infer.errors import RunError
from contactcal.infer.image.read import ImageFile
from contactcal.infer.methods import registry
from contactcal.infer.methods.base import AreaResult, Started

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
NAN = float("nan")
# A pre-contact ring at 1-2 kPa (its disc shrinks), contact from 3 kPa (it grows): px, ±5 %.
P = np.arange(0.0, 8.0)
AREA = np.array([0.0, 900.0, 600.0, 100.0, 200.0, 300.0, 400.0, 500.0])
LOWER, UPPER = np.where(AREA > 0, 0.95 * AREA, NAN), np.where(AREA > 0, 1.05 * AREA, NAN)


def test_shrinking_steps_reference_values() -> None:
    hit = shrinking_steps(P, AREA, LOWER, UPPER, AREA > 0)
    assert hit.tolist() == [False, True, True, False, False, False, False, False]
    # the same steps in another order: the same steps are revised
    perm = np.random.default_rng(0).permutation(P.size)
    again = shrinking_steps(P[perm], AREA[perm], LOWER[perm], UPPER[perm], (AREA > 0)[perm])
    assert again.tolist() == hit[perm].tolist()


def test_a_decrease_within_the_intervals_is_kept() -> None:
    area = np.array([100.0, 95.0, 120.0])  # noise: 100 ± 5 % overlaps 95 ± 5 %
    hit = shrinking_steps([3.0, 4.0, 5.0], area, 0.95 * area, 1.05 * area, [True] * 3)
    assert not hit.any()


def test_no_interval_no_revision() -> None:
    nan = np.full(P.size, NAN)
    assert not shrinking_steps(P, AREA, nan, nan, AREA > 0).any()
    # the next contact step states no interval: nothing to compare with
    upper = UPPER.copy()
    upper[3] = NAN
    assert shrinking_steps(P, AREA, LOWER, upper, AREA > 0).tolist()[2] is False


def test_the_next_step_in_contact_is_the_comparison() -> None:
    # 2 kPa is not in contact: 1 kPa is compared with 3 kPa (contact, much smaller)
    contact = AREA > 0
    contact[2] = False
    assert shrinking_steps(P, AREA, LOWER, UPPER, contact).tolist()[1] is True


def test_a_slowly_shrinking_ring_is_revised_whole() -> None:
    # 650 → 620 → 600 px: each step within the next one's interval, then the drop to contact
    area = np.array([0.0, 650.0, 620.0, 600.0, 100.0, 200.0, 300.0])
    p = np.arange(area.size, dtype=float)
    hit = shrinking_steps(p, area, 0.95 * area, 1.05 * area, area > 0)
    assert hit.tolist() == [False, True, True, True, False, False, False]


def test_a_dip_inside_the_contact_range_is_left_as_measured() -> None:
    # an under-segmented frame at 7 kPa: steps 1-2 flag 6 kPa (larger) only, not the growing
    # curve below it, and the whole rule keeps it: it lies inside the contact range (3 kPa on)
    area = np.array([0.0, 0.0, 0.0, 100.0, 200.0, 300.0, 400.0, 50.0, 500.0, 600.0])
    p = np.arange(area.size, dtype=float)
    hit = shrinking_steps(p, area, 0.95 * area, 1.05 * area, area > 0)
    assert np.flatnonzero(hit).tolist() == [6]
    ring, below = session_revisions(p, area, 0.95 * area, 1.05 * area, area > 0)
    assert not ring.any() and not below.any()
    # the same drop below a shorter contact run is a ring's: the steps below it are revised too
    early = np.array([0.0, 300.0, 400.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0])
    ring, below = session_revisions(p, early, 0.95 * early, 1.05 * early, early > 0)
    assert np.flatnonzero(ring).tolist() == [2] and np.flatnonzero(below).tolist() == [1]


def test_a_contact_lost_at_high_pressure_is_not_taken_for_a_ring() -> None:
    # the areas fall to the end (the method loses the contact): no regrowth, nothing revised
    area = np.array([0.0, 0.0, 0.0, 300.0, 500.0, 600.0, 400.0, 200.0, 100.0, 50.0])
    p = np.arange(area.size, dtype=float)
    assert not shrinking_steps(p, area, 0.95 * area, 1.05 * area, area > 0).any()


@pytest.mark.parametrize(
    ("p", "lo"),
    [([0.0, 1.0], [1.0]), ([1.0, 1.0], [1.0, 2.0]), ([0.0, np.inf], [1.0, 2.0])],
)
def test_bad_input_is_rejected(p: list[float], lo: list[float]) -> None:
    with pytest.raises(ValueError, match="shrinking_steps"):
        shrinking_steps(p, lo, lo, [3.0] * len(lo), [True] * len(lo))


def test_session_revisions_drops_contacts_left_below_the_range() -> None:
    area = AREA.copy()
    area[0] = 50.0  # a speck at 0 kPa: nothing lies below it, it grows into the ring
    lo, hi = 0.95 * area, 1.05 * area
    ring, below = session_revisions(P, area, lo, hi, area > 0)
    assert ring.tolist()[:3] == [False, True, True]
    assert below.tolist() == [True] + [False] * 7  # left alone below the revised ring
    assert not (ring & below).any()


def _points(
    p: Sequence[float], areas: Sequence[float], *, repeats: int = 2, phase: str = "loading"
):
    return [
        CalibrationPoint(
            f"{phase}_{i}_{r}.png",
            float(pk),
            a > 0,
            float(a),
            float(a) * 0.01,
            phase=phase,
            step=i,
            area_interval_px=(0.95 * a, 1.05 * a) if a > 0 else (0.0, 0.0),
            area_interval_mm2=(0.0095 * a, 0.0105 * a) if a > 0 else (0.0, 0.0),
        )
        for i, (pk, a) in enumerate(zip(p, areas, strict=True))
        for r in range(repeats)
    ]


def test_revise_points_per_step_and_phase() -> None:
    up = _points(P, AREA)
    # unloading: the same pressures, no ring (grows from 3 kPa); listed downwards
    down_area = np.where(P >= 3, AREA, 0.0)[::-1]
    down = _points(P[::-1], down_area, phase="unloading")
    pts = up + down
    out = revise_points(pts)
    assert len(out) == len(pts)
    for before, after in zip(pts, out, strict=True):
        ring = before.phase == "loading" and before.pressure_kpa in (1.0, 2.0)
        assert after.contact == (before.contact and not ring)
        if ring:
            assert after.area_px == 0.0 and after.area_mm2 == 0.0
            assert after.area_interval_px == (0.0, before.area_interval_px[1])
            assert after.area_interval_mm2 == (0.0, before.area_interval_mm2[1])
            assert "not the contact" in after.note
            assert f"{before.area_px:.0f} px" in after.note
        else:
            assert after is before


def test_frame_revisions_pools_a_step() -> None:
    # two frames per pressure, one of the ring frames missed: the step is still the ring's
    p = np.repeat(P, 2)
    area = np.repeat(AREA, 2)
    contact = area > 0
    contact[2] = False  # one 1 kPa frame without contact (its area 0)
    area[2] = 0.0
    ivs = [(0.95 * a, 1.05 * a) if c else None for a, c in zip(area, contact, strict=True)]
    ring, below = frame_revisions(p, area, contact, ivs)
    assert np.flatnonzero(ring).tolist() == [3, 4, 5]  # the contact frames at 1 and 2 kPa
    assert not below.any()
    assert not any(frame_revisions(p, area, contact, [None] * p.size)[0])


def test_revise_points_leaves_methods_without_intervals_alone() -> None:
    pts = [
        CalibrationPoint(f"{i}.png", float(p), a > 0, float(a), None, step=i)
        for i, (p, a) in enumerate(zip(P, AREA, strict=True))
    ]
    assert revise_points(pts) == pts


def test_revise_points_notes_a_contact_below_the_range() -> None:
    area = AREA.copy()
    area[0] = 50.0
    out = revise_points(_points(P, area, repeats=1))
    assert out[0].contact is False
    assert out[0].note == BELOW_NOTE.format(area=50.0)
    # a lone contact in a session without contact range
    lone = np.zeros(P.size)
    lone[1] = 900.0
    out = revise_points(_points(P, lone, repeats=1))
    assert not any(r.contact for r in out) and out[1].note == NO_RANGE_NOTE


class _Scripted:
    """A stub method: returns the scripted results in order (frames sorted by pressure)."""

    name = "unet"
    NO_REFERENCE = "no reference"

    def __init__(self, areas: Sequence[float]) -> None:
        self.areas = list(areas)

    def start(
        self, files: Sequence[Path], reference: ImageFile | None, bit_depth: int | None = None
    ) -> Started:
        return Started(1, None if reference is None else reference.decode())

    def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
        return None

    def measure(self, image: np.ndarray) -> AreaResult:
        a = self.areas.pop(0)
        iv = (0.95 * a, 1.05 * a) if a > 0 else (0.0, 0.0)
        return AreaResult(a > 0, a, "", None, None, iv)

    def describe(self) -> dict[str, Any]:
        return {"name": self.name}


@pytest.mark.parametrize("rule", [True, False])
def test_calibrate_applies_the_rule(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, rule: bool
) -> None:
    areas = [0.0, 9e4, 6e4, 1e4, *(2e4 + 1e4 * i for i in range(17))]  # 21 frames, 0-20 kPa
    monkeypatch.setattr(registry, "make_method", lambda *a, **k: _Scripted(areas.copy()))
    options = SessionOptions(session_rule=rule)
    rep = calibrate_session(EXAMPLE / "manifest.csv", tmp_path / "cal", "unet", None, options)
    rec = json.loads(rep.files["json"].read_text())
    notes = [r["note"] for r in rec["points"]]
    assert rec["extra"]["session_rule"] is rule
    if rule:
        assert 2.0 <= rep.curve.onset_kpa <= 3.0  # between the last ring and first contact
        assert sum("not the contact" in n for n in notes) == 2
    else:
        assert rep.curve.onset_kpa <= 1.0
        assert not any("session rule" in n for n in notes)


def _frame(p: float, a: float, iv: tuple[float, float] | None) -> ScoredFrame:
    return ScoredFrame("unet", "s", f"{p}.png", p, 0.0, a, a > 0, area_interval_px=iv)


def test_bench_rows_after_the_session_rule() -> None:
    frames = [_frame(p, a, (0.95 * a, 1.05 * a)) for p, a in zip(P, AREA, strict=True)]
    out = session_ruled(frames)
    assert [f.method for f in out] == ["unet" + SESSION_SUFFIX] * P.size
    assert [f.contact for f in out] == [False, False, False, True, True, True, True, True]
    assert out[1].area_px == 0.0 and out[1].area_interval_px == (0.0, 945.0)
    assert session_ruled([_frame(p, a, None) for p, a in zip(P, AREA, strict=True)]) == []


def test_calibrate_says_when_the_rule_removed_every_contact(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    areas = [0.0, 9e4, *([0.0] * 19)]  # one lone contact at 1 kPa
    monkeypatch.setattr(registry, "make_method", lambda *a, **k: _Scripted(areas.copy()))
    with pytest.raises(RunError, match="session rule set every one.*--per-frame-contact"):
        calibrate_session(EXAMPLE / "manifest.csv", tmp_path / "cal", "unet")
    assert not (tmp_path / "cal").exists()


def test_cli_per_frame_contact(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from contactcal.infer.cli import main

    areas = [0.0, 9e4, 6e4, 1e4, *(2e4 + 1e4 * i for i in range(17))]
    monkeypatch.setattr(registry, "make_method", lambda *a, **k: _Scripted(areas.copy()))
    out = tmp_path / "cal"
    args = ["calibrate", str(EXAMPLE / "manifest.csv"), "--out", str(out)]
    assert main([*args, "--per-frame-contact"]) == 0
    rec = json.loads((out / "calibration.json").read_text())
    assert rec["extra"]["session_rule"] is False and rec["onset_kpa"] <= 1.0


def test_evaluate_onset_after_the_rule() -> None:
    from contactcal.infer.evaluate.score import onset_summary

    def scored(name: str, iv: bool) -> list[ScoredFrame]:
        return [
            ScoredFrame(
                name,
                "s",
                f"{p}.png",
                p,
                t,
                a,
                a > 0,
                area_interval_px=((0.95 * a, 1.05 * a) if iv else None),
            )
            for p, a, t in zip(P, AREA, np.where(P >= 3, AREA, 0.0), strict=True)
        ]

    res = onset_summary(scored("unet", True) + scored("classical", False))
    assert 2.0 <= res["methods"]["unet"]["onset_kpa"] <= 3.0
    assert res["methods"]["classical"]["onset_kpa"] <= 1.0  # no interval: flags as measured

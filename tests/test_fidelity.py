"""Nominal renders show the rig paper's observations (issue 9, items 1a-1e; docs/fidelity.md).

Fast subset: two nominal sessions at 400x300, 4 spp, eight pressures. Full check (slow): twelve
sessions at 400x300, 8 spp, the numbers reported in docs/fidelity.md. (Smaller renders do not
stand in: once the camera blur scaled with the width (synth revision 2), the routine's median
error at >= 5 kPa on session 1 was -6 % at 160x120 and -7 % at 240x180, against +3 % at 400x300.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mitsuba")

from contactcal.synth.fidelity import SessionFidelity
from contactcal.synth.fidelity_report import FidelityConfig, run_fidelity, summarise
from contactcal.synth.reflexes import window_ring_circle
from contactcal.synth.rig import RigGeometry
from contactcal.synth.session import RenderConfig
from contactcal.synth.window import WindowReflection

FAST = FidelityConfig(
    sessions=2,
    pressures_kpa=(0, 1, 2, 3, 5, 10, 15, 20),
    seed=9000,
    render=RenderConfig(width=400, height=300, spp=4),
)
FULL = FidelityConfig(sessions=12, workers=2)
BRIGHT_IN_RING_MIN = 0.85  # share of the ROI step's pixels (after erosion) in the window ring
BLOB_ENCLOSES_MIN = 0.9  # share of contact frames (>= 5 kPa) whose half-max blob encloses it
PATCH_IN_ROI_MIN = 0.98  # share of a patch's pixels inside the true 55 % ROI, worst frame
RING_TO_EDGE_MAX = 0.15  # of the ring radius (~1.7 mm on the membrane): our reflex sits ~1 mm
#   outside the contact edge where the paper's hugs it (docs/fidelity.md, "where we differ")


@pytest.fixture(scope="module")
def fast() -> list[SessionFidelity]:
    return [r for r, _ in run_fidelity(FAST)]


def _at(r: SessionFidelity, field: str, lo: float, hi: float = 99.0) -> list:
    vals = getattr(r, field)
    return [v for p, v in zip(r.pressures_kpa, vals, strict=True) if lo <= p <= hi]


def test_window_ring_circle_is_the_reflex_outer_edge() -> None:
    """Reference: the closed-form outer edge equals the window reflex layer's support."""
    for rig in (RigGeometry(), RigGeometry(lgp_gap_mm=12.0), RigGeometry(lgp_gap_mm=1.0)):
        refl = WindowReflection(rig, 400, 300, 16, ss=2)(1.0, np.ones(16))[..., 0]
        cx, cy, r = window_ring_circle(rig, 400, 300)
        ys, xs = np.nonzero(refl > 0)
        assert np.max(np.hypot(xs - cx, ys - cy)) == pytest.approx(r, abs=1.0)


def test_roi_step_finds_the_whole_window_ring(fast: list[SessionFidelity]) -> None:
    """1a: the published ROI step finds the ring (centre 2 %, radius 3 %)."""
    for r in fast:
        assert r.roi_found and r.roi_ok, (r.roi_centre_error, r.roi_radius_error)
        # at 0 kPa the window ring is the brightest structure
        assert r.bright_in_ring >= BRIGHT_IN_RING_MIN and r.ring_grey > r.inside_grey_p99


def test_inner_ring_shrinks_before_contact_then_hugs_it(fast: list[SessionFidelity]) -> None:
    """1b: inner ring back and shrinking at 1-2 kPa, onset 2-4 kPa, then at the contact edge."""
    for r in fast:
        assert 2.0 <= r.onset_kpa <= 4.0
        one, two = _at(r, "inner_ring", 1, 1)[0], _at(r, "inner_ring", 2, 2)[0]
        assert two is not None and (one is None or two < one), (one, two)
        late = [v for v in _at(r, "ring_to_edge", r.onset_kpa + 5.0) if v is not None]
        assert late and max(late) <= RING_TO_EDGE_MAX, late


def test_published_routine_overestimates_from_5_kpa(fast: list[SessionFidelity]) -> None:
    """1c (fast subset): the routine overestimates at >= 5 kPa, by < 60 % at 15-20 kPa.

    Single frames whose brightest structure is the skin land a few % under (docs/fidelity.md);
    the per-session median must still be an overestimate (the full check bins twelve sessions).
    """
    for r in fast:
        errs = _at(r, "classical_error", 5.0)
        assert errs and all(e is not None for e in errs) and np.median(errs) > 0, errs
        assert all(e < 0.6 for e in _at(r, "classical_error", 15.0)), errs


def test_patch_fits_the_roi(fast: list[SessionFidelity]) -> None:
    """1d: the contact patch is inside the 55 % ROI (1e, the blob, needs 400 px: full check)."""
    for r in fast:
        inside = [v for v in r.patch_in_roi if v is not None]
        assert inside and min(inside) >= PATCH_IN_ROI_MIN, inside


@pytest.mark.slow
def test_full_fidelity_check_on_twelve_nominal_sessions() -> None:
    """1a-1e on twelve sessions at 400x300 (numbers in docs/fidelity.md)."""
    s = summarise([r for r, _ in run_fidelity(FULL)])
    assert s["roi_ok"] >= 0.95 * s["sessions"]
    assert s["bright_in_ring_min"] >= BRIGHT_IN_RING_MIN
    high = s["bins"][-1]
    assert 3.0 <= high["median_error_pct"] <= 25.0
    assert s["sessions_over_30pct_at_15_20"] <= s["sessions"] / 6
    assert all(
        b["patch_in_roi_min"] is None or b["patch_in_roi_min"] >= PATCH_IN_ROI_MIN
        for b in s["bins"]
    )
    # 1e: from 5 kPa the routine's blob encloses the contact in >= 90 % of the frames; the rest
    # are frames whose brightest structure is the skin, not the ring (docs/fidelity.md)
    assert all(b["blob_encloses_share"] >= BLOB_ENCLOSES_MIN for b in s["bins"][3:])


def test_cli_refuses_an_output_that_is_not_a_folder_before_rendering(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from contactcal.infer.cli import main

    afile = tmp_path / "afile"
    afile.write_text("kept")
    for out in (afile, afile / "sub"):
        assert main(["fidelity", "--sessions", "1", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "is not a folder" in err[0] and str(afile) in err[0]
    assert main(["fidelity", "--sessions", "1", "--out", "-"]) == 2
    assert "writes a folder of files" in capsys.readouterr().err
    assert afile.read_text() == "kept"


def test_cli_refuses_pressures_past_the_papers_bins_and_names_a_replaced_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 25 kPa frame fell in no bin without a word; a second run replaced the first silently."""
    from contactcal.infer.cli import main

    out = tmp_path / "fid"
    argv = ["fidelity", "--sessions", "1", "--size", "64x48", "--spp", "1", "--out", str(out)]
    assert main([*argv, "--pressures", "0:25:5"]) == 2
    assert "bins, which end at 20 kPa" in capsys.readouterr().err and not out.exists()
    assert main([*argv, "--pressures", "0,10"]) == 0
    said = capsys.readouterr().out
    assert "Bins are (lo, hi] kPa" in said and "note: replaced" not in said
    assert main([*argv, "--pressures", "0,10"]) == 0
    assert f"note: replaced the fidelity report that {out} held" in capsys.readouterr().out

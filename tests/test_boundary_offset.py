"""The rig's boundary offset: Steiner's formula and its inverse, the region's perimeter, the rig
config keys, and where it is applied (only to the model it was measured for)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.methods.base import AreaResult
from contactcal.infer.pipeline.boundary import (
    GONE_NOTE,
    MODEL_KEY,
    OFFSET_KEY,
    BoundaryOffset,
    BoundaryOffsetError,
    apply_offset,
    fit_offset,
    load_boundary_offset,
    offset_area,
    offset_contour,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
SHA = "ab" * 32


def _disc(radius: float, size: int = 160) -> np.ndarray:
    """``(size, size) bool``: the pixels whose centres lie within ``radius`` of the middle."""
    yy, xx = np.mgrid[:size, :size] + 0.5 - size / 2
    return np.hypot(xx, yy) <= radius


def test_steiner_is_exact_for_a_circle_and_inverted_by_fit_offset() -> None:
    a, p = math.pi * 100.0, 2 * math.pi * 10.0  # radius 10
    assert offset_area(a, p, 1.0) == pytest.approx(math.pi * 121.0)
    assert offset_area(a, p, -1.0) == pytest.approx(math.pi * 81.0)
    assert offset_area(a, p, -10.0) == 0.0 and offset_area(a, p, -20.0) == 0.0  # past the middle
    for d in (-2.5, 0.0, 0.7, 3.0):
        assert fit_offset(a, p, offset_area(a, p, d)) == pytest.approx(d)
    assert fit_offset(a, p, 0.0) == pytest.approx(-10.0)  # the vertex: the whole radius


@pytest.mark.parametrize("convex", [True, False])
def test_region_perimeter_of_a_pixel_disc(convex: bool) -> None:
    from contactcal.infer.methods.unet.postprocess import region_perimeter

    keep = _disc(40.0)
    assert region_perimeter(keep, convex) == pytest.approx(2 * math.pi * 40.0, rel=0.02)
    assert region_perimeter(np.zeros((8, 8), bool), convex) == 0.0


def test_steiner_on_pixel_regions_predicts_the_grown_disc() -> None:
    from contactcal.infer.methods.unet.postprocess import region_perimeter

    keep = _disc(30.0)
    a, p = float(keep.sum()), region_perimeter(keep, True)
    for d in (-3.0, 2.0, 5.0):
        assert offset_area(a, p, d) == pytest.approx(float(_disc(30.0 + d).sum()), rel=0.01)


def test_apply_offset_moves_area_soft_area_and_interval_and_says_so() -> None:
    res = AreaResult(True, 1000.0, "", None, 1010.0, (900.0, 1100.0), 120.0)
    out = apply_offset(res, 2.0, 0.15)
    assert out.area_px == pytest.approx(1000.0 + 240.0 + 4 * math.pi)
    assert out.area_interval_px[0] < out.area_px < out.area_interval_px[1]
    assert out.soft_area_px > res.soft_area_px
    assert out.perimeter_px == pytest.approx(120.0 + 4 * math.pi)
    assert "boundary moved +0.150 mm" in out.note and out.contact
    none = AreaResult(False, 0.0, "no contact", None, None, (0.0, 50.0), None)
    assert apply_offset(none, 2.0, 0.15) is none
    no_perimeter = AreaResult(True, 500.0, "", None)  # the classical routine: none measured
    assert apply_offset(no_perimeter, 2.0, 0.15) is no_perimeter
    contour = np.zeros((4, 1, 2), np.int32)
    small = AreaResult(True, 10.0, "", contour, 11.0, (5.0, 30.0), 12.0)
    gone = apply_offset(small, -5.0, -0.4)
    assert not gone.contact and gone.area_px == 0.0 and gone.soft_area_px == 0.0
    assert gone.note.startswith(GONE_NOTE) and "-0.400 mm" in gone.note
    assert gone.contour is None and gone.area_interval_px[0] == 0.0


def _filled(contour: np.ndarray, size: int = 160) -> np.ndarray:
    mask = np.zeros((size, size), np.uint8)
    cv2.drawContours(mask, [contour], -1, 1, thickness=-1)
    return mask > 0


@pytest.mark.parametrize("d", [-6.0, 4.0, 9.5])
def test_the_outline_moves_with_the_area(d: float) -> None:
    """The moved outline bounds the disc of the moved radius (its IoU with it ~1), so the IoU
    `evaluate` takes from it refers to the region whose area is stated."""
    found, _ = cv2.findContours(
        _disc(40.0).astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    moved = _filled(offset_contour(found[0], d))
    want = _disc(40.0 + d)
    iou = (moved & want).sum() / (moved | want).sum()
    assert iou > 0.98, iou
    assert offset_contour(found[0], -45.0) is None  # past the middle: nothing left
    res = AreaResult(True, float(_disc(40.0).sum()), "", found[0], None, None, 2 * math.pi * 40)
    out = apply_offset(res, d, d * 0.02)
    assert (_filled(out.contour) == moved).all()


def _rig(path: Path, **keys: object) -> Path:
    path.write_text(json.dumps({"mm_per_px": 0.126454185, "image_width_px": 400, **keys}))
    return path


def test_rig_config_keys(tmp_path: Path) -> None:
    assert load_boundary_offset(_rig(tmp_path / "a.json")) is None
    b = load_boundary_offset(_rig(tmp_path / "b.json", **{OFFSET_KEY: 0.2, MODEL_KEY: SHA}))
    assert b == BoundaryOffset(0.2, SHA, str(tmp_path / "b.json"))
    with pytest.raises(BoundaryOffsetError, match=r"c\.json: .* go together"):
        load_boundary_offset(_rig(tmp_path / "c.json", **{OFFSET_KEY: 0.2}))
    bad = [{OFFSET_KEY: "0.2", MODEL_KEY: SHA}, {OFFSET_KEY: 3.0, MODEL_KEY: SHA}]
    bad += [{OFFSET_KEY: float("nan"), MODEL_KEY: SHA}, {OFFSET_KEY: 0.1, MODEL_KEY: "abc"}]
    for i, keys in enumerate(bad):
        with pytest.raises(BoundaryOffsetError, match=rf"d{i}\.json: "):
            load_boundary_offset(_rig(tmp_path / f"d{i}.json", **keys))


def test_a_run_reads_its_rig_config_once_also_with_mm_per_px(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import argparse

    from contactcal.infer.pipeline import scale as scale_module
    from contactcal.infer.pipeline.args import read_rig, resolve_rig
    from contactcal.infer.pipeline.scale import PixelScale, RigConfigError

    rig = _rig(tmp_path / "rig.json", **{OFFSET_KEY: 0.2, MODEL_KEY: SHA})
    reads: list[Path] = []
    real = scale_module.read_rig_json
    monkeypatch.setattr(scale_module, "read_rig_json", lambda p: reads.append(p) or real(p))
    args = argparse.Namespace(rig=rig, mm_per_px=None)
    scale, boundary = resolve_rig(args, read_rig(args))
    assert scale == PixelScale(0.126454185, 400) and boundary == BoundaryOffset(0.2, SHA, str(rig))
    assert reads == [rig]
    # --mm-per-px replaces the scale, not the offset; a broken rig config is an error, not ignored
    args = argparse.Namespace(rig=rig, mm_per_px=0.05)
    scale, boundary = resolve_rig(args, read_rig(args))
    assert scale == PixelScale(0.05, None) and boundary is not None
    (tmp_path / "bad.json").write_text("[1, 2]")
    with pytest.raises(RigConfigError, match=r"bad\.json: expected a JSON object"):
        read_rig(argparse.Namespace(rig=tmp_path / "bad.json", mm_per_px=0.05))


def _shipped_sha() -> str:
    from contactcal.infer.files.digest import sha256_file
    from contactcal.infer.methods.unet.runner import DEFAULT_MODEL

    return sha256_file(DEFAULT_MODEL)


def test_measure_files_applies_it_to_its_model_only(tmp_path: Path) -> None:
    pytest.importorskip("onnxruntime")
    from contactcal.infer.methods.registry import make_method
    from contactcal.infer.pipeline.measure import measure_files
    from contactcal.infer.pipeline.scale import PixelScale

    files = [EXAMPLE / "p00.0kpa.jpg", EXAMPLE / "p10.0kpa.jpg"]
    scale = PixelScale(0.126454185, 400)
    mine = BoundaryOffset(0.25, _shipped_sha(), "rig.json")
    unet = make_method("unet")
    plain = measure_files(files, unet, files[0], scale)
    moved = measure_files(files, unet, files[0], scale, boundary=mine)
    a, b = plain[1].result, moved[1].result
    d_px = 0.25 / 0.126454185
    assert b.area_px == pytest.approx(offset_area(a.area_px, a.perimeter_px, d_px))
    assert moved[1].boundary_offset_mm == 0.25 and plain[1].boundary_offset_mm is None
    assert moved[1].to_json("unet")["boundary_offset_mm"] == 0.25
    assert moved[1].area_mm2 == pytest.approx(b.area_px * 0.126454185**2)
    (lo, hi), (lo2, hi2) = a.area_interval_px, b.area_interval_px
    assert lo < lo2 and hi < hi2 and lo2 <= b.area_px <= hi2
    with pytest.raises(BoundaryOffsetError, match=r"rig\.json: .*measured for the model"):
        measure_files(files, unet, files[0], scale, boundary=BoundaryOffset(0.25, SHA, "rig.json"))
    with pytest.raises(BoundaryOffsetError, match="pixel scale"):
        measure_files(files, unet, files[0], None, boundary=mine)
    classical = measure_files(files, make_method("classical"), files[0], scale, boundary=mine)
    assert classical[1].boundary_offset_mm is None  # measured for the U-Net model


def test_cli_evaluate_measures_it_and_calibrate_applies_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("onnxruntime")
    from contactcal.infer.cli import main

    manifest = str(EXAMPLE / "manifest.csv")
    ev = tmp_path / "ev"
    assert main(["evaluate", manifest, "--labels", str(EXAMPLE / "masks"), "--out", str(ev)]) == 0
    assert "boundary offset (unet) against the labels" in capsys.readouterr().out
    off = json.loads((ev / "evaluation.json").read_text())["boundary_offset"]
    assert off["frames"] >= 5 and off["applied_mm"] is None
    assert len(off["frame_offsets_mm"]) == off["frames"] == len(off["frame_offsets_px"])
    lo, hi = off["interval_mm"]
    assert lo <= off["median_mm"] <= hi
    assert off["rig_config"] == {OFFSET_KEY: round(off["median_mm"], 3), MODEL_KEY: _shipped_sha()}
    rig = _rig(tmp_path / "rig.json", **{OFFSET_KEY: 0.3, MODEL_KEY: _shipped_sha()})
    cal = tmp_path / "cal"
    assert main(["calibrate", manifest, "--rig", str(rig), "--out", str(cal)]) == 0
    record = json.loads((cal / "calibration.json").read_text())
    assert record["extra"]["boundary_offset_mm"] == 0.3
    ev2 = tmp_path / "ev2"
    args = ["evaluate", manifest, "--labels", str(EXAMPLE / "masks"), "--rig", str(rig)]
    capsys.readouterr()  # calibrate's table
    assert main([*args, "--out", str(ev2)]) == 0
    printed = capsys.readouterr().out
    assert f"boundary offset +0.300 mm ({rig}); the offset below is what remains" in printed
    off2 = json.loads((ev2 / "evaluation.json").read_text())["boundary_offset"]
    assert off2["applied_mm"] == 0.3 and off2["applied_from"] == str(rig)
    assert off2["median_mm"] == pytest.approx(off["median_mm"] - 0.3, abs=0.03)  # what remains
    stale = _rig(tmp_path / "stale.json", **{OFFSET_KEY: 0.3, MODEL_KEY: SHA})
    ev3 = tmp_path / "ev3"
    args = ["evaluate", manifest, "--labels", str(EXAMPLE / "masks"), "--rig", str(stale)]
    assert main([*args, "--out", str(ev3)]) == 0  # evaluate is how to measure it again
    assert "stale.json: its boundary offset (+0.300 mm)" in capsys.readouterr().out
    off3 = json.loads((ev3 / "evaluation.json").read_text())["boundary_offset"]
    assert off3["applied_mm"] is None and off3["rig_config"] == off["rig_config"]
    out = tmp_path / "r.json"
    frames = [str(EXAMPLE / "p00.0kpa.jpg"), str(EXAMPLE / "p10.0kpa.jpg")]
    assert main(["measure", "--rig", str(stale), "--out", str(out), *frames]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "stale.json" in err[0] and not out.exists()


def _measured(area: float, perimeter: float, width: int = 400) -> object:
    from contactcal.infer.pipeline.measure import Measured

    res = AreaResult(True, area, "", None, perimeter_px=perimeter)
    return Measured(Path("f.png"), width, 300, res, None)


def test_evaluate_offset_branches() -> None:
    from contactcal.infer.evaluate.offset import boundary_offset, current_offset, offset_line
    from contactcal.infer.pipeline.scale import PixelScale

    disc = [_measured(math.pi * r * r, 2 * math.pi * r) for r in (20.0, 25.0, 30.0, 35.0, 40.0)]
    grown = [math.pi * (r + 2.0) ** 2 for r in (20.0, 25.0, 30.0, 35.0, 40.0)]  # 2 px outward
    px = boundary_offset(disc, grown, None, SHA)
    assert px["median_px"] == pytest.approx(2.0) and px["median_mm"] is None
    assert px["rig_config"] is None and "in pixels only" in offset_line(px)
    mm = boundary_offset(disc, grown, PixelScale(0.1, 400), SHA)
    assert mm["median_mm"] == pytest.approx(0.2) and mm["rig_config"][OFFSET_KEY] == 0.2
    few = boundary_offset(disc[:4], grown[:4], PixelScale(0.1, 400), SHA)
    assert few["median_px"] is None and "label at least 5" in few["note"]
    mixed = [
        math.pi * (r + d) ** 2
        for r, d in zip((20, 25, 30, 35, 40), (1, -1, 1, -1, 0.5), strict=True)
    ]
    none = boundary_offset(disc, mixed, PixelScale(0.1, 400), SHA)  # interval holds 0
    assert none["interval_mm"][0] < 0 < none["interval_mm"][1] and none["rig_config"] is None
    assert "includes 0" in offset_line(none)
    far = boundary_offset(disc, grown, PixelScale(1.5, 400), SHA)  # 3 mm: no keys
    assert far["rig_config"] is None and "beyond" in offset_line(far)
    mine = BoundaryOffset(0.1, SHA, "rig.json")
    assert current_offset(mine, SHA) == (mine, "")
    kept, note = current_offset(mine, "cd" * 32)
    assert kept is None and "rig.json" in note and "not applied" in note


def test_calibrate_moves_the_areas_and_mm_per_px_keeps_the_offset(tmp_path: Path) -> None:
    pytest.importorskip("onnxruntime")
    from contactcal.infer.cli import main

    session = tmp_path / "session"
    session.mkdir()
    for f in EXAMPLE.glob("p*.jpg"):
        (session / f.name).write_bytes(f.read_bytes())
    (session / "manifest.csv").write_text((EXAMPLE / "manifest.csv").read_text())
    manifest = str(session / "manifest.csv")
    argv = ["calibrate", manifest, "--mm-per-px", "0.126454185", "--out"]
    assert main([*argv, str(tmp_path / "a")]) == 0
    _rig(session / "rig.json", **{OFFSET_KEY: 0.2, MODEL_KEY: _shipped_sha()})
    assert main([*argv, str(tmp_path / "b")]) == 0
    a, b = (json.loads((tmp_path / x / "calibration.json").read_text()) for x in "ab")
    assert a["extra"]["boundary_offset_mm"] is None and b["extra"]["boundary_offset_mm"] == 0.2
    moved = [(p, q) for p, q in zip(a["points"], b["points"], strict=True) if p["area_px"] > 0]
    assert moved and all(q["area_px"] > p["area_px"] for p, q in moved)


def test_demo_applies_the_offset_of_the_rig_json_beside_its_manifest(tmp_path: Path) -> None:
    """As ``calibrate`` does; the classical routine is never moved."""
    pytest.importorskip("onnxruntime")
    import shutil

    from contactcal.infer.pipeline.demo import run_demo

    session = tmp_path / "session"
    shutil.copytree(EXAMPLE, session, ignore=shutil.ignore_patterns("masks"))
    _rig(session / "rig.json", **{OFFSET_KEY: 0.2, MODEL_KEY: _shipped_sha()})
    run_demo(tmp_path / "demo", session / "manifest.csv")
    records = {
        m: json.loads((tmp_path / "demo" / m / "calibration.json").read_text())
        for m in ("unet", "classical")
    }
    assert records["unet"]["extra"]["boundary_offset_mm"] == 0.2
    assert records["classical"]["extra"]["boundary_offset_mm"] is None

"""``contactcal evaluate``: ImageJ ellipse convention, example-session scores, bad labels."""

from __future__ import annotations

import csv
import json
import math
import shutil
import statistics
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from contactcal.infer.cli import main
from contactcal.infer.evaluate.ellipse import ImageJEllipse, rasterise
from contactcal.infer.evaluate.label_raster import label_mask
from contactcal.infer.evaluate.labels import read_labels
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION
from contactcal.infer.pipeline.manifest import read_session

MANIFEST = EXAMPLE_SESSION / "manifest.csv"
MASKS = EXAMPLE_SESSION / "masks"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _evaluate(out: Path, labels: Path, *extra: str, manifest: Path = MANIFEST) -> int:
    return main(["evaluate", str(manifest), "--labels", str(labels), "--out", str(out), *extra])


def _record(out: Path) -> dict[str, Any]:
    return json.loads((out / "evaluation.json").read_text(encoding="utf-8"))


def _screen_angle_deg(mask: np.ndarray) -> float:
    """Principal-axis angle of a mask from image moments, degrees CCW on screen, in [0, 180)."""
    m = cv2.moments(mask.astype(np.uint8), binaryImage=True)
    theta = 0.5 * math.atan2(2 * m["mu11"], m["mu20"] - m["mu02"])  # from +x towards +y (down)
    return math.degrees(-theta) % 180.0


def test_imagej_ellipse_at_30_degrees_keeps_its_orientation() -> None:
    # ImageJ: 30° counter-clockwise on screen, i.e. the major axis rises to the right.
    e = ImageJEllipse(cx=100.5, cy=80.5, major=120.0, minor=30.0, angle_deg=30.0)
    mask = rasterise(e.to_opencv(), (160, 200))
    assert _screen_angle_deg(mask) == pytest.approx(30.0, abs=0.5)
    ys, xs = np.nonzero(mask)
    assert (xs.mean(), ys.mean()) == pytest.approx((100.0, 80.0), abs=0.05)  # pixel centres
    assert mask.sum() == pytest.approx(e.analytic_area_px, rel=0.01)
    right = xs > 140  # the major axis' right end lies ABOVE the centre (y down)
    assert ys[right].mean() < 80.0
    # OpenCV draws the converted RotatedRect the same way (its fill adds the boundary).
    drawn = np.zeros((160, 200), np.uint8)
    cv2.ellipse(drawn, e.to_opencv(), 1, thickness=-1)
    assert _screen_angle_deg(drawn > 0) == pytest.approx(30.0, abs=0.5)
    assert np.logical_and(mask, drawn > 0).sum() / np.logical_or(mask, drawn > 0).sum() > 0.95


def _imagej_row(mask_file: Path) -> list[str]:
    """cv2.fitEllipse of a mask's outline, written as ImageJ reports it (empty: no contact)."""
    mask = cv2.imread(str(mask_file), cv2.IMREAD_GRAYSCALE)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    name = mask_file.stem + ".jpg"
    if not contours:
        return [name, "", "", "", "", ""]
    (cx, cy), (w, h), angle = cv2.fitEllipse(max(contours, key=cv2.contourArea))
    major, minor, angle = (w, h, angle) if w >= h else (h, w, angle + 90.0)
    return [name, f"{cx + 0.5}", f"{cy + 0.5}", f"{major}", f"{minor}", f"{-angle % 180.0}"]


def _write_csv(path: Path, rows: list[list[str]]) -> Path:
    with open(path, "w", encoding="utf-8", newline="") as fh:
        csv.writer(fh).writerows([["file", "cx", "cy", "major", "minor", "angle_deg"], *rows])
    return path


@pytest.fixture(scope="module")
def both(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """The example session against its exact masks, with both methods."""
    out = tmp_path_factory.mktemp("evaluate") / "out"
    assert _evaluate(out, MASKS, "--method", "both") == 0
    return out, _record(out)


def test_masks_unet_is_accurate(both: tuple[Path, dict[str, Any]]) -> None:
    frames = [f for f in both[1]["frames"] if f["pressure_kpa"] >= 5]
    assert len(frames) == 16
    unet = [f["results"]["unet"] for f in frames]
    assert statistics.median(abs(r["rel_error"]) for r in unet) < 0.05
    assert statistics.median(r["iou"] for r in unet) > 0.9
    masks = {p.stem: int((cv2.imread(str(p), 0) > 0).sum()) for p in MASKS.glob("*.png")}
    assert all(f["label_area_px"] == masks[Path(f["file"]).stem] for f in both[1]["frames"])


def test_both_methods_outputs_and_summary(both: tuple[Path, dict[str, Any]]) -> None:
    out, record = both
    assert {p.name for p in out.iterdir()} == {"evaluation.json", "evaluation.png"}
    png = (out / "evaluation.png").read_bytes()
    assert png.startswith(PNG_MAGIC)
    assert cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR) is not None
    assert all(set(f["results"]) == {"unet", "classical"} for f in record["frames"])
    assert record["unlabelled"] == []
    bins = record["summary"]["bins"]
    assert {(b["method"], b["bin_kpa"]) for b in bins} >= {("unet", "5-10"), ("classical", "5-10")}
    # the example's rig.json gives the scale: the errors in mm² are stated too
    assert all(b["median_abs_error_mm2"] is not None for b in bins if b["bin_kpa"] == "5-10")
    onset = record["summary"]["onset"]
    assert onset["labels_onset_kpa"] is not None
    assert set(onset["methods"]) == {"unet", "classical"}
    assert abs(onset["methods"]["unet"]["error_kpa"]) < 1.0


def test_imagej_ellipse_csv_matches_the_masks(tmp_path: Path) -> None:
    rows = [_imagej_row(p) for p in sorted(MASKS.glob("*.png"))]
    labels = _write_csv(tmp_path / "labels.csv", rows)
    out = tmp_path / "out"
    assert _evaluate(out, labels) == 0
    frames = _record(out)["frames"]
    assert len(frames) == 21
    for f in frames:
        mask = cv2.imread(str(MASKS / (Path(f["file"]).stem + ".png")), 0) > 0
        if f["pressure_kpa"] >= 5:
            assert f["label_area_px"] == pytest.approx(mask.sum(), rel=0.03), f["file"]
            assert f["label_area_analytic_px"] == pytest.approx(f["label_area_px"], rel=0.02)
            # The patches are 1.5:1 ellipses at ~36°: a wrong angle or centre drops the IoU.
            assert f["results"]["unet"]["iou"] > 0.9, f["file"]
        if not mask.any():  # an empty row labels a frame without contact
            assert f["label_area_px"] == 0 and f["results"]["unet"]["rel_error"] is None
    session = read_session(MANIFEST)
    for lab in read_labels(labels, session.frames, session.folder):
        truth = cv2.imread(str(MASKS / (lab.frame.stem + ".png")), 0) > 0
        if truth.sum() > 5000:  # >= 5 kPa
            mask = label_mask(lab, (400, 300)).mask
            assert (mask & truth).sum() / (mask | truth).sum() > 0.95, lab.frame.name


def test_unlabelled_frames_are_listed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    masks = tmp_path / "masks"
    masks.mkdir()
    for p in ("p00.0kpa.png", "p06.0kpa.png", "p12.0kpa.png"):
        shutil.copy(MASKS / p, masks / p)
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical") == 0
    record = _record(out)
    assert [f["file"] for f in record["frames"]] == ["p00.0kpa.jpg", "p06.0kpa.jpg", "p12.0kpa.jpg"]
    assert len(record["unlabelled"]) == 18 and "p01.0kpa.jpg" in record["unlabelled"]
    printed = capsys.readouterr().out
    assert "18 frame(s) without a label" in printed and ", …\n" in printed
    assert "p01.0kpa.jpg" in printed and "p20.0kpa.jpg" not in printed  # the first 10 named


def test_onset_bounded_by_the_labels_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    masks = tmp_path / "masks"
    masks.mkdir()
    for p in ("p06.0kpa.png", "p12.0kpa.png"):
        shutil.copy(MASKS / p, masks / p)
    assert _evaluate(tmp_path / "out", masks) == 0
    onset = _record(tmp_path / "out")["summary"]["onset"]
    assert onset["labels_onset_kpa"] == 6.0
    assert "label a frame without contact below the onset" in onset["note"]
    assert "note: the lowest labelled frame (6 kPa) has contact" in capsys.readouterr().out


GOOD = ["p10.0kpa.jpg", "200.5", "150.5", "90", "70", "15"]


@pytest.mark.parametrize(
    ("header", "row", "expected"),
    [
        (["file", "cx", "cy", "major", "minor"], GOOD[:5], "missing column(s) angle_deg"),
        (  # ImageJ's own Results export: its columns named, how to rename them
            ["", "Label", "Area", "X", "Y", "Major", "Minor", "Angle"],
            ["1", "p10.0kpa.jpg", "5000", *GOOD[1:]],
            "this looks like ImageJ's Results export: rename its columns Label → file, X → cx",
        ),
        (None, [*GOOD[:3], "0", *GOOD[4:]], "major 0 is not in (0, 100000]"),
        (None, [*GOOD[:4], "-3", GOOD[5]], "minor -3 is not in (0, 100000]"),
        (None, [*GOOD[:3], "1e308", "1e308", GOOD[5]], "major 1e+308 is not in (0, 100000]"),
        (None, ["p99.0kpa.jpg", *GOOD[1:]], "'p99.0kpa.jpg' is not a frame of the manifest"),
        (None, ["p10.0kpa.jpg:1", *GOOD[1:]], "remove the ':…' suffix ImageJ adds"),
        (None, [*GOOD[:2], "abc", *GOOD[3:]], "cy 'abc' is not a finite number"),
        (None, [GOOD[0], "900", *GOOD[2:]], "lies outside the 400×300 px frame"),
        (None, [*GOOD[:3], "70", "90", GOOD[5]], "minor 90 is longer than major 70"),
    ],
)
def test_bad_ellipse_csv_exits_2_with_one_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    header: list[str] | None,
    row: list[str],
    expected: str,
) -> None:
    labels = tmp_path / "labels.csv"
    with open(labels, "w", encoding="utf-8", newline="") as fh:
        csv.writer(fh).writerows(
            [header or ["file", "cx", "cy", "major", "minor", "angle_deg"], row]
        )
    out = tmp_path / "out"
    assert _evaluate(out, labels, "--method", "classical") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and expected in err and str(labels) in err
    assert not out.exists()


def test_mask_of_wrong_size_exits_2_naming_both_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frames = [EXAMPLE_SESSION / f"p{p:04.1f}kpa.jpg" for p in (0, 5, 10)]
    manifest = tmp_path / "manifest.csv"
    rows = "".join(f"{f},{p}\n" for f, p in zip(frames, (0, 5, 10), strict=True))
    manifest.write_text("file,pressure_kpa\n" + rows, encoding="utf-8")
    masks = tmp_path / "masks"
    masks.mkdir()
    cv2.imwrite(str(masks / "p05.0kpa.png"), np.zeros((150, 200), np.uint8))
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical", manifest=manifest) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "200×150 px" in err and "400×300 px" in err
    assert str(masks / "p05.0kpa.png") in err and str(frames[1]) in err
    assert not out.exists()


def test_mask_naming_no_frame_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    masks = tmp_path / "masks"
    masks.mkdir()
    shutil.copy(MASKS / "p05.0kpa.png", masks / "frame_5.png")
    assert _evaluate(tmp_path / "out", masks) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "frame_5.png" in err and "no frame of the manifest" in err


def test_corrupt_mask_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A damaged mask PNG is refused like a damaged frame (strict decoding), not read wrong."""
    masks = tmp_path / "masks"
    masks.mkdir()
    ok, buf = cv2.imencode(".png", (np.arange(300 * 400) % 7 == 0).reshape(300, 400) * 255)
    assert ok
    bad = bytearray(buf.tobytes())
    bad[len(bad) // 2 : len(bad) // 2 + 40] = b"\x00" * 40
    (masks / "p10.0kpa.png").write_bytes(bytes(bad))
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "p10.0kpa.png" in err
    assert not out.exists()


def test_onset_with_repeated_pressures(tmp_path: Path) -> None:
    """Repeats at a pressure are pooled into one step; the onset is still compared."""
    frames = [(EXAMPLE_SESSION / f"p{p:04.1f}kpa.jpg", p) for p in (0, 2, 4, 6, 8)]
    copies = []
    for f, p in frames:
        for k in range(2):
            c = tmp_path / f"r{k}_{f.name}"
            shutil.copy(f, c)
            copies.append((c, p))
    (tmp_path / "m.csv").write_text(
        "file,pressure_kpa\n" + "".join(f"{c.name},{p}\n" for c, p in copies), encoding="utf-8"
    )
    masks = tmp_path / "masks"
    masks.mkdir()
    for c, p in copies:
        shutil.copy(EXAMPLE_SESSION / "masks" / f"p{p:04.1f}kpa.png", masks / f"{c.stem}.png")
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "unet", manifest=tmp_path / "m.csv") == 0
    onset = json.loads((out / "evaluation.json").read_text())["summary"]["onset"]
    assert onset["labels_onset_kpa"] is not None and "pooled" in onset["note"]
    assert abs(onset["methods"]["unet"]["error_kpa"]) < 0.5


def test_every_labelled_frame_is_in_a_bin(tmp_path: Path) -> None:
    """A step logged at 20.01 kPa (or a rig going past 20) is counted, in the open last bin."""
    lines = MANIFEST.read_text().splitlines()
    lines[-1] = lines[-1].rsplit(",", 1)[0] + ",20.01"
    manifest = tmp_path / "manifest.csv"
    rows = [r.split(",", 1) for r in lines[1:]]
    manifest.write_text(lines[0] + "\n" + "".join(f"{EXAMPLE_SESSION / f},{p}\n" for f, p in rows))
    out = tmp_path / "out"
    assert _evaluate(out, MASKS, "--method", "classical", manifest=manifest) == 0
    bins = {b["bin_kpa"]: b for b in _record(out)["summary"]["bins"]}
    assert list(bins) == ["0-3", "3-5", "5-10", ">=10"]
    assert sum(b["frames"] for b in bins.values()) == len(rows)


def test_printed_table_counts_found_and_false_contacts() -> None:
    """A false contact below onset shows in the printed table (1/2 kept), not only in the JSON."""
    from contactcal.infer.bench.scoring import ScoredFrame, bin_table
    from contactcal.infer.evaluate.report import format_table

    def frame(p: float, true: float, area: float) -> ScoredFrame:
        return ScoredFrame("unet", "s", f"{p}.png", p, true, area, area > 0, iou=None)

    frames = [frame(1.0, 0.0, 0.0), frame(2.0, 0.0, 40.0), frame(6.0, 100.0, 0.0)]
    onset = {"labels_onset_kpa": None, "note": "n", "methods": {}}
    rows = format_table(bin_table(frames), onset).splitlines()
    assert rows[0].split()[4:9] == ["contact", "found", "no", "contact", "kept"]
    assert rows[1].split()[:5] == ["unet", "0-3", "2", "–", "1/2"]
    assert rows[3].split()[:5] == ["unet", "5-10", "1", "0/1", "–"]

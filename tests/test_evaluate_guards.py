"""Guards of ``contactcal evaluate`` / ``boundary-offset`` against inputs that cannot be right:
one session pooled as several (copied or re-run evaluations), and label masks or ellipses that
cannot be a contact label on this rig (no background, more than the window ring)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from contactcal.infer.cli import main
from contactcal.infer.evaluate.label_raster import LabelMask
from contactcal.infer.evaluate.labels import Label, LabelError
from contactcal.infer.evaluate.pool import pool_offsets
from contactcal.infer.evaluate.window import Window, check_label_area, find_window
from contactcal.infer.image.read import ImageFile
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION

MANIFEST = EXAMPLE_SESSION / "manifest.csv"
MASKS = EXAMPLE_SESSION / "masks"
HEADER = "file,cx,cy,major,minor,angle_deg\n"


def _evaluate(out: Path, labels: Path, *extra: str) -> int:
    return main(["evaluate", str(MANIFEST), "--labels", str(labels), "--out", str(out), *extra])


def _record(folder: Path) -> dict[str, Any]:
    return json.loads((folder / "evaluation.json").read_text(encoding="utf-8"))


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


@pytest.fixture(scope="module")
def twice(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The example session evaluated (U-Net, the rig.json's scale) into two folders."""
    root = tmp_path_factory.mktemp("eval")
    for name in ("a", "b"):
        assert _evaluate(root / name, MASKS) == 0
    return root / "a", root / "b"


# ---- boundary-offset: each session once ----------------------------------------------------


def test_evaluation_records_its_inputs_digests(twice: tuple[Path, Path]) -> None:
    inputs = _record(twice[0])["inputs"]
    sha = hashlib.sha256(MANIFEST.read_bytes()).hexdigest()
    assert inputs["manifest"] == {"file": str(MANIFEST.resolve()), "sha256": sha}
    ref = EXAMPLE_SESSION / "p00.0kpa.jpg"
    assert inputs["reference"] == {
        "file": "p00.0kpa.jpg",
        "sha256": hashlib.sha256(ref.read_bytes()).hexdigest(),
    }
    assert len(inputs["frames"]) == len(list(MASKS.glob("*.png")))
    for e in inputs["frames"]:
        assert e["sha256"] == hashlib.sha256((EXAMPLE_SESSION / e["file"]).read_bytes()).hexdigest()


def test_copied_evaluation_folders_are_refused_naming_both(
    twice: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    copies = [tmp_path / f"c{i}" for i in range(1, 6)]
    for c in copies:
        shutil.copytree(twice[0], c)
    assert main(["boundary-offset", *map(str, copies)]) == 2
    err = _one_line(capsys)
    assert str(copies[0] / "evaluation.json") in err and str(copies[1] / "evaluation.json") in err
    assert "one session" in err and "p00.0kpa.jpg" in err and "pooled over" not in err


def test_evaluate_run_twice_on_one_session_is_refused(twice: tuple[Path, Path]) -> None:
    with pytest.raises(ValueError, match=r"a/evaluation\.json and .*b/evaluation\.json: both read"):
        pool_offsets(list(twice))


def test_one_labelled_frame_shared_is_enough(twice: tuple[Path, Path], tmp_path: Path) -> None:
    """Labels of one session split over two runs share at least its reference frame; frames
    renamed in the second are named there."""
    record = _record(twice[1])
    record["inputs"]["reference"]["sha256"] = "f" * 64
    shared = record["inputs"]["frames"][7]
    record["inputs"]["frames"] = [{**shared, "file": "renamed.jpg"}]
    (tmp_path / "split").mkdir()
    (tmp_path / "split" / "evaluation.json").write_text(json.dumps(record))
    with pytest.raises(ValueError, match=rf"both read the frame {shared['file']} \(named renamed"):
        pool_offsets([twice[0], tmp_path / "split"])


def _rewrite(src: Path, dst: Path, inputs: object) -> Path:
    record = _record(src)
    if inputs is None:
        del record["inputs"]
    else:
        record["inputs"] = inputs
    dst.mkdir()
    (dst / "evaluation.json").write_text(json.dumps(record))
    return dst


def test_older_evaluation_without_digests_is_refused_not_pooled(
    twice: tuple[Path, Path], tmp_path: Path
) -> None:
    old = _rewrite(twice[0], tmp_path / "old", None)
    with pytest.raises(ValueError, match=r"old/evaluation\.json: records no digests .* again"):
        pool_offsets([old])
    bad = {"frames": [{"file": "x.jpg", "sha256": "nothex"}], "reference": None}
    odd = _rewrite(twice[0], tmp_path / "odd", bad)
    with pytest.raises(ValueError, match=r"odd/evaluation\.json: its inputs are malformed"):
        pool_offsets([odd])


def test_sessions_with_identical_manifests_still_pool(
    twice: tuple[Path, Path], tmp_path: Path
) -> None:
    """Sessions of one protocol share the manifest's bytes (names, pressures); their frames
    differ, and they are pooled (the check is on frames, not on the manifest)."""
    runs = []
    for i in range(5):
        inputs = _record(twice[0])["inputs"]
        for e in (inputs["reference"], *inputs["frames"]):
            e["sha256"] = hashlib.sha256(f"{i}{e['sha256']}".encode()).hexdigest()
        runs.append(_rewrite(twice[0], tmp_path / f"s{i}", inputs))
        record = _record(runs[-1])  # other contacts: other label areas
        for f in record["frames"]:
            f["label_area_px"] += i * bool(f["label_area_px"])
        (runs[-1] / "evaluation.json").write_text(json.dumps(record))
    pooled = pool_offsets(runs)
    assert len(pooled["sessions"]) == 5


# ---- evaluate: labels that cannot be contact labels -----------------------------------------


def _masks_with(tmp_path: Path, name: str, image: np.ndarray) -> Path:
    masks = tmp_path / "masks"
    shutil.copytree(MASKS, masks)
    cv2.imwrite(str(masks / name), image)
    return masks


def _contact(name: str = "p10.0kpa.png") -> np.ndarray:
    return cv2.imread(str(MASKS / name), cv2.IMREAD_GRAYSCALE) > 0


@pytest.mark.parametrize(
    ("kind", "said"),
    [
        ("background 50, contact 128", "no pixel is 0 (values 50, 128)"),
        ("all 255", "no pixel is 0 (values 255)"),
        ("inverted", "more than the"),
        ("alpha only", "in the alpha channel only"),
        ("white on transparent", "every colour value is 255 and the shape is in the alpha"),
    ],
)
def test_mask_that_cannot_be_a_contact_label_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, said: str
) -> None:
    c = _contact()
    image = {
        "background 50, contact 128": np.where(c, 128, 50),
        "all 255": np.full(c.shape, 255),
        "inverted": np.where(c, 0, 255),
        "alpha only": np.dstack([np.zeros((*c.shape, 3)), np.where(c, 255, 0)]),  # BGRA
        "white on transparent": np.dstack([np.full((*c.shape, 3), 255), np.where(c, 255, 0)]),
    }[kind].astype(np.uint8)
    masks = _masks_with(tmp_path, "p10.0kpa.png", image)
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical") == 2
    err = _one_line(capsys)
    assert str(masks / "p10.0kpa.png") in err and said in err and "expected" in err
    assert not out.exists()


def test_documented_mask_forms_are_still_accepted(tmp_path: Path) -> None:
    """0 = background, anything > 0 = contact: a grey level of 1, a colour mask, all-zero."""
    masks = tmp_path / "masks"
    shutil.copytree(MASKS, masks)
    c = _contact()
    cv2.imwrite(str(masks / "p10.0kpa.png"), np.where(c, 1, 0).astype(np.uint8))
    red = np.zeros((*c.shape, 3), np.uint8)
    red[..., 2] = np.where(_contact("p15.0kpa.png"), 200, 0)
    cv2.imwrite(str(masks / "p15.0kpa.png"), red)
    opaque = np.dstack([np.where(_contact("p20.0kpa.png"), 255, 0)] * 3 + [np.full(c.shape, 255)])
    cv2.imwrite(str(masks / "p20.0kpa.png"), opaque.astype(np.uint8))  # BGRA, alpha uniform
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical") == 0
    areas = {f["file"]: f["label_area_px"] for f in _record(out)["frames"]}
    assert areas["p10.0kpa.jpg"] == int(c.sum())
    assert areas["p15.0kpa.jpg"] == int(_contact("p15.0kpa.png").sum())
    assert areas["p20.0kpa.jpg"] == int(_contact("p20.0kpa.png").sum())
    assert areas["p00.0kpa.jpg"] == 0


@pytest.mark.parametrize(
    ("row", "said"),
    [
        ("p10.0kpa.jpg,200,150,1000,1000,0", "runs 350 px past the edge of the 400×300 px"),
        ("p10.0kpa.jpg,390,290,600,500,0", "runs 290 px past the edge"),  # clipped: 3.6× off
        ("p10.0kpa.jpg,200,150,380,280,0", "inside the window ring (radius 132 px"),
        # an ellipse in mm (ImageJ's scale left on): a small patch near the frame's corner
        ("p10.0kpa.jpg,26,21,9,7,0", "lies mostly outside the window ring (centre"),
    ],
)
def test_ellipse_larger_than_the_window_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], row: str, said: str
) -> None:
    labels = tmp_path / "labels.csv"
    labels.write_text(HEADER + row + "\n", encoding="utf-8")
    out = tmp_path / "out"
    assert _evaluate(out, labels, "--method", "classical") == 2
    err = _one_line(capsys)
    assert f"{labels} row 1" in err and said in err
    assert not out.exists()


def test_window_bound_and_its_absence(tmp_path: Path) -> None:
    window = find_window(ImageFile.read(EXAMPLE_SESSION / "p00.0kpa.jpg"))
    assert window is not None and 120 < window.radius_px < 145
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((300, 400), 90, np.uint8))
    assert find_window(ImageFile.read(blank)) is None  # no ring: only the frame bounds a label
    label = Label(tmp_path / "f.png", tmp_path / "f_mask.png", None, None)
    big = LabelMask(np.ones((300, 400), bool), 119_999, None)
    check_label_area(label, big, (400, 300), None)
    with pytest.raises(LabelError, match="f_mask.png: labels 119999 px"):
        check_label_area(label, big, (400, 300), Window(blank, 100.0))
    check_label_area(label, LabelMask(big.mask, 36_000, None), (400, 300), Window(blank, 100.0))


def test_the_rig_config_is_never_overwritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --rig named like evaluate's own output in --out: refused, kept byte for byte."""
    out = tmp_path / "out"
    out.mkdir()
    rig = out / "evaluation.json"
    rig.write_text('{"mm_per_px": 0.1, "image_width_px": 400}', encoding="utf-8")
    before = rig.read_bytes()
    assert _evaluate(out, MASKS, "--method", "classical", "--rig", str(rig)) == 2
    assert "is an input of this run" in _one_line(capsys) and rig.read_bytes() == before


# ---- the session's units and scale ------------------------------------------------------------


def test_records_the_scale_it_used(twice: tuple[Path, Path]) -> None:
    rig = json.loads((EXAMPLE_SESSION / "rig.json").read_text(encoding="utf-8"))
    record = _record(twice[0])
    assert record["mm_per_px"] == rig["mm_per_px"]
    assert record["scale_image_width_px"] == rig["image_width_px"]
    assert record["warning"] is None


def test_refuses_a_manifest_in_bar(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Pressures in bar (0-0.2) would all score in the 0-3 kPa bin; calibrate refuses them too."""
    session = tmp_path / "bar"
    shutil.copytree(EXAMPLE_SESSION, session)
    rows = (session / "manifest.csv").read_text(encoding="utf-8").splitlines()
    bar = [rows[0]] + [f"{f},{float(p) / 100:g}" for f, p in (r.split(",")[:2] for r in rows[1:])]
    (session / "manifest.csv").write_text("\n".join(bar) + "\n", encoding="utf-8")
    argv = ["evaluate", str(session / "manifest.csv"), "--labels", str(session / "masks")]
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    assert "below 1 kPa" in _one_line(capsys)
    assert not (tmp_path / "out").exists()


def test_a_soft_edged_mask_is_read_at_half_its_largest_value_and_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A paint tool's anti-aliased edge (grey levels between 0 and 255) is not counted as
    contact in full: the mask reads at 128, as its hard version does, and the run says so."""
    c = _contact().astype(np.float32)
    soft = cv2.GaussianBlur(c, (0, 0), 1.0)  # edge pixels 0 < v < 1; the patch's core 1
    image = np.round(255 * soft).astype(np.uint8)
    masks = _masks_with(tmp_path, "p10.0kpa.png", image)
    out = tmp_path / "out"
    assert _evaluate(out, masks, "--method", "classical") == 0
    frames = {f["file"]: f for f in _record(out)["frames"]}
    assert frames["p10.0kpa.jpg"]["label_area_px"] == int(np.count_nonzero(image > 127.5))
    assert abs(frames["p10.0kpa.jpg"]["label_area_px"] - c.sum()) < 0.02 * c.sum()
    assert frames["p10.0kpa.jpg"]["label_note"].startswith("soft edge: ")
    assert frames["p15.0kpa.jpg"]["label_note"] is None  # the exact masks: read as drawn
    assert "note: 1 mask(s) with a soft edge" in capsys.readouterr().out


def test_two_masks_of_one_frame_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "probe").write_text("")
    if (tmp_path / "PROBE").exists():
        pytest.skip("a case-insensitive file system holds one of x.png and x.PNG")
    masks = _masks_with(tmp_path, "p10.0kpa.PNG", np.zeros((300, 400), np.uint8))
    assert _evaluate(tmp_path / "out", masks, "--method", "classical") == 2
    err = _one_line(capsys)
    assert "p10.0kpa" in err and "expected one mask per frame" in err


def test_a_mask_saved_as_jpeg_is_refused_with_advice_that_fits_a_mask(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A JPEG named .png was told "rename it to .jpg"; a .jpg mask was then skipped silently."""
    ok, jpeg = cv2.imencode(".jpg", (_contact() * 255).astype(np.uint8))
    assert ok
    masks = _masks_with(tmp_path, "unused.png", np.zeros((300, 400), np.uint8))
    (masks / "unused.png").unlink()
    (masks / "p10.0kpa.png").write_bytes(jpeg.tobytes())
    assert _evaluate(tmp_path / "out", masks, "--method", "classical") == 2
    err = _one_line(capsys)
    assert "p10.0kpa.png: not a PNG file (its content is a JPEG image); masks must be PNG" in err
    (masks / "p10.0kpa.png").rename(masks / "p10.0kpa.jpg")
    assert _evaluate(tmp_path / "out", masks, "--method", "classical") == 2
    assert "p10.0kpa.jpg: a .jpg image in the mask folder; masks must be PNG" in _one_line(capsys)
    assert not (tmp_path / "out").exists()


def test_masks_beside_the_jpeg_frames_are_still_read(tmp_path: Path) -> None:
    """The frames themselves are not taken for JPEG masks when the masks lie beside them."""
    session = tmp_path / "session"
    shutil.copytree(EXAMPLE_SESSION, session)
    for mask in (session / "masks").iterdir():
        mask.rename(session / mask.name)
    argv = ["evaluate", str(session / "manifest.csv"), "--labels", str(session)]
    assert main([*argv, "--out", str(tmp_path / "out"), "--method", "classical"]) == 0
    labelled = len(list((EXAMPLE_SESSION / "masks").glob("*.png")))
    assert len(_record(tmp_path / "out")["frames"]) == labelled


def test_an_evaluation_replaced_in_out_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A second run into one --out replaced the first evaluation without a word."""
    out = tmp_path / "out"
    assert _evaluate(out, MASKS, "--method", "classical") == 0
    assert "note: replaced" not in capsys.readouterr().out
    assert _evaluate(out, MASKS, "--method", "classical") == 0
    said = capsys.readouterr().out
    assert f"note: replaced an earlier evaluation of this manifest that {out} held" in said
    other = tmp_path / "session2"
    shutil.copytree(EXAMPLE_SESSION, other)
    argv = ["evaluate", str(other / "manifest.csv"), "--labels", str(other / "masks")]
    assert main([*argv, "--out", str(out), "--method", "classical"]) == 0
    assert (
        f"note: replaced the evaluation of {MANIFEST.resolve()} that {out}"
        in capsys.readouterr().out
    )
    (out / "evaluation.json").write_text("{", encoding="utf-8")
    assert main([*argv, "--out", str(out), "--method", "classical"]) == 0
    assert "not readable as an evaluation" in capsys.readouterr().out

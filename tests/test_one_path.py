"""One path: training (cache + validation scoring) and the deployed segmenter agree exactly.

A session is fed through both paths with the shipped model as the network: the training path
(`contactcal.train.data.build_cache` → onnxruntime → `contactcal.train.metrics.score_batch`) and
the deployed one (`UnetMethod` through `measure_files`). Network inputs and areas must be
identical, with a normal reference frame, with a reference whose ring is not visible, and
without a reference at all.
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from contactcal.infer.bench.dataset import REQUIRED_COLUMNS, IndexRow, read_index, sessions_of  # noqa: E402
from contactcal.infer.image.gray import ImageError  # noqa: E402
from contactcal.infer.image.read import ImageFile, load_image  # noqa: E402
from contactcal.infer.methods.unet.method import UnetMethod  # noqa: E402
from contactcal.infer.methods.unet.prepare import prepare, session_reference  # noqa: E402
from contactcal.infer.methods.unet.ring import locate_ring  # noqa: E402
from contactcal.infer.pipeline.measure import measure_files  # noqa: E402
from contactcal.train.data import build_cache  # noqa: E402
from contactcal.train.metrics import score_batch  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "session"
PRESSURES = (0.0, 2.0, 4.0, 8.0, 14.0, 20.0)


def _example_dataset(root: Path) -> Path:
    """The bundled (rendered) example session as a one-finger dataset, frames as PNG."""
    with open(EXAMPLE / "truth.csv", newline="") as fh:
        truth = {float(r["pressure_kpa"]): r for r in csv.DictReader(fh)}
    session = root / "finger_0000"
    (session / "frames").mkdir(parents=True)
    (session / "masks").mkdir()
    rows = []
    for p in PRESSURES:
        stem = f"p{p:04.1f}kpa"
        # PNG: the deployed method then decodes fully, as training does.
        cv2.imwrite(
            str(session / "frames" / f"{stem}.png"), cv2.imread(str(EXAMPLE / f"{stem}.jpg"))
        )
        shutil.copy(EXAMPLE / "masks" / f"{stem}.png", session / "masks" / f"{stem}.png")
        t = truth[p]
        rows.append(
            [
                0,
                session.name,
                f"{session.name}/frames/{stem}.png",
                f"{session.name}/masks/{stem}.png",
                p,
                t["contact"],
                t["area_px"],
                0.05,
                2.35,
                0,
            ]
        )
    with open(root / "index.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(REQUIRED_COLUMNS)  # the rows above are in this order
        w.writerows(rows)
    return root


def _hide_ring(path: Path) -> None:
    """Overwrite a frame with a low-contrast copy in which no ring is found."""
    gray = load_image(path)
    flat = np.clip(gray * 0.2 + 80.0, 0, 255).astype(np.uint8)
    assert not locate_ring(flat).found, "precondition: the ring must not be found"
    cv2.imwrite(str(path), flat)


def _deployed(unet: UnetMethod, rows: list[IndexRow], reference: Path | None):
    """Network inputs and areas of the deployed segmenter (inputs captured at the network)."""
    seen: list[np.ndarray] = []
    run = unet.segmenter.probabilities

    def spy(x: np.ndarray) -> np.ndarray:
        seen.append(x.copy())
        return run(x)

    unet.segmenter.probabilities = spy  # type: ignore[method-assign]
    if reference is not None and not locate_ring(load_image(reference)).found:
        # measure_files refuses a dark reference beside lit frames; the method itself (as
        # bench and the robustness suite call it) still runs the one path
        with pytest.raises(ImageError, match="shows no window ring"):
            measure_files([r.frame for r in rows], unet, reference)
        seen.clear()
        unet.start([r.frame for r in rows], ImageFile.read(reference))
        areas = [unet.measure(load_image(r.frame)).area_px for r in rows]
        return np.stack(seen), areas
    measured = measure_files([r.frame for r in rows], unet, reference)
    return np.stack(seen), [m.result.area_px for m in measured]


def _training(unet: UnetMethod, rows: list[IndexRow], reference: bool):
    """Network inputs and areas of the training path (cache, then validation scoring)."""
    spec = unet.segmenter.spec
    cache = build_cache(rows, spec.preprocess, spec.channels)
    x = cache.x.float().numpy()
    if not reference:  # the path training's functions take for a frame without a reference
        none = session_reference(None, spec.preprocess)
        preps = [prepare(load_image(r.frame), none, spec.preprocess, spec.channels) for r in rows]
        x = np.stack([p.x for p in preps])
        cache.boxes[:] = [p.box for p in preps]
    prob = np.stack([unet.segmenter.probabilities(xi) for xi in x])
    return x, [f.area_px for f in score_batch(prob, cache, 0, spec)]


@pytest.mark.parametrize("case", ["reference", "reference without ring", "no reference"])
def test_training_and_deployment_agree(tmp_path: Path, case: str) -> None:
    root = _example_dataset(tmp_path / "data")
    rows = next(iter(sessions_of(read_index(root)).values()))
    if case == "reference without ring":
        _hide_ring(rows[0].frame)
    unet = UnetMethod()
    reference = None if case == "no reference" else rows[0].frame
    x_train, a_train = _training(unet, rows, reference is not None)
    x_dep, a_dep = _deployed(unet, rows, reference)
    assert x_dep.shape == x_train.shape == (len(rows), unet.segmenter.spec.channels, 192, 192)
    np.testing.assert_array_equal(x_dep, x_train)
    assert a_dep == a_train
    if case == "reference":  # the shared path also measures well here
        truth = [r.area_px for r in rows]
        assert [a > 0 for a in a_dep] == [t > 0 for t in truth]
        assert all(abs(a / t - 1) < 0.1 for a, t in zip(a_dep, truth, strict=True) if t > 1000)


@pytest.mark.slow
def test_rendered_session_agrees(tmp_path: Path) -> None:
    """A session rendered here (Mitsuba, tiny) through both paths."""
    pytest.importorskip("mitsuba")
    from contactcal.infer.cli import main

    out = tmp_path / "r"
    args = [
        "synth",
        "--fingers",
        "1",
        "--pressures",
        "0,4,12",
        "--size",
        "160x120",
        "--spp",
        "2",
        "--seed",
        "11",
        "--hard-fraction",
        "0",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    rows = next(iter(sessions_of(read_index(out)).values()))
    unet = UnetMethod()
    for reference in (rows[0].frame, None):
        x_train, a_train = _training(unet, rows, reference is not None)
        x_dep, a_dep = _deployed(UnetMethod(), rows, reference)
        np.testing.assert_array_equal(x_dep, x_train)
        assert a_dep == a_train

"""Calibrate the U-Net's change gate (metadata ``min_change``) on validation renders.

A kept region whose mean |frame − reference| (network input units,
:func:`~contactcal.infer.methods.unet.postprocess.region_change`) is below ``min_change`` is
"no contact": a bright speck on the window, or a pre-contact reflection, is already in the
session's zero-pressure frame, while contact changes the image where it happens. The threshold is
read here from validation frames, never from the benchmark:

* every frame above the session's lowest pressure where the model keeps a region (the gate off),
  as rendered and, with ``specks``, with ``draws`` window specks per session at each level (the
  robustness suite's :func:`~contactcal.infer.bench.perturb.speck`, the same speck in the
  reference frame; draw ``d`` of session ``s`` seeded ``[seed, s, d]`` at every level);
* :func:`margin_threshold`: :data:`MARGIN` times below the smallest change of a region in
  contact, so that no validation contact is lost and a camera change that shrinks every change
  (lower contrast ~0.85× at the suite's 0.75, blur) still leaves the first contacts above it.

``python -m contactcal.train.change_gate MODEL --data DIR... [--speck L...] --out NEW.onnx``
writes the model again with ``min_change`` set (graph and weights copied untouched). It refuses a
folder given twice and the model's training data as far as the model records it, and records in
the ``min_change`` entry what it was calibrated on (:mod:`contactcal.train.calibration_data`).
The model's interval was calibrated with its previous gate (the gate decides which frames are in
contact), so the output says to calibrate the interval again.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.bench.dataset import read_index, sessions_of
from contactcal.infer.bench.perturb import speck
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.infer.methods.unet.ring import locate_ring
from contactcal.train.calibration_data import calibration_data, calibration_folders, with_record
from contactcal.train.restate import (
    check_paths,
    metadata_of,
    read_model,
    restating_parser,
    run_restating,
    save_restated,
    stale,
)

#: The gate sits this factor below the smallest change of a validation region in contact. The
#: largest gate that loses no validation contact would sit just below that change (0.3 % on
#: v2.3's validation renders), where any camera change that shrinks changes loses first contacts;
#: 2 rejects fewer false regions (86 against 131 of 157 there) with room for such changes.
MARGIN = 2.0


def margin_threshold(change: np.ndarray, contact: np.ndarray) -> tuple[float, dict[str, Any]]:
    """The gate :data:`MARGIN` times below the smallest change of a region in contact.

    Args:
        change: ``(N,)`` kept regions' changes, network input units (>= 0).
        contact: ``(N,) bool`` whether each region's frame is truly in contact.

    Returns:
        ``(min_change, summary)``: ``min_change = hi / MARGIN``, ``hi`` the smallest true change;
        the summary counts the false regions it removes.

    Raises:
        ValueError: no region in a frame with true contact, or a change that is not finite.
    """
    change, contact = np.asarray(change, np.float64), np.asarray(contact, bool)
    if change.shape != contact.shape or not np.all(np.isfinite(change)):
        raise ValueError(f"expected finite changes, one per region; got shape {change.shape}")
    if not contact.any():
        raise ValueError(
            "no region in a frame in contact (data without contact, or a model that segments "
            "none of it); expected frames in contact that the model segments"
        )
    hi = float(change[contact].min())
    t = hi / MARGIN
    false = change[~contact]
    summary = {
        "regions_true": int(contact.sum()),
        "regions_false": int(false.size),
        "smallest_true_change": hi,
        "margin": MARGIN,
        "false_removed": int((false < t).sum()),
        "min_change": t,
    }
    return t, summary


def _session_changes(
    m: UnetMethod, grays: list[np.ndarray], contact: list[bool]
) -> list[tuple[float, bool]]:
    """``(change, contact)`` of each kept region of one session (frames after the first)."""
    m.set_reference(grays[0])
    out = []
    for gray, truth in zip(grays[1:], contact[1:], strict=True):
        img, _ = m._shrunk(gray)
        seg = m.segmenter.segment(img, m.reference)
        if seg.change is not None:
            out.append((seg.change, truth))
    return out


def _check_options(specks: Sequence[float], draws: int, seed: int) -> None:
    """Raise ValueError naming the option (``--speck``, ``--draws``, ``--seed``) that is bad."""
    bad = [s for s in specks if not 0.0 < s <= 1.0]
    if bad:
        raise ValueError(f"--speck {bad[0]:g}: expected speck levels in (0, 1] (fraction of white)")
    if draws < 1:
        raise ValueError(f"--draws {draws}: expected at least 1 speck per session and level")
    if seed < 0:
        raise ValueError(f"--seed {seed}: expected an integer >= 0 (numpy seeds are not negative)")


def collect_changes(
    model: str | os.PathLike[str],
    data_dirs: Sequence[str | os.PathLike[str]],
    specks: Sequence[float] = (),
    draws: int = 1,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, dict[str, int]]:
    """Every kept region's change, the gate off, through the deployment path.

    Args:
        model: an exported ``.onnx`` model with a reference channel.
        data_dirs: ``contactcal synth`` datasets (each session's lowest pressure is its
            reference frame).
        specks: window speck levels (fraction of white, (0, 1]) added besides the frames as
            rendered.
        draws: specks per session and level.
        seed: the specks' places and sizes; session ``s`` of a dataset (counted from 0 in each)
            and draw ``d`` use ``default_rng([seed, s, d])`` at every level.

    Returns:
        ``(change (N,), contact (N,) bool, frames measured per speck level)``.

    Raises:
        ValueError: a speck level outside (0, 1], ``draws`` < 1 or ``seed`` < 0 (the message
            names the option: ``--speck``, ``--draws``, ``--seed``).
    """
    _check_options(specks, draws, seed)
    return _changes(UnetMethod(model, change_gate=False), data_dirs, specks, draws, seed)


def _changes(
    m: UnetMethod,
    data_dirs: Sequence[str | os.PathLike[str]],
    specks: Sequence[float],
    draws: int,
    seed: int,
) -> tuple[np.ndarray, np.ndarray, dict[str, int]]:
    """:func:`collect_changes` through ``m`` (the gate off), the options checked."""
    cfg = m.segmenter.spec.preprocess
    rows: list[tuple[float, bool]] = []
    frames: dict[str, int] = {}
    for d in data_dirs:
        for s, sess in enumerate(sessions_of(read_index(Path(d))).values()):
            sess = sorted(sess, key=lambda r: r.pressure_kpa)
            grays = [load_image(r.frame) for r in sess]
            truth = [bool(r.contact) for r in sess]
            ring = locate_ring(grays[0], cfg)
            for level in (0.0, *specks):
                for k in range(draws if level > 0.0 else 1):
                    # One speck on the window: the same place and size in every frame.
                    rng = [np.random.default_rng([seed, s, k]) for _ in grays]
                    g = [speck(x, level, r, ring=ring) for x, r in zip(grays, rng, strict=True)]
                    rows += _session_changes(m, g, truth)
                    frames[str(level)] = frames.get(str(level), 0) + len(grays) - 1
    change = np.array([c for c, _ in rows], np.float64)
    return change, np.array([t for _, t in rows], bool), frames


def gate_model(
    model: str | os.PathLike[str],
    data_dirs: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    specks: Sequence[float] = (),
    draws: int = 1,
    seed: int = 0,
) -> dict[str, Any]:
    """Write ``model`` with its ``min_change`` calibrated on ``data_dirs`` to ``out``.

    Args:
        model: an exported ``.onnx`` model with a reference channel.
        data_dirs: ``contactcal synth`` datasets that are neither its training, its benchmark
            nor any held-out check data; what of this is checked:
            :mod:`contactcal.train.calibration_data`.
        out: the new ``.onnx`` file; must not be ``model`` (inputs are never overwritten).
        specks, draws, seed: window specks added to the frames (:func:`collect_changes`).

    Returns:
        The summary (:func:`margin_threshold`) with the frames measured per speck level, the
        datasets' record (``data``, also written in the ``min_change`` entry) and ``stale``
        (:func:`~contactcal.train.restate.stale`: the interval, when the gate changed).

    Raises:
        ValueError: bad output name or option, a path that is no dataset folder, a folder given
            twice, the model's training data, a model without a reference channel, or data
            without a region in contact; the cheap checks (output, options, folders) come
            before the model is loaded.
    """

    src, dst = check_paths(model, out)
    _check_options(specks, draws, seed)  # the cheap checks first: no model loaded for a typo
    dirs = calibration_folders(data_dirs)  # the folders before the model is read
    content, proto = read_model(src)  # once: the model measured is the model rewritten
    record = calibration_data(dirs, metadata_of(proto))
    m = UnetMethod(src, change_gate=False, content=content)
    base = dataclasses.replace(m.segmenter.spec, min_change=m.model_min_change)
    if not base.uses_reference:
        raise ValueError(f"{src}: the change gate needs a model with a reference channel")
    change, contact, frames = _changes(m, dirs, specks, draws, seed)
    try:
        t, summary = margin_threshold(change, contact)
    except ValueError as exc:  # named: which data, which model
        raise ValueError(f"--data {' '.join(map(str, dirs))}: {src}: {exc}") from None
    spec = dataclasses.replace(base, min_change=t)
    entry = with_record(spec.to_metadata()["min_change"], record)
    save_restated(proto, {"min_change": entry}, spec, dst)
    extra = {"specks": list(specks), "draws": draws, "seed": seed, "data": record}
    again = stale(["interval"] if t != base.min_change else [], dst)
    return {**summary, "frames": frames, **extra, "stale": again}


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m contactcal.train.change_gate MODEL --data DIR... --out NEW.onnx``."""
    ap = restating_parser(
        "python -m contactcal.train.change_gate",
        "Calibrate an exported model's change gate (metadata min_change only) on validation "
        "renders.",
    )
    ap.add_argument(
        "--speck", type=float, nargs="*", default=[], help="window speck levels to add (0-1]"
    )
    ap.add_argument("--draws", type=int, default=3, help="specks per session and level")
    ap.add_argument("--seed", type=int, default=0, help="seeds the specks' places and sizes")
    a = ap.parse_args(argv)
    return run_restating(
        lambda: gate_model(a.model, a.data, a.out, a.speck, a.draws, a.seed), a.out
    )


if __name__ == "__main__":
    raise SystemExit(main())

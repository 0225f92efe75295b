"""``contactcal boundary-offset``: one rig's offset pooled over several sessions' evaluations,
and the distribution-free interval of a median it shares with ``evaluate``."""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from contactcal.infer.cli import main
from contactcal.infer.evaluate.offset import median_interval, offset_line, resolved_offset
from contactcal.infer.evaluate.pool import pool_offsets, pooled_text
from contactcal.infer.pipeline.boundary import MODEL_KEY, OFFSET_KEY

SHA = "ab" * 32


def _inputs(folder: Path) -> dict[str, object]:
    """``evaluate``'s input digests for a session of its own (distinct frames per folder)."""

    def entry(name: str) -> dict[str, str]:
        return {"file": name, "sha256": hashlib.sha256(f"{folder}/{name}".encode()).hexdigest()}

    manifest = {"file": "manifest.csv", "sha256": "0" * 64}  # alike in every session
    return {"manifest": manifest, "reference": entry("p0.png"), "frames": [entry("p5.png")]}


def _evaluation(
    folder: Path, offsets: object, sha: str = SHA, applied: float | None = None
) -> Path:
    folder.mkdir(parents=True)
    off = {"model_sha256": sha, "applied_mm": applied, "frame_offsets_mm": offsets}
    record = {"inputs": _inputs(folder), "frames": [], "boundary_offset": off}
    (folder / "evaluation.json").write_text(json.dumps(record))
    return folder


def _five(tmp_path: Path, centres: tuple[float, ...], **kw: object) -> list[Path]:
    return [
        _evaluation(tmp_path / f"s{i}", [c - 0.02, c - 0.01, c, c + 0.01, c + 0.03], **kw)
        for i, c in enumerate(centres)
    ]


def test_median_interval_is_the_sign_tests() -> None:
    assert median_interval([3, 1, 2, 5, 4]) == (1.0, 5.0)  # n = 5: [min, max], 93.75 %
    assert median_interval(range(1, 11)) == (2.0, 9.0)  # n = 10: k = 2, 97.9 %; k = 3: 89 %
    lo, hi = median_interval(np.arange(100.0))
    assert (lo, hi) == (41.0, 58.0)  # ≈ 50 ± 1.645·√100/2
    with pytest.raises(ValueError, match="at least 5 values, got 4"):
        median_interval([1, 2, 3, 4])
    assert resolved_offset([0.1, 0.2, 0.15, 0.12, 0.3]) == pytest.approx(0.15)
    assert resolved_offset([0.1, -0.2, 0.15, 0.12, 0.3]) == 0.0  # one sign differs: [min, max]
    assert resolved_offset([0.1, 0.2, 0.15, 0.12]) == 0.0  # too few to resolve


def test_false_resolves_stay_near_the_level() -> None:
    """A zero offset resolved in at most ~10 % of noise draws, for any count from 5 up (the
    frame bootstrap it replaces resolved one in 2 with 2 values, 1 in 7 with 5)."""
    rng = np.random.default_rng(0)
    for n in (5, 6, 8, 12, 30):
        hits = [resolved_offset(rng.normal(0.0, 0.1, n)) != 0.0 for _ in range(2000)]
        assert np.mean(hits) <= 0.10 + 3 * math.sqrt(0.1 * 0.9 / 2000), n


def test_sessions_agreeing_on_an_offset_give_the_keys(tmp_path: Path) -> None:
    runs = _five(tmp_path, (0.15, 0.2, 0.18, 0.22, 0.17))
    pooled = pool_offsets(runs)
    assert pooled["median_mm"] == pytest.approx(0.18)
    assert pooled["interval_mm"] == pytest.approx((0.15, 0.22))
    assert pooled["rig_config"] == {OFFSET_KEY: 0.18, MODEL_KEY: SHA}
    again = pool_offsets([r / "evaluation.json" for r in runs])
    assert again["rig_config"] == pooled["rig_config"]
    applied = _five(tmp_path / "a", (0.05, 0.06, 0.04, 0.07, 0.05), applied=0.1)
    assert pool_offsets(applied)["rig_config"][OFFSET_KEY] == pytest.approx(0.15)
    far = _evaluation(tmp_path / "far", [4.2, 4.25, 4.3, 4.2, 4.1])  # evaluate: "does not fit"
    with pytest.raises(ValueError, match=r"far/evaluation\.json: this session's offset \+4\.200"):
        pool_offsets([*runs[:4], far])
    near = _five(tmp_path / "near", (1.95, 1.96, 1.97, 1.98, 1.99))
    assert pool_offsets(near)["rig_config"][OFFSET_KEY] == pytest.approx(1.97)
    edge = _evaluation(tmp_path / "edge", [2.0002, 2.0003, 2.0004, 2.0005, 2.0006])
    assert pool_offsets([*near[:4], edge])["rig_config"] is not None  # 2.000 mm, as evaluate


def test_sessions_that_disagree_about_the_sign_give_none(tmp_path: Path) -> None:
    pooled = pool_offsets(_five(tmp_path, (-0.1, 0.12, -0.05, 0.08, 0.2)))
    assert pooled["rig_config"] is None and "includes 0" in pooled_text(pooled)


def test_bad_sets_of_evaluations(tmp_path: Path) -> None:
    good = _five(tmp_path, (0.1, 0.2, 0.15, 0.12, 0.3))
    with pytest.raises(ValueError, match="given twice"):
        pool_offsets([*good[:4], good[0] / "evaluation.json"])
    with pytest.raises(ValueError, match="pooling needs 5"):
        pool_offsets(good[:4])
    short = _evaluation(tmp_path / "short", [0.1, 0.2])
    assert pool_offsets([*good, short])["left_out"] == [str(short / "evaluation.json")]
    with pytest.raises(ValueError, match="differ in model"):
        pool_offsets([*good[:4], _evaluation(tmp_path / "b", [0.1] * 5, sha="cd" * 32)])
    with pytest.raises(ValueError, match="differ in the boundary offset already applied"):
        pool_offsets([*good[:4], _evaluation(tmp_path / "c", [0.1] * 5, applied=0.2)])
    bad = {
        "px": (None, "in pixels only"),
        "nan": ([0.1, float("nan"), 0.1, 0.1, 0.1], "not finite numbers"),
        "str": (["0.1"] * 5, "not finite numbers"),
        "num": (0.1, "not finite numbers"),
    }
    for name, (offsets, said) in bad.items():
        with pytest.raises(ValueError, match=rf"{name}/evaluation\.json: .*{said}"):
            pool_offsets([*good[:4], _evaluation(tmp_path / name, offsets)])
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "evaluation.json").write_text(json.dumps({"boundary_offset": None}))
    (tmp_path / "list").mkdir()
    (tmp_path / "list" / "evaluation.json").write_text("[1, 2]")
    for name in ("old", "list"):
        with pytest.raises(ValueError, match=rf"{name}/evaluation\.json: has no U-Net"):
            pool_offsets([*good[:4], tmp_path / name])
    (tmp_path / "empty").mkdir()  # said missing, and what writes it, not "not a readable ..."
    said = "missing; expected the evaluation.json that `contactcal evaluate ... --out DIR` writes"
    for given in (tmp_path / "empty", tmp_path / "typo"):
        file = given / "evaluation.json" if given.is_dir() else given
        with pytest.raises(ValueError, match=f"^{re.escape(f'{file}: {said}')}"):
            pool_offsets([*good[:4], given])
    (tmp_path / "empty" / "evaluation.json").write_text("{")
    with pytest.raises(ValueError, match="empty/evaluation.json: not a readable evaluation.json"):
        pool_offsets([*good[:4], tmp_path / "empty"])
    (tmp_path / "nested" / "evaluation.json").mkdir(parents=True)  # was ".../evaluation.json
    folder = tmp_path / "nested" / "evaluation.json"  # /evaluation.json: missing", joined twice
    said = f"{folder}: is a folder; expected the evaluation.json of `contactcal evaluate`"
    with pytest.raises(ValueError, match=f"^{re.escape(said)}$"):
        pool_offsets([*good[:4], tmp_path / "nested"])


def test_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    runs = [str(p) for p in _five(tmp_path, (0.15, 0.2, 0.18, 0.22, 0.17))]
    assert main(["boundary-offset", *runs]) == 0
    out = capsys.readouterr().out
    assert "pooled over 5 sessions: +0.180 mm" in out and '"boundary_offset_mm": 0.18' in out
    assert main(["boundary-offset", *runs[:2]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pooling needs 5" in err[0]


def test_one_sessions_keys_are_printed_with_the_pooling_they_need() -> None:
    """evaluate prints the keys of a resolved offset, but as one session's: a lab that pastes
    them is told to pool five or more sessions first."""
    off = {
        "stale": None,
        "frames": 18,
        "median_px": 0.24,
        "interval_px": [0.16, 0.31],
        "median_mm": 0.03,
        "interval_mm": [0.02, 0.039],
        "rig_config": {"boundary_offset_mm": 0.03, "boundary_offset_model_sha256": "ab"},
        "applied_mm": None,
        "applied_from": None,
    }
    text = offset_line(off)
    assert "one session's: pool five or more sessions' evaluations with `contactcal " in text
    assert text.endswith(
        'apply it: "boundary_offset_mm": 0.03, "boundary_offset_model_sha256": "ab"'
    )
    assert "note:" not in text  # no offset applied: nothing to say about one


def test_an_applied_offset_is_said_and_the_keys_state_the_total() -> None:
    """With the rig's offset applied the measured one is what remains: the text says which was
    applied (and from where), and that the keys hold the total, not the printed median."""
    off = {
        "stale": None,
        "frames": 18,
        "median_px": -14.8,
        "interval_px": [-15.0, -14.6],
        "median_mm": -1.87,
        "interval_mm": [-1.9, -1.85],
        "rig_config": {"boundary_offset_mm": 0.03, "boundary_offset_model_sha256": "ab"},
        "applied_mm": 1.9,
        "applied_from": "s/rig.json",
    }
    text = offset_line(off)
    assert text.startswith(
        "note: the U-Net's areas include the rig's boundary offset +1.900 mm (s/rig.json)"
    )
    assert "against the labels on top of the applied +1.900 mm, 18 frames: -1.870 mm" in text
    assert 'apply the total (+1.900 mm applied + this): "boundary_offset_mm": 0.03' in text

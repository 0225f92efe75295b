"""``contactcal boundary-offset``: one rig's offset pooled over several sessions' evaluations."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from contactcal.infer.cli import main
from contactcal.infer.evaluate.pool import pool_offsets, pooled_text
from contactcal.infer.pipeline.boundary import MODEL_KEY, OFFSET_KEY

SHA = "ab" * 32


def _evaluation(
    folder: Path, offsets: list[float] | None, sha: str = SHA, applied: float | None = None
) -> Path:
    folder.mkdir(parents=True)
    off = {"model_sha256": sha, "applied_mm": applied, "frame_offsets_mm": offsets}
    (folder / "evaluation.json").write_text(json.dumps({"boundary_offset": off}))
    return folder


def test_sessions_agreeing_on_an_offset_give_the_keys(tmp_path: Path) -> None:
    runs = [
        _evaluation(tmp_path / f"s{i}", [c - 0.02, c, c + 0.03])
        for i, c in enumerate((0.15, 0.2, 0.18, 0.22))
    ]
    pooled = pool_offsets(runs)
    assert pooled["median_mm"] == pytest.approx(0.19)
    lo, hi = pooled["interval_mm"]
    assert 0.15 <= lo <= 0.19 <= hi <= 0.22
    assert pooled["rig_config"] == {OFFSET_KEY: 0.19, MODEL_KEY: SHA}
    assert [s["frames"] for s in pooled["sessions"]] == [3, 3, 3, 3]
    again = pool_offsets(
        [r / "evaluation.json" for r in runs],
    )
    assert again == {**pooled, "sessions": again["sessions"]}
    applied = [_evaluation(tmp_path / f"a{i}", [0.05, 0.06], applied=0.1) for i in range(2)]
    assert pool_offsets(applied)["rig_config"][OFFSET_KEY] == pytest.approx(0.155)


def test_sessions_that_disagree_about_the_sign_give_none(tmp_path: Path) -> None:
    runs = [_evaluation(tmp_path / f"s{i}", [c]) for i, c in enumerate((-0.1, 0.12, -0.05, 0.08))]
    pooled = pool_offsets(runs)
    assert pooled["rig_config"] is None and "nothing to change" in pooled_text(pooled)


def test_bad_sets_of_evaluations(tmp_path: Path) -> None:
    a = _evaluation(tmp_path / "a", [0.1, 0.2])
    with pytest.raises(ValueError, match="2 or more"):
        pool_offsets([a])
    b = _evaluation(tmp_path / "b", [0.1], sha="cd" * 32)
    with pytest.raises(ValueError, match="differ in model"):
        pool_offsets([a, b])
    c = _evaluation(tmp_path / "c", [0.1], applied=0.2)
    with pytest.raises(ValueError, match="differ in the boundary offset already applied"):
        pool_offsets([a, c])
    d = _evaluation(tmp_path / "d", None)
    with pytest.raises(ValueError, match=r"d/evaluation\.json: has no U-Net boundary offsets"):
        pool_offsets([a, d])
    e = _evaluation(tmp_path / "e", [])
    with pytest.raises(ValueError, match="only 1 of the 2 evaluations"):
        pool_offsets([a, e])
    (tmp_path / "f").mkdir()
    with pytest.raises(ValueError, match="not a readable evaluation.json"):
        pool_offsets([a, tmp_path / "f"])


def test_cli_pools_two_evaluations(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("onnxruntime")
    example = Path(__file__).resolve().parents[1] / "examples" / "session"
    base = ["evaluate", str(example / "manifest.csv"), "--labels", str(example / "masks")]
    for name in ("e1", "e2"):
        assert main([*base, "--out", str(tmp_path / name)]) == 0
    capsys.readouterr()
    assert main(["boundary-offset", str(tmp_path / "e1"), str(tmp_path / "e2")]) == 0
    out = capsys.readouterr().out
    assert "pooled over 2 sessions" in out and "boundary_offset_model_sha256" in out
    assert main(["boundary-offset", str(tmp_path / "e1")]) == 2
    assert "2 or more" in capsys.readouterr().err

"""Bench figures: coinciding method curves stay visible and are named in the legend; a
robustness figure no sampled frame scores says so."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from contactcal.infer.bench.plots import (
    LINE_STYLES,
    legend_label,
    line_style,
    plot_error_vs_pressure,
    plot_robustness,
    same_as,
)
from contactcal.infer.bench.robustness_text import robustness_text
from contactcal.infer.bench.scoring import ScoredFrame

pytest.importorskip("matplotlib")


def _frames(method: str, errors: list[float]) -> list[ScoredFrame]:
    """One contact frame per pressure 5, 6, ... kPa with the given relative area errors."""
    return [
        ScoredFrame(
            method=method,
            session="s0",
            frame=f"p{5 + i:02d}.png",
            pressure_kpa=5.0 + i,
            true_area_px=1000.0,
            area_px=1000.0 * (1 + e),
            contact=True,
            mm_per_px=0.01,
        )
        for i, e in enumerate(errors)
    ]


def test_line_styles_differ_and_cycle() -> None:
    styles = [line_style(i) for i in range(len(LINE_STYLES))]
    assert len({(s["ls"], s["lw"]) for s in styles}) == len(LINE_STYLES)
    widths = [s["lw"] for s in styles]
    assert widths == sorted(widths, reverse=True)  # later lines thinner: earlier ones show
    assert line_style(len(LINE_STYLES)) == styles[0]
    line_style(0)["lw"] = 99.0  # a copy: the table is not changed
    assert LINE_STYLES[0]["lw"] != 99.0


def test_same_as_finds_only_an_exact_twin() -> None:
    a = np.array([[5.0, 1.0], [6.0, 2.0]])
    drawn = {"classical": a + 1.0, "unet": a.copy()}
    assert same_as(a, drawn) == "unet"
    assert same_as(a + 1e-9, drawn) is None
    assert same_as(a[:1], drawn) is None  # another shape
    assert same_as(a, {}) is None


def test_legend_names_a_hidden_twin() -> None:
    a = np.array([[5.0, 1.0], [6.0, 2.0]])
    drawn = {"classical": a + 1.0, "unet": a.copy()}
    assert legend_label("unet[v23]", a, drawn) == "unet[v23] (same as unet)"
    assert legend_label("unet[int8]", a * 1.01, drawn) == "unet[int8]"


def test_error_vs_pressure_with_identical_methods(tmp_path: Path, monkeypatch) -> None:
    from contactcal.infer.bench import plots

    labels: list[str] = []
    styles: list[int] = []

    def spy_label(method: str, curve: np.ndarray, drawn: dict) -> str:
        labels.append(legend_label(method, curve, drawn))
        return labels[-1]

    def spy_style(i: int) -> dict:
        styles.append(i)
        return line_style(i)

    monkeypatch.setattr(plots, "legend_label", spy_label)
    monkeypatch.setattr(plots, "line_style", spy_style)
    errs = [0.01, -0.02, 0.03]
    frames = _frames("unet", errs) + _frames("unet[v23]", errs) + _frames("classical", [0.4] * 3)
    out = tmp_path / "evp.png"
    plot_error_vs_pressure(out, frames)
    assert labels.count("unet[v23] (same as unet)") == 2  # both panels
    assert sorted(set(styles)) == [0, 1, 2]
    assert out.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in tmp_path.iterdir()] == ["evp.png"]  # no temporary left


def _robustness(no_contact_frames: int) -> dict[str, Any]:
    """A robustness result of 3 sampled frames, two perturbations of two levels each, one method
    (2 frames with contact at >= 5 kPa, ``no_contact_frames`` without contact)."""
    levels = {"levels": [0, 1], "labels": ["0", "1"], "baseline": 0}
    perts = [
        {"name": n, "unit": "u", "reference": "unperturbed", **levels} for n in ("blur", "noise")
    ]
    rows = [
        {
            "perturbation": p["name"],
            "level": level,
            "label": str(level),
            "in_range": True,
            "baseline": level == 0,
            "method": "unet",
            "median_abs_rel_error_ge5": 0.1,
            "error_ratio": 1.0,
            "error_ratio_interval": None,
            "error_change_points": 0.0,
            "contact_frames_ge5": 2,
            "no_contact_frames": no_contact_frames,
            "no_contact_accuracy": 1.0 if no_contact_frames else None,
        }
        for p in perts
        for level in (0, 1)
    ]
    return {"frames": ["a", "b", "c"], "seed": 0, "perturbations": perts, "rows": rows}


def _panel_texts(tmp_path: Path, monkeypatch, rob: dict[str, Any], metric: str) -> list[list]:
    """The texts drawn in each panel of :func:`plot_robustness`'s figure."""
    from contactcal.infer.bench import plots

    figures: list = []
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig))
    plot_robustness(tmp_path / "r.png", rob, metric)
    return [[t.get_text() for t in ax.texts] for ax in figures[0].axes if ax.get_visible()]


def test_no_contact_figure_of_a_sample_without_such_frames_says_so(
    tmp_path: Path, monkeypatch
) -> None:
    """No sampled frame without contact: each panel says so in place of its (absent) points."""
    said = "no frame without contact\nin the sample (3 frames)"
    assert _panel_texts(tmp_path, monkeypatch, _robustness(0), "no_contact") == [[said]] * 2
    assert _panel_texts(tmp_path, monkeypatch, _robustness(1), "no_contact") == [[], []]
    assert _panel_texts(tmp_path, monkeypatch, _robustness(0), "error") == [[], []]


def test_error_figure_of_a_sample_without_contact_at_5_kpa_says_so(
    tmp_path: Path, monkeypatch
) -> None:
    rob = _robustness(1)
    for r in rob["rows"]:
        r |= {"contact_frames_ge5": 0, "median_abs_rel_error_ge5": None, "error_ratio": None}
    said = "no frame with true contact at ≥ 5 kPa\nin the sample (3 frames)"
    assert _panel_texts(tmp_path, monkeypatch, rob, "error") == [[said]] * 2


def test_report_says_why_the_no_contact_figure_has_no_points() -> None:
    text = robustness_text(_robustness(0))
    assert "none of the 3 sampled frames is without true contact, so the figure has no" in text
    assert "](robustness_no_contact.png)" in text  # still embedded: its panels say why
    assert "none of the" not in robustness_text(_robustness(1))

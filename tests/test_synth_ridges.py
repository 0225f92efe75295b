"""Rendered ridges: their spatial period inside the contact matches the fingerprint's period."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

pytest.importorskip("mitsuba")

from contactcal.synth.camera import CameraEffects
from contactcal.synth.fingerprint import make_fingerprint
from contactcal.synth.randomize import sample_session
from contactcal.synth.ridge_period import ridge_period_px
from contactcal.synth.session import RenderConfig, render_session

pytestmark = pytest.mark.slow


def test_ridge_period_inside_contact_matches_texture() -> None:
    session = sample_session(np.random.default_rng(24))
    clean = CameraEffects(exposure=2.0, full_well=1e6, read_noise=0.0)  # no noise, blur, JPEG
    session = dataclasses.replace(session, camera=clean, ridge_contrast=1.0)
    config = RenderConfig(width=480, height=360, spp=4, weight_size=1024)
    out = next(iter(render_session(session, [14.0], config, seed=(0,))))
    assert out is not None and out.mask.sum() > 1000
    gray = cv2.cvtColor(out.frame, cv2.COLOR_RGB2GRAY).astype(np.float64)
    inner = cv2.erode(out.mask.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
    measured = ridge_period_px(gray, max_period_px=12.0, mask=inner)  # ridge band, not shading
    expected = make_fingerprint(np.random.default_rng(session.fingerprint_seed)).period_mm / (
        out.mm_per_px
    )
    print(f"ridge period {measured:.3f} px measured, {expected:.3f} px expected")
    assert measured == pytest.approx(expected, rel=0.08), (
        f"ridge period {measured:.2f} px in the render, {expected:.2f} px expected"
    )

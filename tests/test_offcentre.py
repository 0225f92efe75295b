"""End to end on a fresh render: an off-centre finger (hard case) through the shipped model."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

pytest.importorskip("mitsuba")

from contactcal.infer.image.gray import to_gray_u8
from contactcal.infer.methods.unet.method import UnetMethod
from contactcal.synth.randomize import sample_session
from contactcal.synth.session import RenderConfig, render_session

pytestmark = pytest.mark.slow


def test_off_centre_finger() -> None:
    session = sample_session(np.random.default_rng(24))  # well exposed, crisp ridges
    finger = dataclasses.replace(session.finger, offset_mm=(3.5, -2.5))  # ~0.35 a off-centre
    session = dataclasses.replace(session, finger=finger)
    config = RenderConfig(width=400, height=300, spp=8)
    ref, frame = render_session(session, [0.0, 12.0], config, seed=(24,))
    assert ref is not None and frame is not None
    ys, xs = np.nonzero(frame.mask)
    assert abs(xs.mean() - 199.5) + abs(ys.mean() - 149.5) > 15, "patch should be off-centre"
    unet = UnetMethod(outline=True)
    unet.set_reference(to_gray_u8(ref.frame))
    res = unet.measure(to_gray_u8(frame.frame))
    assert res.contact and res.contour is not None
    pred = np.zeros(frame.mask.shape, np.uint8)
    cv2.drawContours(pred, [res.contour], -1, 1, -1)
    iou = np.logical_and(pred > 0, frame.mask).sum() / np.logical_or(pred > 0, frame.mask).sum()
    rel = res.area_px / frame.mask.sum() - 1
    print(f"off-centre: IoU {iou:.3f}, relative area error {rel:+.3f}")
    assert iou > 0.85 and abs(rel) < 0.1, f"IoU {iou:.3f}, relative area error {rel:+.3f}"

"""Renderer smoke tests: variant choice, camera model, determinism, ring geometry, hit points.

Tiny frames (64x48, 2-4 spp); one renderer is shared by the module (loading is the slow part).
"""

from __future__ import annotations

import numpy as np
import pytest

from contactcal.synth.rig import RigGeometry, mm_per_px_at, pixel_rays, project_to_pixels
from contactcal.synth.variant import VARIANTS, choose_variant
from contactcal.synth.window import (
    WindowReflection,
    fresnel_unpolarized,
    sample_profile,
    window_transmission,
)

W, H = 64, 48
RIG = RigGeometry()
A = RIG.clamp_radius_mm
M = 128  # contact-weight texture


def _flat(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.zeros_like(x)


def _cap(h: float):
    return lambda x, y: h * np.clip(1.0 - (x * x + y * y) / A**2, 0.0, None)


def _radial_profile(img: np.ndarray) -> np.ndarray:
    """Mean luminance per 1-px ring around the principal point (index = radius in px)."""
    lum = img.mean(axis=-1)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    r = np.hypot(jj - (W / 2 - 0.5), ii - (H / 2 - 0.5))
    k = np.round(r).astype(int)
    return np.bincount(k.ravel(), lum.ravel()) / np.maximum(np.bincount(k.ravel()), 1)


# ------------------------------------------------------------------ no Mitsuba needed
def test_rig_rejects_bad_geometry() -> None:
    with pytest.raises(ValueError, match="rig.py"):
        RigGeometry(lgp_inner_radius_mm=14.0)
    with pytest.raises(ValueError, match="aspect"):
        pixel_rays(RIG, 64, 64)


def test_projection_inverts_pixel_rays() -> None:
    o, d = pixel_rays(RIG, W, H)
    t = (0.0 - o[..., 2]) / d[..., 2]
    pts = (o + t[..., None] * d).reshape(-1, 3)
    uv = project_to_pixels(RIG, pts, W, H)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    np.testing.assert_allclose(uv, np.stack([jj, ii], -1).reshape(-1, 2), atol=1e-9)
    # looking up, world +x is on the image's left and +y at the top
    u, v = project_to_pixels(RIG, np.array([[5.0, 3.0, 0.0]]), W, H)[0]
    assert u < W / 2 - 0.5 and v < H / 2 - 0.5
    depth = RIG.cylinder_height_mm + RIG.window_thickness_mm + RIG.chamber_depth_mm
    assert mm_per_px_at(RIG, 0.0, W, H) == pytest.approx(2 * depth * np.tan(np.radians(14.5)) / H)


def test_sample_profile_is_periodic_linear() -> None:
    p = np.array([1.0, 3.0, 2.0, 0.0])
    nodes = 2 * np.pi * np.arange(4) / 4
    np.testing.assert_allclose(sample_profile(p, nodes), p, atol=1e-12)
    np.testing.assert_allclose(sample_profile(p, nodes - 2 * np.pi), p, atol=1e-12)
    mids = sample_profile(p, nodes + np.pi / 4)
    np.testing.assert_allclose(mids, 0.5 * (p + np.roll(p, -1)), atol=1e-12)  # 0 -> p[0] wraps
    assert sample_profile(np.array([0.7]), np.array([0.0, 1.0, 6.0])) == pytest.approx(0.7)


def test_window_closed_form() -> None:
    assert fresnel_unpolarized(np.array([1.0]), 1.49)[0] == pytest.approx(0.0387, abs=2e-4)
    refl = WindowReflection(RIG, W, H, n_profile=8)(1.0, np.ones(8))
    t2 = window_transmission(RIG, W, H)
    assert refl.shape == (H, W, 3) and refl.dtype == np.float32
    r0 = 0.0387
    assert 0.5 * (2 * r0 / (1 + r0)) < refl.max() <= 2 * 0.06 / 1.06  # slab 2R/(1+R)
    assert np.all((t2 > 0.8) & (t2 <= 1.0))
    prof = _radial_profile(refl)
    ring_r = int(np.argmax(prof))
    assert ring_r > 0.6 * H / 2  # peripheral outer ring


def test_choose_variant_is_valid(monkeypatch: pytest.MonkeyPatch) -> None:
    assert choose_variant() in VARIANTS
    assert choose_variant() == choose_variant()  # cached probe, same answer
    monkeypatch.delenv("CONTACTCAL_MI_VARIANT", raising=False)
    assert choose_variant("scalar_rgb") == "scalar_rgb"
    with pytest.raises(ValueError, match="variant.py"):
        choose_variant("cuda_ad_rgb")


# ------------------------------------------------------------------ Mitsuba
@pytest.fixture(scope="module")
def renderer():
    pytest.importorskip("mitsuba")
    from contactcal.synth.render import RigRenderer

    r = RigRenderer(RIG, W, H, spp=4, n_rings=48, n_sectors=128, weight_size=M, normal_map_size=256)
    yield r
    r.close()


@pytest.mark.slow
def test_scene_loads_in_chosen_variant(renderer) -> None:
    import mitsuba as mi

    assert renderer.variant in VARIANTS
    assert mi.variant() == renderer.variant
    img = renderer.render(_flat, np.zeros((M, M), np.float32), 1.0, np.ones(16), seed=0)
    assert img.shape == (H, W, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and img.max() > 0


@pytest.mark.slow
def test_deterministic(renderer) -> None:
    w = np.zeros((M, M), np.float32)
    w[40:80, 40:80] = 1.0
    prof = 1.0 + 0.3 * np.cos(np.linspace(0, 2 * np.pi, 16, endpoint=False))
    a = renderer.render(_cap(2.0), w, 1.0, prof, particle_seed=1, seed=5)
    renderer.render(_flat, np.zeros_like(w), 2.0, np.ones(4), particle_seed=2, seed=9)
    b = renderer.render(_cap(2.0), w, 1.0, prof, particle_seed=1, seed=5)
    np.testing.assert_array_equal(a, b)
    c = renderer.render(_cap(2.0), w, 1.0, prof, particle_seed=1, seed=6)
    assert not np.array_equal(a, c)


@pytest.mark.slow
def test_inner_ring_shrinks_and_outer_ring_stays(renderer) -> None:
    w = np.zeros((M, M), np.float32)
    refl = WindowReflection(RIG, W, H, n_profile=8)(1.0, np.ones(8))
    r_outer = int(np.argmax(_radial_profile(refl)))
    assert r_outer > 0.6 * H / 2  # the window's ring is peripheral
    radii = []
    for h in (0.0, 5.5, 7.0):
        img = renderer.render(_cap(h), w, 1.0, np.ones(8), seed=1)
        prof = _radial_profile(img)
        assert prof[r_outer] > 3 * prof[2]  # outer ring present, centre darker
        radii.append(int(np.argmax(prof[: r_outer - 1])))
    # concave mirror past its focal condition: the LGP's image on the membrane shrinks
    assert radii[0] > radii[1] > radii[2] > 0, radii


@pytest.mark.slow
def test_hit_points_flat(renderer) -> None:
    hp = renderer.hit_points(_flat)
    assert hp.shape == (H, W, 3)
    ok = ~np.isnan(hp[..., 0])
    assert ok[H // 2, W // 2] and not ok[0, 0]  # centre on the membrane, corner off it
    assert np.all(hp[ok][:, 2] == 0.0)
    assert np.all(np.hypot(hp[ok][:, 0], hp[ok][:, 1]) <= A + 1e-4)
    uv = project_to_pixels(RIG, hp[ok], W, H)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    np.testing.assert_allclose(uv, np.stack([jj[ok], ii[ok]], -1), atol=1e-3)


@pytest.mark.slow
def test_marker_lands_on_projected_pixel(renderer) -> None:
    """A skin dot in the contact-weight texture appears where project_to_pixels says."""
    c = (np.arange(M) + 0.5) * 2 * A / M - A
    xx, yy = np.meshgrid(c, c)  # row i -> y, column j -> x
    dot = ((xx - 5.0) ** 2 + (yy - 3.0) ** 2 < 1.0).astype(np.float32)
    on = renderer.render(_flat, dot, 1.0, np.ones(4), seed=3)
    off = renderer.render(_flat, np.zeros_like(dot), 1.0, np.ones(4), seed=3)
    diff = np.abs(on - off).sum(-1)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    u = (diff * jj).sum() / diff.sum()
    v = (diff * ii).sum() / diff.sum()
    pu, pv = project_to_pixels(RIG, np.array([[5.0, 3.0, 0.0]]), W, H)[0]
    assert abs(u - pu) < 1.0 and abs(v - pv) < 1.0


@pytest.mark.slow
def test_mitsuba_camera_matches_pixel_rays(renderer) -> None:
    import mitsuba as mi

    sensor = renderer.scene.sensors()[0]
    _, d = pixel_rays(RIG, W, H)
    for i, j in ((0, 0), (10, 40), (H - 1, W - 1)):
        ray, _ = sensor.sample_ray(
            0.0, 0.5, mi.Point2f((j + 0.5) / W, (i + 0.5) / H), mi.Point2f(0.5, 0.5)
        )
        np.testing.assert_allclose(np.array(ray.d).ravel(), d[i, j], atol=1e-5)


@pytest.mark.slow
def test_bad_inputs(renderer) -> None:
    with pytest.raises(ValueError, match="contact_weight"):
        renderer.render(_flat, np.zeros((M + 1, M), np.float32), 1.0, np.ones(4))
    with pytest.raises(ValueError, match="azimuthal_profile"):
        renderer.render(_flat, np.zeros((M, M), np.float32), 1.0, -np.ones(4))
    with pytest.raises(ValueError, match="z_fn"):
        renderer.render(lambda x, y: np.full_like(x, np.nan), np.zeros((M, M)), 1.0, np.ones(4))


@pytest.mark.slow
def test_lgp_azimuth_agrees_between_mitsuba_and_window(renderer) -> None:
    """One lit LED sector at φ = 90° (+y) shows at the image top in both layers."""
    prof = np.zeros(16)
    prof[4] = 1.0  # φ_4 = 2π 4/16 = 90°
    lay = renderer.render_layers(_flat, np.zeros((M, M), np.float32), 1.0, prof, seed=2)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    for name in ("scene", "reflection"):
        lum = lay[name].mean(-1)
        u, v = (lum * jj).sum() / lum.sum(), (lum * ii).sum() / lum.sum()
        assert v < H / 2 - 0.5 - 0.25 * H / 2, (name, u, v)
        assert abs(u - (W / 2 - 0.5)) < 0.1 * W, (name, u, v)

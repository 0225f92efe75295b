"""Procedural fingerprint ridge textures in millimetre space (numpy + OpenCV, deterministic).

Pipeline of :func:`make_fingerprint`: an orientation field from the zero-pole (Sherlock-Monro)
model of singular points plus smooth noise, ridges grown from white noise by iterated oriented
band-pass (Gabor-like) filtering in the Fourier domain, a gentle warp that makes the ridge period
vary slowly (+- ``period_variation``), then pores and ridge breaks. One finger = one seed: the same
generator state gives a byte-identical texture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

PATTERNS = ("arch", "loop", "whorl")
LOOP_ROUND_BETA = 0.85  # 0 = plain zero-pole loop (needle-like tip), <1 = rounder recurve
LOOP_ROUND_MM = 3.0  # extent of that correction around the core (mm)
_REMAP_WIDTH = 4096  # points per row of the cv2.remap maps


@dataclass(frozen=True)
class FingerprintConfig:
    """Parameters of the fingerprint texture generator (lengths in mm)."""

    size_mm: float = 28.0  # side of the square; covers membranes of radius <= 14 mm; cost ~ size²
    px_per_mm: float = 20.0  # 7-11 px per ridge period by default; higher = sharper, cost ~ px²
    period_mm_range: tuple[float, float] = (0.35, 0.55)  # ridge+valley period drawn uniformly
    #   (Maltoni: ~0.5 mm, 0.40-0.47 from ridge counts; widened for children/large fingers)
    period_variation: float = 0.03  # relative std of the local period (slow warp); 0 = uniform
    iterations: int = 6  # ridge-growth iterations; fewer = noisier ridges, more = slower
    orientation_bins: int = 16  # oriented filters; fewer = faster but facetted curved ridges
    bandwidth: float = 0.15  # radial std of the band-pass / ridge frequency; wider = more minutiae
    orientation_noise_rad: float = 0.12  # std of the smooth orientation perturbation (rad)
    ridge_sharpness: float = 2.0  # tanh gain of the output profile; high = binary, low = sinusoid
    pore_density_per_mm2: float = 2.0  # pores per mm² of skin (placed on ridges); 0 disables
    pore_diameter_mm: float = 0.10  # FWHM of a pore (real: 0.06-0.25 mm)
    pore_depth: float = 0.6  # fractional darkening at a pore centre, in [0, 1]
    break_density: float = 0.03  # ridge breaks per mm² (each cuts ~1 ridge); 0 disables
    break_size_mm: float = 0.30  # FWHM of a break; larger cuts more ridges
    pattern_probs: tuple[float, float, float] = (0.1, 0.6, 0.3)  # P(arch), P(loop), P(whorl)
    margin_mm: float = 1.5  # padding against FFT wrap-around at the borders; cost vs edge artefacts

    def __post_init__(self) -> None:
        lo, hi = self.period_mm_range
        ppp = self.px_per_mm * lo
        probs = np.asarray(self.pattern_probs, dtype=float)
        _require(0.0 < lo <= hi, f"period_mm_range must be 0 < lo <= hi mm, got {(lo, hi)}")
        _require(ppp >= 4.0, f"px_per_mm={self.px_per_mm} gives {ppp:.2f} px/period, need >= 4")
        _require(self.size_mm >= 4 * hi, f"size_mm must be >= 4 periods, got {self.size_mm}")
        _require(self.iterations >= 1, f"iterations must be >= 1, got {self.iterations}")
        _require(
            self.orientation_bins >= 4,
            f"orientation_bins must be >= 4, got {self.orientation_bins}",
        )
        _require(self.bandwidth > 0 and self.ridge_sharpness > 0, "bandwidth, ridge_sharpness <= 0")
        _require(0 <= self.pore_depth <= 1, f"pore_depth must be in [0, 1], got {self.pore_depth}")
        ok = probs.shape == (3,) and bool((probs >= 0).all()) and probs.sum() > 0
        _require(ok, f"pattern_probs must be 3 weights >= 0, sum > 0, got {self.pattern_probs}")
        for k in _NON_NEGATIVE:
            _require(getattr(self, k) >= 0, f"{k} must be >= 0, got {getattr(self, k)}")


_NON_NEGATIVE = "period_variation orientation_noise_rad pore_density_per_mm2 margin_mm".split()
_NON_NEGATIVE += "pore_diameter_mm break_density break_size_mm".split()


def _require(ok: bool, msg: str) -> None:
    """Raise ``ValueError`` naming the config and this file unless ``ok``."""
    if not ok:
        raise ValueError(f"FingerprintConfig (synth/fingerprint.py): {msg}")


DEFAULT_CONFIG = FingerprintConfig()


@dataclass(frozen=True, eq=False)
class Fingerprint:
    """One finger's ridge texture.

    Attributes:
        ridges: ``(N, N) float32`` in [0, 1]; 1 = ridge crest (skin touching), 0 = valley.
            Row ``i`` / column ``j`` is the pixel centred at ``y = (i + 0.5) / px_per_mm -
            size_mm / 2`` / ``x = (j + 0.5) / px_per_mm - size_mm / 2`` (texture frame, mm).
        period_mm: mean ridge period (mm).
        pattern: one of ``"arch"``, ``"loop"``, ``"whorl"``.
        px_per_mm: resolution (px/mm).
        size_mm: side of the covered square, ``N / px_per_mm`` (mm).
    """

    ridges: np.ndarray = field(repr=False)
    period_mm: float
    pattern: str
    px_per_mm: float
    size_mm: float

    def sample(self, x_mm: np.ndarray, y_mm: np.ndarray, fill: float = 0.5) -> np.ndarray:
        """Bilinearly sample the texture at texture-frame coordinates (centred at (0, 0)).

        Args:
            x_mm: x coordinates (mm), any shape broadcastable with ``y_mm``.
            y_mm: y coordinates (mm).
            fill: value returned outside the square ``|x|, |y| <= size_mm / 2`` (0.5 = neither
                ridge nor valley); between the border and the outer pixel centres the edge value
                is used.

        Returns:
            ``float32`` array of the broadcast shape, values in [0, 1] (or ``fill``).
        """
        x, y = np.broadcast_arrays(np.asarray(x_mm, float), np.asarray(y_mm, float))
        half = 0.5 * self.size_mm
        out = _bilinear(
            self.ridges, (y + half) * self.px_per_mm - 0.5, (x + half) * self.px_per_mm - 0.5
        ).reshape(x.shape)
        inside = (np.abs(x) <= half) & (np.abs(y) <= half)
        return np.where(inside, out, np.float32(fill)).astype(np.float32)


def _bilinear(img: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Bilinear lookup of ``(H, W)`` ``img`` at fractional pixel ``rows, cols``, edge-clamped.

    ``cv2.remap`` with ``BORDER_REPLICATE``; coordinates are clamped first (NaN -> 0: callers mask
    them) and cast to float32 (OpenCV's map type: ~1e-5 px rounding). Returns a flat float32 array.
    """
    h, w = img.shape
    r = np.clip(np.nan_to_num(np.ravel(rows)), 0, h - 1).astype(np.float32)
    c = np.clip(np.nan_to_num(np.ravel(cols)), 0, w - 1).astype(np.float32)
    n = r.size
    if n == 0:
        return np.zeros(0, np.float32)
    width = min(n, _REMAP_WIDTH)  # remap needs map sides < 32767: wrap the points into rows
    pad = -n % width
    maps = [np.pad(v, (0, pad), mode="edge").reshape(-1, width) for v in (c, r)]
    src = np.ascontiguousarray(img, dtype=np.float32)
    out = cv2.remap(src, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out.ravel()[:n]


def _freqs(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Frequency grids ``(H, 1)``, ``(1, W//2+1)`` (cycles/px) matching ``np.fft.rfft2``."""
    return np.fft.fftfreq(shape[0])[:, None], np.fft.rfftfreq(shape[1])[None, :]


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], sigma_px: float) -> np.ndarray:
    """White noise low-passed by a Gaussian of std ``sigma_px``; ``(H, W) float64``, unit std."""
    fy, fx = _freqs(shape)
    spec = np.fft.rfft2(rng.standard_normal(shape))
    out = np.fft.irfft2(spec * np.exp(-2 * (math.pi * sigma_px) ** 2 * (fx**2 + fy**2)), s=shape)
    return out / max(out.std(), 1e-12)


def _orientation(
    rng: np.random.Generator, pattern: str, x: np.ndarray, y: np.ndarray
) -> np.ndarray:
    """Ridge tangent angle (rad, mod pi) of a pattern class on mm grids ``x, y`` ``(H, W)``."""
    alpha = rng.uniform(-0.3, 0.3)  # in-plane finger rotation
    ca, sa = math.cos(alpha), math.sin(alpha)
    # Canonical frame: ridges ~ along u far away, fingertip towards -v (up in the image).
    u, v = ca * x + sa * y, -sa * x + ca * y
    if pattern == "arch":  # ridges v = -h(u) with a Gaussian bump h, strongest around v0
        amp, s, v0 = rng.uniform(0.6, 1.4), rng.uniform(3.0, 5.0), rng.uniform(-3.0, 3.0)
        slope = amp * u / s * np.exp(-0.5 * (u / s) ** 2 - 0.5 * ((v - v0) / 5.0) ** 2)
        return alpha + np.arctan(slope)
    z = u + 1j * v
    cx, cy = rng.uniform(-2.0, 2.0), rng.uniform(-3.0, 1.0)
    if pattern == "loop":
        side = rng.choice([-1.0, 1.0])
        cores = [complex(cx, cy)]
        deltas = [complex(cx + side * rng.uniform(4.0, 7.0), cy + rng.uniform(4.0, 7.0))]
    else:
        sep, phi = rng.uniform(0.3, 2.5), rng.uniform(0, math.pi)
        off = 0.5 * sep * complex(math.cos(phi), math.sin(phi))
        cores = [complex(cx, cy) + off, complex(cx, cy) - off]
        deltas = [
            complex(cx + sx * rng.uniform(4.5, 7.5), cy + rng.uniform(4.0, 7.0)) for sx in (-1, 1)
        ]
    theta = np.full(z.shape, alpha)
    for c in cores:
        theta += 0.5 * np.angle(z - c)
    for d in deltas:
        theta -= 0.5 * np.angle(z - d)
    if pattern == "loop":  # round the loop tip: slow the turn near the opening axis psi
        c, d = cores[0], deltas[0]
        psi = 2.0 * (alpha - 0.5 * np.angle(c - d))  # where the field near c is radial
        fade = np.exp(-0.5 * np.abs(z - c) ** 2 / LOOP_ROUND_MM**2)
        theta -= 0.5 * LOOP_ROUND_BETA * np.sin(np.angle(z - c) - psi) * fade
    return theta


def _grow_ridges(
    rng: np.random.Generator, theta: np.ndarray, period_px: float, cfg: FingerprintConfig
) -> np.ndarray:
    """Grow ridges along tangent angles ``theta`` ``(H, W)`` (rad) from white noise.

    Returns:
        ``(H, W) float32`` in [-1, 1]; +1 = ridge crest.
    """
    shape = theta.shape
    k_bins = cfg.orientation_bins
    fy, fx = _freqs(shape)
    f0 = 1.0 / period_px
    radial = np.exp(-0.5 * ((np.hypot(fx, fy) - f0) / (cfg.bandwidth * f0)) ** 2)
    ang = np.arctan2(fy, fx)
    sig_ang = 0.6 * math.pi / k_bins
    b = np.mod(theta, math.pi) / (math.pi / k_bins)  # continuous bin coordinate
    filters, weights = [], []
    for k in range(k_bins):
        d = np.mod(ang - (k * math.pi / k_bins + math.pi / 2) + math.pi / 2, math.pi) - math.pi / 2
        filters.append((radial * np.exp(-0.5 * (d / sig_ang) ** 2)).astype(np.float32))
        dist = np.abs(np.mod(b - k + k_bins / 2, k_bins) - k_bins / 2)
        weights.append(np.clip(1.0 - dist, 0.0, 1.0).astype(np.float32))
    x = rng.standard_normal(shape).astype(np.float32)
    for it in range(cfg.iterations):
        spec = np.fft.rfft2(x)
        out = np.zeros(shape, np.float32)
        for filt, w in zip(filters, weights, strict=True):
            out += w * np.fft.irfft2(spec * filt, s=shape)
        out /= max(float(out.std()), 1e-12)
        gain = cfg.ridge_sharpness if it == cfg.iterations - 1 else 2.0
        x = np.tanh(gain * out)
    return x


def _blobs(rng: np.random.Generator, count: int, fwhm_px: float, keep: np.ndarray) -> np.ndarray:
    """Unit-peak Gaussian blobs at ``count`` random pixels of ``(H, W) bool keep`` that are True."""
    shape = keep.shape
    rows, cols = rng.integers(0, shape[0], count), rng.integers(0, shape[1], count)
    ok = keep[rows, cols]
    imp = np.zeros(shape)
    np.add.at(imp, (rows[ok], cols[ok]), 1.0)
    sig = fwhm_px / 2.3548
    fy, fx = _freqs(shape)
    gauss = np.exp(-2 * (math.pi * sig) ** 2 * (fx**2 + fy**2))
    peak = np.fft.irfft2(gauss, s=shape)[0, 0]  # response of one impulse at its centre
    return np.fft.irfft2(np.fft.rfft2(imp) * gauss, s=shape) / peak


def make_fingerprint(
    rng: np.random.Generator, config: FingerprintConfig = DEFAULT_CONFIG
) -> Fingerprint:
    """Generate one finger's ridge texture.

    Args:
        rng: source of all randomness (pattern, singular points, period, noise, pores, breaks).
        config: generator parameters.

    Returns:
        :class:`Fingerprint` with ``ridges`` ``(N, N) float32`` in [0, 1],
        ``N = round(size_mm * px_per_mm)``.
    """
    cfg = config
    ppm = cfg.px_per_mm
    n = max(8, round(cfg.size_mm * ppm))
    m = round(cfg.margin_mm * ppm)
    probs = np.asarray(cfg.pattern_probs, float)
    pattern = PATTERNS[int(rng.choice(3, p=probs / probs.sum()))]
    period_mm = float(rng.uniform(*cfg.period_mm_range))
    period_px = period_mm * ppm
    # Padded working grid; pixel centres in mm, (0, 0) at the texture centre.
    npad = n + 2 * m
    coords = (np.arange(npad) + 0.5 - npad / 2) / ppm
    ymm, xmm = np.meshgrid(coords, coords, indexing="ij")
    theta = _orientation(rng, pattern, xmm, ymm)
    theta += cfg.orientation_noise_rad * _smooth_noise(rng, (npad, npad), 2.0 * ppm)
    grown = _grow_ridges(rng, theta, period_px, cfg)
    # Slow period variation: sample at p + grad(phi); local scale = I + Hessian(phi).
    phi = _smooth_noise(rng, (npad, npad), 3.0 * ppm)
    gy, gx = np.gradient(phi)
    hyy, hxx = np.gradient(gy, axis=0), np.gradient(gx, axis=1)
    scale = cfg.period_variation / max(float((0.5 * (hxx + hyy)).std()), 1e-12)
    crop = (slice(m, m + n),) * 2
    rr, cc = np.meshgrid(np.arange(n) + m, np.arange(n) + m, indexing="ij")
    warped = _bilinear(grown, rr + scale * gy[crop], cc + scale * gx[crop]).reshape(n, n)
    ridges = 0.5 + 0.5 * warped
    area = cfg.size_mm**2
    if cfg.pore_density_per_mm2 > 0:
        count = int(rng.poisson(cfg.pore_density_per_mm2 * area / max(ridges.mean(), 0.1)))
        pores = _blobs(rng, count, cfg.pore_diameter_mm * ppm, ridges > 0.5)
        ridges = ridges * (1.0 - cfg.pore_depth * np.clip(pores, 0.0, 1.0))
    if cfg.break_density > 0:
        count = int(rng.poisson(cfg.break_density * area))
        holes = _blobs(rng, count, cfg.break_size_mm * ppm, np.ones((n, n), bool))
        ridges = ridges * (1.0 - np.clip(1.5 * holes, 0.0, 1.0))
    ridges = np.clip(ridges, 0.0, 1.0).astype(np.float32)
    ridges.setflags(write=False)
    return Fingerprint(ridges, period_mm, pattern, float(ppm), n / ppm)

"""Figures, speed and spp study of the rig renderer (numbers quoted in docs/renderer.md).

    python -m contactcal.synth.render_demo figures --out docs
    python -m contactcal.synth.render_demo bench
    python -m contactcal.synth.render_demo spp --width 648 --height 486

Demo membrane states (mm): ``flat`` (0 kPa), ``cap`` ``z = 6 (1 - r²/a²)`` (free inflation),
``plateau`` ``z = min(7 (1 - r²/a²), 4.5)`` with a fake contact weight of 0.47 mm stripes
(concentric, like a whorl) in a central ellipse, mimicking ridges.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from contactcal.infer.parser import Parser, folder_arg
from contactcal.synth.rig import RigGeometry

__all__ = ["demo_states", "tonemap"]

ZFn = Callable[[np.ndarray, np.ndarray], np.ndarray]
PROFILE = 1.0 + 0.15 * np.cos(np.arange(16) * 2 * np.pi / 16 * 8)  # 16 LEDs, mild ripple


def tonemap(img: np.ndarray, exposure: float = 3.0, gamma: float = 2.2) -> np.ndarray:
    """Linear RGB ``(H, W, 3)`` -> ``uint8`` BGR for PNG: ``clip(exposure * x) ** (1/gamma)``."""
    x = np.clip(np.asarray(img, np.float64) * exposure, 0.0, 1.0) ** (1.0 / gamma)
    return (x[..., ::-1] * 255.0 + 0.5).astype(np.uint8)


def _cap(h: float, a: float) -> ZFn:
    """Paraboloid cap of apex height ``h`` over the clamp radius ``a`` (mm)."""
    return lambda x, y: h * np.clip(1.0 - (x * x + y * y) / a**2, 0.0, None)


def demo_states(rig: RigGeometry, m: int) -> dict[str, tuple[ZFn, np.ndarray]]:
    """Demo ``(z_fn, contact_weight (m, m))`` per state name (see module docstring)."""
    a = rig.clamp_radius_mm
    c = (np.arange(m) + 0.5) * 2 * a / m - a
    xx, yy = np.meshgrid(c, c)  # row i -> y, column j -> x (the weight texture convention)
    cap = partial(_cap, a=a)
    h_cap, z_top = 7.0, 4.5
    r_c = a * np.sqrt(1.0 - z_top / h_cap)  # plateau radius
    ell = (xx / (0.78 * r_c)) ** 2 + ((yy + 0.3) / (0.98 * r_c)) ** 2 <= 1.0
    stripes = 0.5 + 0.5 * np.cos(2 * np.pi * np.hypot(xx - 0.8, yy + 1.5) / 0.47)
    zero = np.zeros((m, m), np.float32)
    return {
        "flat": (cap(0.0), zero),
        "cap": (cap(6.0), zero),
        "plateau": (
            lambda x, y: np.minimum(cap(h_cap)(x, y), z_top),
            (ell * stripes).astype(np.float32),
        ),
    }


def _save(path: Path, bgr: np.ndarray) -> None:
    from contactcal.infer.image.write import write_image

    write_image(path, bgr)


def _label(bgr: np.ndarray, text: str) -> np.ndarray:
    import cv2

    out = bgr.copy()
    cv2.putText(out, text, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1)
    return out


def figures(out: Path, width: int = 648, height: int = 486, spp: int = 16) -> None:
    """Write the docs PNGs: three states, an inflation strip and two ablation pairs."""
    from contactcal.synth.coating import MembraneOptics
    from contactcal.synth.render import RigRenderer

    rig = RigGeometry()
    m = 1024
    states = demo_states(rig, m)
    with RigRenderer(rig, width, height, spp=spp, weight_size=m) as r:
        for name, (z_fn, w) in states.items():
            _save(out / f"render_{name}.png", tonemap(r.render(z_fn, w, 1.0, PROFILE, seed=1)))
        z_fn, w = states["plateau"]
        lay = r.render_layers(z_fn, w, 1.0, PROFILE, seed=1)
        full = lay["transmission"][..., None] * lay["scene"] + lay["reflection"]
        panels = [
            _label(tonemap(lay["scene"]), "Mitsuba: membrane + LGP"),
            _label(tonemap(lay["reflection"]), "closed form: window reflex"),
            _label(tonemap(full), "frame = T^2 * scene + reflex"),
        ]
        _save(out / "ablation_window.png", _half(np.hstack(panels)))
        smooth = MembraneOptics(particle_tilt_deg=0.0, sparkle_fraction=0.0)
        no_flakes = r.render(z_fn, w, 1.0, PROFILE, optics=smooth, seed=1)
        r.render(z_fn, w, 1.0, PROFILE, optics=MembraneOptics(), seed=1)  # restore
        pair = [_label(tonemap(no_flakes), "no flakes"), _label(tonemap(full), "mica flakes")]
        _save(out / "ablation_flakes.png", _half(np.hstack(pair)))
    with RigRenderer(rig, 256, 192, spp=spp, weight_size=256) as r:
        a = rig.clamp_radius_mm
        strip = []
        no_contact = np.zeros((256, 256), np.float32)
        for h in (0.0, 1.0, 3.0, 5.0, 6.0, 7.0):
            img = r.render(_cap(h, a), no_contact, 1.0, PROFILE, seed=1)
            strip.append(_label(tonemap(img), f"h = {h:g} mm"))
        _save(out / "inflation_strip.png", np.vstack([np.hstack(strip[:3]), np.hstack(strip[3:])]))


def _half(bgr: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.resize(bgr, (bgr.shape[1] // 2, bgr.shape[0] // 2), interpolation=cv2.INTER_AREA)


def benchmark(sizes=((256, 192), (648, 486)), spp: int = 16, frames: int = 5) -> list[dict]:
    """Median seconds per frame (render incl. in-place updates and window) per thread count."""
    import drjit as dr

    from contactcal.synth.render import RigRenderer

    rig = RigGeometry()
    rows = []
    n_threads = dr.thread_count()
    states = list(demo_states(rig, 1024).values())
    for w, h in sizes:
        with RigRenderer(rig, w, h, spp=spp, weight_size=1024) as r:
            for threads in sorted({1, n_threads}):
                dr.set_thread_count(threads)
                r.render(*states[2], 1.0, PROFILE, seed=0)  # warm-up (kernel compilation)
                times = []
                for k in range(frames):
                    z_fn, wt = states[k % len(states)]
                    t0 = time.perf_counter()
                    r.render(z_fn, wt, 1.0, PROFILE, seed=k)
                    times.append(time.perf_counter() - t0)
                s = float(np.median(times))
                rows.append({"size": f"{w}x{h}", "spp": spp, "threads": threads, "s": s})
                print(f"{w}x{h} spp={spp} threads={threads}: {s:.2f} s/frame, {1 / s:.2f} fps")
        dr.set_thread_count(n_threads)
    return rows


def spp_study(width: int, height: int, spps=(1, 2, 4, 8, 16, 32, 64), n_ref: int = 4) -> None:
    """PSNR (tone-mapped) and ridge-energy-mask IoU vs a (64 x n_ref)-spp reference."""
    import cv2

    from contactcal.synth.render import RigRenderer

    rig = RigGeometry()
    z_fn, w = demo_states(rig, 1024)["plateau"]
    with RigRenderer(rig, width, height, spp=64, weight_size=1024) as r:
        ref = sum(r.render(z_fn, w, 1.0, PROFILE, seed=1000 + k) for k in range(n_ref)) / n_ref
        s = width / 256

        def energy(img: np.ndarray) -> np.ndarray:
            g = (tonemap(img)[..., 1] / 255.0).astype(np.float32)
            bp = cv2.GaussianBlur(g, (0, 0), 0.6 * s) - cv2.GaussianBlur(g, (0, 0), 2.5 * s)
            return cv2.GaussianBlur(bp * bp, (0, 0), 4 * s)

        e_ref = energy(ref)
        thr = 0.5 * e_ref.max()
        m_ref = e_ref > thr
        t_ref = tonemap(ref) / 255.0
        print("| spp | PSNR dB | ridge-mask IoU |\n|---|---|---|")
        for spp in spps:
            r.spp = spp
            img = r.render(z_fn, w, 1.0, PROFILE, seed=7)
            psnr = 10 * np.log10(1.0 / np.mean((tonemap(img) / 255.0 - t_ref) ** 2))
            msk = energy(img) > thr
            iou = (msk & m_ref).sum() / max((msk | m_ref).sum(), 1)
            print(f"| {spp} | {psnr:.1f} | {iou:.3f} |")


def main(argv: list[str] | None = None) -> None:
    """Command line entry (see module docstring)."""
    ap = Parser(prog="python -m contactcal.synth.render_demo")
    ap.add_argument("what", choices=("figures", "bench", "spp"))
    ap.add_argument("--out", type=folder_arg, default=Path("docs"))
    ap.add_argument("--width", type=int, default=648)
    ap.add_argument("--height", type=int, default=486)
    ap.add_argument("--spp", type=int, default=16)
    args = ap.parse_args(argv)
    if args.what == "figures":
        figures(args.out, args.width, args.height, args.spp)
    elif args.what == "bench":
        benchmark(spp=args.spp)
    else:
        spp_study(args.width, args.height)


if __name__ == "__main__":
    main()

"""Pick a Mitsuba variant that works on this machine without ever aborting the process.

``llvm_ad_rgb`` is about 3x faster than ``scalar_rgb`` but, with the LLVM 14/15 that Debian
ships as default, Dr.Jit's code generation dies with ``LLVM ERROR: Cannot select fminimum``:
an ``abort()`` that no ``try`` can catch. A known-good LLVM (16-19) is therefore located,
verified by rendering a tiny scene in a *subprocess*, and only then exported as
``DRJIT_LIBLLVM_PATH`` in this process (Dr.Jit reads it lazily, when an LLVM variant is first
set, so this must happen before ``mi.set_variant("llvm_...")``).

Environment:
    ``CONTACTCAL_MI_VARIANT``: force ``scalar_rgb`` or ``llvm_ad_rgb`` (the latter still needs a
    good LLVM; if none passes the probe, ``choose_variant`` raises ``RuntimeError``).
    ``DRJIT_LIBLLVM_PATH``: if already set, it is probed first.
"""

from __future__ import annotations

import glob
import os
import re
import subprocess
import sys
import warnings

__all__ = ["VARIANTS", "choose_variant", "find_llvm_candidates", "set_variant"]

VARIANTS: tuple[str, ...] = ("llvm_ad_rgb", "scalar_rgb")
_GOOD_MAJORS: tuple[int, ...] = (19, 18, 17, 16)
_LIB_DIRS: tuple[str, ...] = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib64",
    "/usr/lib",
    "/usr/local/lib",
    "/opt/homebrew/opt/llvm/lib",
)
_PROBE_TIMEOUT_S = 180.0
# Renders a 16x16 frame with the llvm variant; prints OK only if the pixels are finite.
_PROBE = """
import mitsuba as mi, numpy as np
mi.set_variant("llvm_ad_rgb")
scene = mi.load_dict({
    "type": "scene",
    "integrator": {"type": "path", "max_depth": 3},
    "sensor": {"type": "perspective", "fov": 40,
               "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, -4], target=[0, 0, 0],
                                                          up=[0, 1, 0]),
               "film": {"type": "hdrfilm", "width": 16, "height": 16}},
    "light": {"type": "rectangle",
              "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}},
              "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], 180)},
})
img = np.asarray(mi.render(scene, spp=4))
print("OK" if np.isfinite(img).all() and img.max() > 0 else "BAD")
"""
_CACHE: dict[str, str] = {}


def _major(path: str) -> int | None:
    """LLVM major version from a library file name (``libLLVM.so.19.1``, ``libLLVM-18.so``)."""
    m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", os.path.basename(path))
    return int(m.group(1)) if m else None


def find_llvm_candidates() -> list[str]:
    """Known-good LLVM shared libraries on this machine, best first.

    Returns:
        Absolute paths: an existing ``DRJIT_LIBLLVM_PATH`` first (whatever its version, it was
        chosen by the user), then ``libLLVM*.so*`` of majors 19, 18, 17, 16 found in the
        standard library folders and ``/usr/lib/llvm-N/lib``.
    """
    out: list[str] = []
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env and os.path.isfile(env):
        out.append(env)
    for major in _GOOD_MAJORS:
        dirs = [*_LIB_DIRS, f"/usr/lib/llvm-{major}/lib"]
        for d in dirs:
            for pat in (f"libLLVM.so.{major}*", f"libLLVM-{major}*.so*", f"libLLVM-{major}.so"):
                for p in sorted(glob.glob(os.path.join(d, pat))):
                    real = os.path.realpath(p)
                    if _major(p) == major and real not in {os.path.realpath(q) for q in out}:
                        out.append(p)
    return out


def _probe(lib: str) -> bool:
    """True if a subprocess with ``DRJIT_LIBLLVM_PATH=lib`` renders with ``llvm_ad_rgb``."""
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=lib)
    env.pop("CONTACTCAL_MI_VARIANT", None)
    try:
        res = subprocess.run(
            [sys.executable, "-c", _PROBE],
            env=env,
            capture_output=True,
            text=True,
            timeout=_PROBE_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return res.returncode == 0 and res.stdout.strip().endswith("OK")


def _working_llvm() -> str | None:
    """First candidate LLVM library that passes the subprocess probe (cached per process)."""
    if "lib" not in _CACHE:
        _CACHE["lib"] = ""
        for lib in find_llvm_candidates():
            if _probe(lib):
                _CACHE["lib"] = lib
                break
    return _CACHE["lib"] or None


def choose_variant(prefer: str = "auto") -> str:
    """Return the fastest Mitsuba variant that is safe to use in this process.

    Args:
        prefer: ``"auto"`` (llvm if a known-good LLVM passes the probe, else scalar),
            ``"llvm_ad_rgb"`` (same, but warns when falling back) or ``"scalar_rgb"``.
            The environment variable ``CONTACTCAL_MI_VARIANT`` overrides it.

    Returns:
        ``"llvm_ad_rgb"`` or ``"scalar_rgb"``. When llvm is returned, ``DRJIT_LIBLLVM_PATH``
        has been set in ``os.environ`` to the verified library.

    Raises:
        ValueError: ``prefer`` or ``CONTACTCAL_MI_VARIANT`` is not one of the known variants.
        RuntimeError: ``CONTACTCAL_MI_VARIANT=llvm_ad_rgb`` but no LLVM passes the probe.
    """
    forced = os.environ.get("CONTACTCAL_MI_VARIANT", "").strip()
    choice = forced or prefer
    if choice not in (*VARIANTS, "auto"):
        src = "environment CONTACTCAL_MI_VARIANT" if forced else "argument prefer"
        raise ValueError(
            f"synth/variant.py: {src} must be one of {(*VARIANTS, 'auto')}, got {choice!r}"
        )
    if choice == "scalar_rgb":
        return "scalar_rgb"
    lib = _working_llvm()
    if lib is not None:
        os.environ["DRJIT_LIBLLVM_PATH"] = lib
        return "llvm_ad_rgb"
    if forced:
        raise RuntimeError(
            "synth/variant.py: CONTACTCAL_MI_VARIANT=llvm_ad_rgb but no LLVM 16-19 library "
            f"passed the render probe (candidates: {find_llvm_candidates()})"
        )
    if choice == "llvm_ad_rgb":
        warnings.warn(
            "synth/variant.py: no working LLVM 16-19 found; falling back to scalar_rgb",
            RuntimeWarning,
            stacklevel=2,
        )
    return "scalar_rgb"


def set_variant(prefer: str = "auto") -> str:
    """``choose_variant`` then ``mitsuba.set_variant``; returns the variant name."""
    variant = choose_variant(prefer)
    import mitsuba as mi

    if mi.variant() != variant:
        mi.set_variant(variant)
    return variant

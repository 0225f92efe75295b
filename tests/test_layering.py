"""`infer` (the deployable core) never imports torch, kornia, onnx or mitsuba."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("torch", "kornia", "onnx", "mitsuba", "drjit")


def test_infer_imports_no_heavy_dependency() -> None:
    code = (
        "import sys, pkgutil, importlib, contactcal.infer as p\n"
        "for m in pkgutil.iter_modules(p.__path__):\n"
        "    importlib.import_module('contactcal.infer.' + m.name)\n"
        "from contactcal.infer.cli import build_parser\n"
        "build_parser()\n"
        f"print([h for h in {HEAVY!r} if h in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", f"heavy modules imported by contactcal.infer: {out.stdout}"

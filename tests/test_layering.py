"""Layering: the deployable core (`infer`) stands alone; dependencies point one way.

`infer` imports neither the other roles (`synth`, `train`) nor the heavy libraries, in any import
statement (module level or inside functions); `synth` and `train` may import `infer`, not each
other. Checked on the source's import statements and, at run time, on `sys.modules`.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("torch", "kornia", "onnx", "onnxscript", "mitsuba", "drjit")
#: role folder → top-level names its import statements must not reach.
FORBIDDEN = {
    # PIL: not a declared core dependency (matplotlib pulls it in, so the wheel test would not
    # notice an import of it in the core).
    "infer": ("contactcal.synth", "contactcal.train", "PIL", *HEAVY),
    "synth": ("contactcal.train", "torch", "kornia"),
    "train": ("contactcal.synth", "mitsuba", "drjit"),
}


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every import statement in a file (relative imports resolved)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise AssertionError(f"{path}:{node.lineno}: use absolute contactcal imports")
            out.append((node.lineno, node.module or ""))
    return out


def _reaches(module: str, name: str) -> bool:
    return module == name or module.startswith(name + ".")


@pytest.mark.parametrize("role", sorted(FORBIDDEN))
def test_import_statements_point_one_way(role: str) -> None:
    bad = [
        f"{path.relative_to(ROOT)}:{line}: imports {mod}"
        for path in sorted((ROOT / role).rglob("*.py"))
        for line, mod in imported_modules(path)
        if any(_reaches(mod, name) for name in FORBIDDEN[role])
    ]
    assert not bad, "\n".join(bad)


def test_checker_sees_function_level_imports(tmp_path: Path) -> None:
    src = tmp_path / "m.py"
    src.write_text("def f():\n    from contactcal.train.loop import train\n    import torch.nn\n")
    mods = [m for _, m in imported_modules(src)]
    assert mods == ["contactcal.train.loop", "torch.nn"]
    assert _reaches("torch.nn", "torch") and not _reaches("torchvision", "torch")


def test_infer_loads_no_heavy_module_at_run_time() -> None:
    code = (
        "import sys, pkgutil, importlib, contactcal.infer as p\n"
        "for m in pkgutil.walk_packages(p.__path__, 'contactcal.infer.'):\n"
        "    importlib.import_module(m.name)\n"
        "from contactcal.infer.cli import build_parser\n"
        "build_parser()\n"
        f"print([h for h in {HEAVY!r} if h in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", f"heavy modules imported by contactcal.infer: {out.stdout}"


#: train modules that load no heavy module at import: the restating tools (`python -m
#: contactcal.train.interval`, `.change_gate`, `.floor`: onnx only when they run), the CLI's
#: subcommands and the run folder's check (`train` refuses an --out before loading torch).
LIGHT_TRAIN = (
    "contactcal.train.interval",
    "contactcal.train.change_gate",
    "contactcal.train.floor",
    "contactcal.train.commands",
    "contactcal.train.run_folder",
)


def test_restating_tools_load_no_heavy_module_at_import() -> None:
    code = (
        "import sys, importlib\n"
        f"for m in {LIGHT_TRAIN!r}:\n"
        "    importlib.import_module(m)\n"
        f"print([h for h in {HEAVY!r} if h in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", f"heavy modules imported by {LIGHT_TRAIN}: {out.stdout}"

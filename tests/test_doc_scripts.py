"""The scripts in docs/scripts that reproduce the documentation's numbers still import, and
``unet_phases.py`` still finds every function it times (a renamed function broke it once)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "docs" / "scripts"
#: Optional heavy dependencies a script may import: it is skipped where one is missing.
OPTIONAL = ("torch", "kornia", "mitsuba", "matplotlib", "tqdm")


def _load(path: Path) -> ModuleType:
    """Import a script as a module (its ``main`` is not run: each is guarded by __main__)."""
    name = f"_doc_script_{path.stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the class is built
    sys.path.insert(0, str(SCRIPTS))  # scripts import their siblings (cli_speed's _session)
    try:
        spec.loader.exec_module(module)
    except ModuleNotFoundError as exc:
        if exc.name is not None and exc.name.split(".")[0] in OPTIONAL:
            pytest.skip(f"{path.name} needs {exc.name}")
        raise
    finally:
        sys.path.remove(str(SCRIPTS))
        sys.modules.pop(name, None)
    return module


@pytest.mark.parametrize("path", sorted(SCRIPTS.glob("*.py")), ids=lambda p: p.name)
def test_script_imports_without_running(path: Path) -> None:
    source = path.read_text(encoding="utf-8")
    assert 'if __name__ == "__main__":' in source, f"{path.name}: work outside a __main__ guard"
    _load(path)


def test_unet_phases_times_functions_that_exist() -> None:
    phases = _load(SCRIPTS / "unet_phases.py").PHASES
    missing = [name for name, (owner, attr) in phases.items() if not hasattr(owner, attr)]
    assert not missing, f"unet_phases.PHASES names functions that are gone: {missing}"

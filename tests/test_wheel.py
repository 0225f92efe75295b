"""What `pip install .` gives a lab: the model, its card and the example session as package data,
the licence, one version; and `contactcal demo` running from the wheel with core dependencies."""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from importlib import resources
from pathlib import Path

import pytest

import contactcal.infer
from contactcal.infer.cli import main
from contactcal.infer.methods.unet.runner import DEFAULT_MODEL
from contactcal.infer.pipeline.examples import EXAMPLE_SESSION

ROOT = Path(__file__).resolve().parents[1]


def test_version_is_pyprojects(capsys: pytest.CaptureFixture[str]) -> None:
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert contactcal.infer.__version__ == project["version"]
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.strip() == f"contactcal {project['version']}"
    assert project["license"] == "MIT" and "MIT License" in (ROOT / "LICENSE").read_text()


def test_model_and_example_are_package_data() -> None:
    model = Path(str(resources.files("contactcal.models").joinpath("contact_unet.onnx")))
    session = Path(str(resources.files("contactcal.examples").joinpath("session")))
    assert DEFAULT_MODEL == model and model.is_file()
    assert EXAMPLE_SESSION == session and (session / "manifest.csv").is_file()


@pytest.mark.slow
def test_wheel_runs_the_demo_with_core_dependencies(tmp_path: Path) -> None:
    if shutil.which("git") is None:
        pytest.skip("needs git (the smoke test copies the tracked files)")
    run = subprocess.run(
        ["bash", str(ROOT / ".ci" / "wheel-smoke"), str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    (wheel,) = (tmp_path / "dist").glob("contactcal-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    session = {n for n in names if n.startswith("contactcal/examples/session/")}
    assert {"contactcal/models/contact_unet.onnx", "contactcal/models/MODEL_CARD.md"} <= names
    assert sum(n.endswith(".jpg") for n in session) == 21
    assert sum(n.startswith("contactcal/examples/session/masks/") for n in session) == 21
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    freeze = subprocess.run(
        [str(tmp_path / "venv" / "bin" / "python"), "-m", "pip", "freeze"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.lower()
    assert not any(heavy in freeze for heavy in ("torch", "mitsuba", "onnx==", "kornia"))

"""Every ``contactcal`` command shown in the README and docs runs as written, on tiny data.

Commands are taken from the fenced code blocks of the Markdown files (continuation lines joined,
a leading ``.venv/bin/`` dropped). Each must parse with the real CLI parser; then each file's
commands run in order in a scratch folder, with only their sizes shrunk (frames, fingers,
epochs, network, timing repeats) so that the suite stays fast. ``make`` commands are not run
here: ``make test`` is this suite, and ``make demo`` is ``contactcal demo`` after the set-up.
"""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from contactcal.infer.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "session"
DOCS = sorted(
    [
        ROOT / "README.md",
        *ROOT.glob("docs/*.md"),
        *ROOT.glob("*/README.md"),
        *ROOT.glob("models/*.md"),
    ]
)
#: Option → tiny value, so a documented command runs in seconds on tiny data.
SHRINK = {
    "--fingers": "2",
    "--sessions": "1",
    "--pressures": "0,4,12",
    "--size": "48x36",
    "--spp": "1",
    "--workers": "1",
    "--epochs": "1",
    "--input-size": "32",
    "--levels": "2",
    "--base": "4",
    "--repeats": "1",
    "--timing-frames": "1",
}


def documented_commands(path: Path) -> list[list[str]]:
    """``contactcal`` command lines of the fenced code blocks of a Markdown file, as argv."""
    text = path.read_text(encoding="utf-8")
    out = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.split(" #")[0].strip()
            line = line.removeprefix(".venv/bin/")
            if line.startswith("contactcal "):
                out.append(shlex.split(line)[1:])
    return out


#: Doc file → command → options its commands keep as written, because a later command of that
#: doc needs the full data: ``docs/evaluate.md`` pools five procedural sessions, each with at
#: least five frames in contact the U-Net can see (~10 s at 400×300).
KEEP = {"evaluate.md": {"procedural": ("--fingers", "--pressures", "--size")}}


def shrink(argv: list[str], doc: str = "") -> list[str]:
    """The same command with :data:`SHRINK`'s sizes, except what :data:`KEEP` keeps."""
    out = list(argv)
    keep = KEEP.get(doc, {}).get(out[0], ())
    for i, arg in enumerate(out[:-1]):
        if arg in SHRINK and arg not in keep:
            out[i + 1] = SHRINK[arg]
    return out


ALL = [(p, argv) for p in DOCS for argv in documented_commands(p)]


def python_blocks(path: Path) -> list[str]:
    """The ``python`` fenced code blocks of a Markdown file."""
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def rig_files(root: Path) -> None:
    """The walkthrough's stand-in rig files, made from the bundled example session."""
    from test_video import make_log, make_video

    shutil.copytree(EXAMPLE, root / "session")
    (root / "rig" / "check").mkdir(parents=True)
    shutil.copy(EXAMPLE / "rig.json", root / "rig" / "rig.json")
    for name, kpa in (("ref", 0), ("pressed", 10)):
        img = cv2.imread(str(EXAMPLE / f"p{kpa:04.1f}kpa.jpg"))
        cv2.imwrite(str(root / "rig" / "check" / f"{name}.png"), img)
    kpas = (0, 2, 4, 8, 12, 16, 20, 12, 4, 0)
    make_video(root / "rig" / "run.avi", kpas)
    make_log(root / "rig" / "pressure_log.csv", kpas, np.random.default_rng(0))


#: Doc file name → what its commands expect to find in the working folder.
FIXTURES = {"calibrate-a-display.md": rig_files}


def test_docs_show_commands() -> None:
    assert len(ALL) >= 8, "the docs' command examples were not found"
    assert {a[0] for _, a in ALL} >= {"synth", "train", "export", "bench"}


@pytest.mark.parametrize(("path", "argv"), ALL, ids=[" ".join(a[:2]) for _, a in ALL])
def test_documented_command_parses(path: Path, argv: list[str]) -> None:
    try:
        build_parser().parse_args(argv)
    except SystemExit as exc:
        raise AssertionError(f"{path.name}: `contactcal {' '.join(argv)}` does not parse") from exc


@pytest.mark.slow
@pytest.mark.parametrize("path", sorted({p for p, _ in ALL}), ids=lambda p: p.name)
def test_documented_commands_run(
    path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("mitsuba")
    pytest.importorskip("torch")
    from contactcal.infer.bench import config as bench_config
    from contactcal.infer.bench import run as bench_run

    tiny = bench_config.BenchConfig(repeats=1, timing_frames=1, full_size=(96, 72), threads=(1,))
    monkeypatch.setattr(bench_run, "BenchConfig", lambda **_: tiny)
    monkeypatch.setattr(bench_config, "BenchConfig", lambda **_: tiny)
    monkeypatch.chdir(tmp_path)
    if path.name in FIXTURES:
        FIXTURES[path.name](tmp_path)
    for argv in documented_commands(path):
        code = main(shrink(argv, path.name))
        assert code == 0, f"{path.name}: `contactcal {' '.join(argv)}` exited {code}"
    for code in python_blocks(path):
        exec(compile(code, str(path), "exec"), {})  # the doc's snippet, as written

"""The data a restating tool calibrates on (``interval``, ``min_change``): a path that is no
dataset folder, a folder given twice and the model's training data (as its ``data_digest``
records it) are refused before any frame is read; what was used is recorded in the written entry,
which deployment reads as before."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from contactcal.infer.methods.unet.runner import DEFAULT_MODEL, OnnxSegmenter
from contactcal.infer.methods.unet.spec import ModelError, read_spec

onnx = pytest.importorskip("onnx")

from contactcal.train.change_gate import gate_model  # noqa: E402
from contactcal.train.change_gate import main as gate_main  # noqa: E402
from contactcal.train.digest import dataset_digest  # noqa: E402
from contactcal.train.interval import main as interval_main  # noqa: E402
from contactcal.train.interval import recalibrate_model  # noqa: E402

TOOLS: list[Callable[..., Any]] = [recalibrate_model, gate_model]


def _trained_on(path: Path, dirs: list[Path]) -> Path:
    """The shipped model written to ``path`` as if trained on ``dirs`` (its ``data_digest``)."""
    proto = onnx.load(str(DEFAULT_MODEL))
    meta = {p.key: p.value for p in proto.metadata_props}
    onnx.helper.set_model_props(proto, {**meta, "data_digest": dataset_digest(dirs)})
    onnx.save(proto, str(path))
    return path


def recorded(folder: Path) -> dict[str, Any]:
    """What a calibration records of ``folder``: its name, its index.csv's sha256, its frames."""
    index = (folder / "index.csv").read_bytes()
    frames = len(index.decode().splitlines()) - 1  # one row per frame below the header
    return {
        "folder": folder.name,
        "index_sha256": hashlib.sha256(index).hexdigest(),
        "frames": frames,
    }


@pytest.fixture
def folders(tmp_path: Path) -> list[Path]:
    """Three different one-finger datasets."""
    from procedural import write_dataset

    return [write_dataset(tmp_path / n, fingers=1, seed=s) for s, n in enumerate("abc")]


@pytest.mark.parametrize("tool", TOOLS, ids=["interval", "change_gate"])
def test_a_folder_given_twice_is_refused(
    tool: Callable[..., Any], folders: list[Path], tmp_path: Path
) -> None:
    link = tmp_path / "link"
    link.symlink_to(folders[0], target_is_directory=True)
    out = tmp_path / "out.onnx"
    with pytest.raises(ValueError, match=rf"--data {link}: the same folder as {folders[0]}"):
        tool(DEFAULT_MODEL, [folders[0], folders[1], link], out)
    assert not out.exists()


@pytest.mark.parametrize("tool", TOOLS, ids=["interval", "change_gate"])
def test_the_models_training_data_is_refused(
    tool: Callable[..., Any], folders: list[Path], tmp_path: Path
) -> None:
    a, b, c = folders
    out = tmp_path / "out.onnx"
    alone = _trained_on(tmp_path / "on_a.onnx", [a])
    with pytest.raises(ValueError, match=rf"--data {a}: the model was trained on this data"):
        tool(alone, [c, a], out)
    both = _trained_on(tmp_path / "on_ab.onnx", [a, b])
    with pytest.raises(ValueError, match=rf"--data {a} {b}: the model was trained on this data"):
        tool(both, [c, a, b], out)
    assert not out.exists()


def test_the_cli_names_the_folder_in_one_line(
    folders: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out.onnx"
    argv = [str(DEFAULT_MODEL), "--data", str(folders[0]), str(folders[0]), "--out", str(out)]
    assert interval_main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --data {folders[0]}: the same folder as {folders[0]}")
    assert err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("main", [interval_main, gate_main], ids=["interval", "change_gate"])
@pytest.mark.parametrize(
    ("kind", "problem"),
    [("missing", "does not exist"), ("file", "is not a folder"), ("empty", "missing index.csv")],
)
def test_the_cli_names_the_option_of_a_bad_folder(
    main: Callable[[list[str]], int],
    kind: str,
    problem: str,
    folders: list[Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    bad, out = tmp_path / "bad", tmp_path / "out.onnx"
    if kind == "file":
        bad.write_text("x")
    elif kind == "empty":
        bad.mkdir()
    argv = [str(DEFAULT_MODEL), "--data", str(folders[0]), str(bad), "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --data {bad}: {problem}; expected a dataset folder")
    assert err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("main", [interval_main, gate_main], ids=["interval", "change_gate"])
def test_a_bad_folder_or_option_is_named_before_the_model_is_read(
    main: Callable[[list[str]], int], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model, out = tmp_path / "broken.onnx", tmp_path / "out.onnx"
    model.write_text("not a model")  # its error would come first if it were read first
    argv = [str(model), "--data", str(tmp_path / "none"), "--out", str(out)]
    assert main(argv) == 2
    assert capsys.readouterr().err.startswith(f"error: --data {tmp_path / 'none'}: does not exist")
    if main is gate_main:
        from procedural import write_dataset

        data = write_dataset(tmp_path / "d", fingers=1)
        assert main([str(model), "--data", str(data), "--out", str(out), "--draws", "0"]) == 2
        assert capsys.readouterr().err.startswith("error: --draws 0: expected at least 1")
    assert not out.exists()


def test_recorded_entries_read_as_the_spec_and_others_stay_errors() -> None:
    meta = {p.key: p.value for p in onnx.load(str(DEFAULT_MODEL)).metadata_props}
    spec = read_spec(meta, "m.onnx")
    record = [{"folder": "v", "index_sha256": "0" * 64, "frames": 3}]
    entries = {
        **meta,
        "interval": json.dumps({**json.loads(meta["interval"]), "data": record}),
        "min_change": json.dumps({"value": spec.min_change, "data": record}),
    }
    assert read_spec(entries, "m.onnx") == spec
    for bad in ({"value": 0.1, "data": [], "x": 1}, {"value": True, "data": []}, {"data": []}):
        with pytest.raises(ModelError, match=r"m.onnx.*min_change must be a finite number"):
            read_spec({**meta, "min_change": json.dumps(bad)}, "m.onnx")
    pre = {**json.loads(meta["preprocess"]), "data": record}  # recorded under two entries only
    with pytest.raises(ModelError, match=r"preprocess: unknown key\(s\) \['data'\]"):
        read_spec({**meta, "preprocess": json.dumps(pre)}, "m.onnx")


def test_gate_records_its_data_and_says_the_interval_is_stale(
    folders: list[Path], tmp_path: Path
) -> None:
    out = tmp_path / "gated.onnx"
    summary = gate_model(DEFAULT_MODEL, folders[:2], out, draws=1)
    entry = json.loads({p.key: p.value for p in onnx.load(str(out)).metadata_props}["min_change"])
    assert entry == {"value": summary["min_change"], "data": summary["data"]}
    assert summary["data"] == [recorded(d) for d in folders[:2]]
    spec = OnnxSegmenter(out).spec
    shipped = OnnxSegmenter().spec
    assert spec == dataclasses.replace(shipped, min_change=summary["min_change"])
    assert "the area interval (interval) was calibrated before this change" in summary["stale"]
    assert f"rerun `python -m contactcal.train.interval {out} --data" in summary["stale"]


def test_interval_records_its_data(folders: list[Path], tmp_path: Path) -> None:
    out = tmp_path / "re.onnx"
    summary = recalibrate_model(DEFAULT_MODEL, folders, out)
    entry = json.loads({p.key: p.value for p in onnx.load(str(out)).metadata_props}["interval"])
    assert entry == {**summary["interval"], "data": [recorded(d) for d in folders]}
    assert summary["data"] == entry["data"]
    assert dataclasses.asdict(OnnxSegmenter(out).spec.interval) == summary["interval"]

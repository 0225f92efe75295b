"""ONNX export: checker, torch/onnxruntime parity at a new shape, metadata read back by
deployment's ``read_spec``, errors."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
onnx = pytest.importorskip("onnx")
ort = pytest.importorskip("onnxruntime")

from procedural import write_dataset  # noqa: E402
from test_train import tiny_config  # noqa: E402

from contactcal.infer.methods.unet.config import PreprocessConfig  # noqa: E402
from contactcal.infer.methods.unet.runner import OnnxSegmenter  # noqa: E402
from contactcal.infer.methods.unet.spec import (  # noqa: E402
    OPTIONAL_SPEC_KEYS,
    PROVENANCE_KEYS,
    SPEC_KEYS,
    read_spec,
)
from contactcal.train.commands import OPSETS  # noqa: E402
from contactcal.train.digest import dataset_digest  # noqa: E402
from contactcal.train.export import PARITY_ATOL, PARITY_RTOL, export_onnx, load_run, self_check  # noqa: E402
from contactcal.train.loop import train  # noqa: E402


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("export")
    data = write_dataset(root / "data", fingers=3)
    train([data], root / "run", tiny_config(epochs=1, input_size=64), progress=False)
    return root / "run"


@pytest.mark.slow
def test_export_metadata_and_parity(run_dir: Path, tmp_path: Path) -> None:
    out = export_onnx(run_dir, tmp_path / "models" / "tiny.onnx")
    assert out == tmp_path / "models" / "tiny.onnx" and out.is_file()
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # no temp left
    model = onnx.load(str(out))
    onnx.checker.check_model(model, full_check=True)
    meta = {p.key: p.value for p in model.metadata_props}
    # no input_size, no reference; the optional region is always written
    assert sorted(meta) == sorted((*SPEC_KEYS, *OPTIONAL_SPEC_KEYS, *PROVENANCE_KEYS))
    assert meta["region"] == "largest"
    assert meta["channels"] == "2"
    assert PreprocessConfig(**json.loads(meta["preprocess"])) == PreprocessConfig(input_size=64)
    assert float(meta["threshold"]) == 0.5 and float(meta["min_contact_area_px"]) == 4.0
    assert meta["data_digest"] == dataset_digest([run_dir.parent / "data"])
    assert meta["contactcal_version"] and meta["created"] and meta["output"] == "logits"
    # the area interval, calibrated on the run's validation finger (5 frames at most)
    interval = json.loads(meta["interval"])
    assert interval["level"] == 0.9 and 1 <= interval["frames"] <= 5 and interval["widen"] >= 0
    # deployment reads exactly the run's spec, with the calibrated interval
    cfg, _, ckpt = load_run(run_dir)
    spec = read_spec(meta, out)
    assert (
        spec == dataclasses.replace(cfg.spec(), interval=spec.interval) == OnnxSegmenter(out).spec
    )
    assert spec.interval is not None and spec.interval.widen == interval["widen"]
    # dynamic batch/H/W: run at a size other than the export's and compare with torch
    from contactcal.train.model import UNet

    net = UNet(cfg.model).eval()
    net.load_state_dict(ckpt["model"])
    x = torch.randn((3, 2, 80, 96), generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        ref = net(x).numpy()
    sess = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    got = sess.run(None, {"input": x.numpy()})[0]
    assert got.shape == (3, 1, 80, 96)
    np.testing.assert_allclose(got, ref, atol=PARITY_ATOL, rtol=PARITY_RTOL)


def test_self_check_rejects_foreign_metadata(tmp_path: Path) -> None:
    from contactcal.infer.methods.unet.spec import IntervalSpec, ModelSpec

    spec = ModelSpec(
        1, PreprocessConfig(input_size=32), 0.5, 4.0, IntervalSpec(0.9, 0.1, 0.9, 1.0, 9)
    )
    graph = onnx.helper.make_graph(
        [onnx.helper.make_node("Identity", ["input"], ["logits"])],
        "g",
        [onnx.helper.make_tensor_value_info("input", onnx.TensorProto.FLOAT, [1])],
        [onnx.helper.make_tensor_value_info("logits", onnx.TensorProto.FLOAT, [1])],
    )
    proto = onnx.helper.make_model(graph)
    provenance = {k: "x" for k in PROVENANCE_KEYS}
    onnx.helper.set_model_props(proto, {**spec.to_metadata(), **provenance})
    self_check(proto.SerializeToString(), spec, tmp_path / "m.onnx")  # accepted
    onnx.helper.set_model_props(proto, {**spec.to_metadata(), **provenance, "input_size": "32"})
    with pytest.raises(RuntimeError, match="input_size"):
        self_check(proto.SerializeToString(), spec, tmp_path / "m.onnx")


@pytest.mark.slow
def test_export_errors(run_dir: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="config.json"):
        export_onnx(tmp_path / "nothing", tmp_path / "m.onnx")
    dataset = write_dataset(tmp_path / "data", fingers=1)  # a dataset folder, not a run
    (dataset / "config.json").write_text(json.dumps({"fingers": 1, "seed": 0}))
    with pytest.raises(ValueError, match="not a `contactcal train` run config"):
        export_onnx(dataset, tmp_path / "m.onnx")
    with pytest.raises(ValueError, match=r"\.onnx"):
        export_onnx(run_dir, tmp_path / "m.txt")
    moved = tmp_path / "moved"  # a run whose data folder is not where its config says
    moved.mkdir()
    (moved / "best.pt").write_bytes((run_dir / "best.pt").read_bytes())
    info = json.loads((run_dir / "config.json").read_text())
    (moved / "config.json").write_text(json.dumps({**info, "data_dirs": ["gone/data"]}))
    with pytest.raises(ValueError, match=r"config\.json: the run's dataset folder gone/data"):
        export_onnx(moved, tmp_path / "m.onnx")
    assert all(Path(d).is_absolute() for d in info["data_dirs"])  # found from any folder
    (moved / "config.json").write_text(json.dumps({**info, "data_digest": "0" * 64}))
    with pytest.raises(ValueError, match=r"no longer hold the data it was trained on"):
        export_onnx(moved, tmp_path / "m.onnx")  # e.g. re-rendered with another seed since
    (moved / "config.json").write_text(
        json.dumps({k: v for k, v in info.items() if k != "data_dirs"})
    )
    with pytest.raises(ValueError, match="expected data_dirs"):
        export_onnx(moved, tmp_path / "m.onnx")
    assert not (tmp_path / "m.onnx").exists()


@pytest.mark.slow
@pytest.mark.parametrize("opset", [OPSETS[0], OPSETS[-1]])
def test_export_at_the_ends_of_the_opset_range(run_dir: Path, tmp_path: Path, opset: int) -> None:
    out = export_onnx(run_dir, tmp_path / "m.onnx", opset=opset)  # checks itself: parity
    assert onnx.load(str(out)).opset_import[0].version == opset


def test_cli_export_refuses_bad_options_before_the_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from contactcal.infer.cli import main

    target = tmp_path / "kept.onnx"
    target.write_bytes(b"kept")
    link = tmp_path / "link.onnx"
    link.symlink_to(target)
    run = tmp_path / "no_run"  # never read: the options are refused first
    folder = tmp_path / "folder.onnx"
    folder.mkdir()
    for argv, says in (
        (["--out", str(tmp_path / "m.onnx"), "--opset", "99"], "--opset must be"),
        (["--out", str(link)], f"--out {link}: is a symbolic link"),
        (["--out", str(tmp_path / "m.txt")], f"--out {tmp_path / 'm.txt'}: expected an output"),
        (["--out", str(folder)], f"--out {folder}: exists and is not a regular file"),
        (["--out", str(target / "m.onnx")], f"--out {target / 'm.onnx'}: {target}: is not a"),
    ):
        assert main(["export", str(run), *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0] and "--out -" not in err[0], err
    assert target.read_bytes() == b"kept" and link.is_symlink()


@pytest.mark.slow
def test_cli_a_failed_export_check_is_one_line_and_writes_nothing(
    run_dir: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from contactcal.infer.cli import main
    from contactcal.train import export
    from contactcal.train.export_check import ExportCheckError

    def parity_fails(*args: object) -> None:
        raise ExportCheckError("ONNX output differs from torch\n  max |diff| 0.3")

    monkeypatch.setattr(export, "check_parity", parity_fails)
    out = tmp_path / "m.onnx"
    assert main(["export", str(run_dir), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "ONNX output differs from torch max |diff| 0.3; nothing was written" in err[0]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_export_of_an_unfinished_run_warns(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A run without val_bins.csv (stopped, or still training) exports, with one warning line; a
    finished run whose last.pt was deleted, without."""
    from contactcal.infer.cli import main

    assert main(["export", str(run_dir), "--out", str(tmp_path / "done.onnx")]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "replaced" not in out  # finished: no warning; nothing replaced
    run = tmp_path / "run"
    shutil.copytree(run_dir, run)
    (run / "val_bins.csv").unlink()
    assert main(["export", str(run), "--out", str(tmp_path / "m.onnx")]) == 0
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert err.startswith(f"warning: {run}: an unfinished run (no val_bins.csv"), err
    assert "--resume the run to its last epoch" in err and (tmp_path / "m.onnx").is_file()
    kept = tmp_path / "kept"  # finished, its last.pt deleted (only best.pt kept): no warning
    shutil.copytree(run_dir, kept)
    (kept / "last.pt").unlink()
    assert main(["export", str(kept), "--out", str(tmp_path / "k.onnx")]) == 0
    assert capsys.readouterr().err == "" and (tmp_path / "k.onnx").is_file()


@pytest.mark.slow
def test_cli_export_says_which_model_it_replaced(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An --out that held a file is replaced with a note naming it and its content's sha256."""
    from contactcal.infer.cli import main
    from contactcal.infer.files.digest import sha256_bytes

    out = tmp_path / "m.onnx"
    out.write_bytes(b"an earlier model")
    assert main(["export", str(run_dir), "--out", str(out)]) == 0
    wrote, note = capsys.readouterr().out.strip().splitlines()
    held = sha256_bytes(b"an earlier model")[:12]
    assert wrote == f"wrote {out}"
    assert note == f"note: replaced {out} (sha256 {held}); give each run its own --out to keep both"
    assert onnx.load(str(out)).graph.node  # the new model


@pytest.mark.slow
def test_tune_min_area_never_worse(run_dir: Path, tmp_path: Path) -> None:
    from contactcal.train.threshold import tune_min_area

    best, s = tune_min_area(run_dir)
    assert best >= 0 and s["frames"] > 0
    tuned = s["tuned_false_contacts"] + s["tuned_missed_contacts"]
    assert tuned <= s["default_false_contacts"] + s["default_missed_contacts"]
    out = export_onnx(run_dir, tmp_path / "t.onnx", min_contact_area_px=best)
    meta = {p.key: p.value for p in onnx.load(str(out)).metadata_props}
    assert float(meta["min_contact_area_px"]) == best


def test_widest_margin_reference_values() -> None:
    """Fewest errors for 3-53 px (false regions 0-2 px, smallest contact 53 px) → sqrt(3 · 53);
    a tie further up (177-271) is not chosen; without any rise the lowest optimum is kept."""
    pytest.importorskip("torch")
    from contactcal.train.threshold import widest_margin

    areas = np.array([0, 0, 1, 2, 119, 176, 611, 53, 110, 270, 335], float)
    contact = np.array([False] * 7 + [True] * 4)
    assert widest_margin(areas, contact, 30.0) == pytest.approx(np.sqrt(3.0 * 53.0))
    clean = np.array([0, 0, 40, 50], float)
    assert widest_margin(clean, np.array([False, False, True, True]), 30.0) == pytest.approx(
        np.sqrt(1.0 * 40.0)
    )
    # a one-pixel optimum (false region 9 px, contact 10 px) keeps the 10-px contact
    tight = np.array([9, 10, 50], float)
    assert widest_margin(tight, np.array([False, True, True]), 30.0) == 10.0

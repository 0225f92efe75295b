"""Write an exported model again with some of its deployment metadata restated.

The graph and weights are copied untouched; the new metadata must pass ``onnx.checker`` (full
check) and read back through deployment's ``read_spec`` as the intended spec before the file is
written (atomically). Used by :mod:`contactcal.train.interval` (``interval``, ``region``),
:mod:`contactcal.train.change_gate` (``min_change``) and :mod:`contactcal.train.floor`
(``preprocess``). A tool whose change leaves a calibrated entry stale says so (:func:`stale`):
in its summary's ``stale`` and in a warning line.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any

from contactcal.infer.errors import option_error
from contactcal.infer.files.atomic import atomic_open
from contactcal.infer.files.destination import check_destination
from contactcal.infer.files.digest import sha256_file
from contactcal.infer.files.regular import read_input_bytes
from contactcal.infer.files.replaced import replaced_file_note
from contactcal.infer.methods.unet.spec import ModelSpec, read_spec
from contactcal.infer.parser import Parser, folder_arg

#: Each calibrated metadata entry: what it is, and the tool that calibrates it; in the order to
#: rerun them (the interval is calibrated with the model's change gate on, the gate with it off).
RECALIBRATED_BY = {
    "min_change": ("the change gate (min_change)", "python -m contactcal.train.change_gate"),
    "interval": ("the area interval (interval)", "python -m contactcal.train.interval"),
}


def stale(entries: Collection[str], out: Path) -> str | None:
    """The summary's ``stale``: which calibrated entries a change left stale and what to rerun.

    Args:
        entries: keys of :data:`RECALIBRATED_BY` calibrated before the change (and kept as they
            were in the written model).
        out: the written model, the one to calibrate again.

    Returns:
        One sentence naming the entries and the tools to rerun, in order; None when ``entries``
        is empty.
    """
    order = [RECALIBRATED_BY[k] for k in RECALIBRATED_BY if k in entries]
    if not order:
        return None
    what = " and ".join(name for name, _ in order)
    tools = ", then ".join(f"`{tool} {out} --data DIR... --out NEW.onnx`" for _, tool in order)
    return (
        f"{what} {'was' if len(order) == 1 else 'were'} calibrated before this change and "
        f"{'is' if len(order) == 1 else 'are'} kept as before; rerun {tools} on validation renders"
    )


def check_model_out(out: Path, protect: Collection[Path]) -> None:
    """Refuse an output model (``--out``) before any work: not ``.onnx``, one of the inputs
    ``protect`` (any spelling or hard link), a link, a folder or device, or under a file.

    Raises:
        ValueError: ``--out OUT: ...``, naming what was expected.
    """
    if out.suffix.lower() != ".onnx":
        raise ValueError(f"--out {out}: expected an output file name ending in .onnx")
    try:
        check_destination(out, protect)
    except ValueError as exc:
        raise option_error("--out", out, exc) from None


def earlier_model_note(out: Path) -> str | None:
    """The note naming the model a command's ``--out`` replaces, with the start of its sha256
    (call it before the command writes ``out``); None when there is none yet."""
    return replaced_file_note(out, _model_held)


def _model_held(out: Path) -> str:
    """The start of the sha256 of the model file ``out`` (its content before the run)."""
    try:
        return f"sha256 {sha256_file(out)[:12]}"
    except OSError as exc:
        return f"unreadable: {exc.strerror}"


def check_paths(model: str | os.PathLike[str], out: str | os.PathLike[str]) -> tuple[Path, Path]:
    """``(model, out)`` as paths, or an error: ``out`` must pass :func:`check_model_out`, which
    refuses ``model`` itself (inputs are never overwritten).

    Raises:
        ValueError: bad output name or destination, or the output is the input.
    """
    src, dst = Path(model), Path(out)
    check_model_out(dst, [src])
    return src, dst


#: What a restating tool's ``MODEL`` must be, for its refusals.
_MODEL_EXPECTED = "a .onnx file written by contactcal export"


def load_proto(model: Path) -> Any:
    """The ONNX ``ModelProto`` of ``model``.

    Raises:
        ValueError: the file cannot be read or is not an ONNX model (the message names it).
    """
    return read_model(model)[1]


def read_model(model: Path) -> tuple[bytes, Any]:
    """The content of ``model`` and its ONNX ``ModelProto``, from one read of the file (a tool
    that measures the model and rewrites it measures the model it writes), read as every input
    is (:func:`~contactcal.infer.files.regular.read_input_bytes`: a folder, device or pipe is
    refused unread, never read until memory runs out nor waited on).

    Raises:
        ValueError: the file is a folder or not a regular file, cannot be read, or is not an
            ONNX model (the message names it).
    """
    import onnx
    from google.protobuf.message import DecodeError

    try:
        content = read_input_bytes(model, _MODEL_EXPECTED, ValueError)
    except OSError as exc:
        raise _unreadable(model, exc) from None
    try:
        return content, onnx.load_from_string(content)
    except (DecodeError, ValueError) as exc:
        raise _unreadable(model, exc) from None


def _unreadable(model: Path, exc: Exception) -> ValueError:
    """The error of a ``model`` that could not be read, or is not an ONNX model (``exc``)."""
    return ValueError(f"{model}: not a readable ONNX model ({exc}); expected {_MODEL_EXPECTED}")


def metadata_of(proto: Any) -> dict[str, str]:
    """An ONNX ``ModelProto``'s ``metadata_props`` as a dict."""
    return {p.key: p.value for p in proto.metadata_props}


def save_restated(proto: Any, updates: Mapping[str, str], spec: ModelSpec, out: Path) -> None:
    """Write ``proto`` to ``out`` with ``updates`` merged into its metadata.

    Args:
        proto: the loaded source model (modified in place: its metadata).
        updates: metadata key → new string value.
        spec: the spec the new metadata must read back as.
        out: destination ``.onnx`` (replaced atomically, only on success).

    Raises:
        RuntimeError: the new metadata does not read back as ``spec``.
    """
    import onnx

    onnx.helper.set_model_props(proto, {**metadata_of(proto), **updates})
    onnx.checker.check_model(proto, full_check=True)
    if read_spec(metadata_of(proto), out) != spec:
        raise RuntimeError(f"{out}: the metadata does not read back as the intended spec")
    with atomic_open(out, "wb") as fh:
        fh.write(proto.SerializeToString())


def restating_parser(prog: str, description: str) -> argparse.ArgumentParser:
    """The command line every restating tool shares: ``MODEL --data DIR... --out NEW.onnx``."""
    ap = Parser(prog=prog, description=description)
    ap.add_argument("model", type=Path, help="exported .onnx model")
    ap.add_argument("--data", type=folder_arg, nargs="+", required=True, help="dataset folder(s)")
    ap.add_argument("--out", type=Path, required=True, help="new .onnx file")
    return ap


def run_restating(restate: Callable[[], dict[str, Any]], out: str | os.PathLike[str]) -> int:
    """Run a restating tool: print its summary (standard JSON) and 0, or one error line and 2
    (nothing written; or, where standard output failed after ``out`` was written, saying so and
    repeating the notes); an earlier model that ``out`` held is named after the ``wrote`` line
    (:func:`earlier_model_note`), and a summary's ``stale`` (:func:`stale`) is also a warning
    line on stderr.

    Args:
        restate: writes ``out`` and returns the summary (raises ``ValueError`` / ``OSError``).
        out: the file it writes, for the last lines.
    """
    from contactcal.infer.files.stdout import named_stdout, printing_after

    replaced = earlier_model_note(Path(out))  # before the run writes it; said once written
    try:
        with named_stdout():  # a closed pipe: one line, as the CLI's (no traceback)
            summary = restate()
            warning = f"warning: {out}: {summary['stale']}" if summary.get("stale") else None
            with printing_after([out], [warning, replaced]):
                print(json.dumps(summary, indent=1, allow_nan=False))
                print(f"wrote {out}")
                if replaced is not None:
                    print(replaced)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if warning is not None:
        print(warning, file=sys.stderr)
    return 0

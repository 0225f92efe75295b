"""The ``measure`` and ``demo`` subcommands."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from contactcal.infer.calibration.command import add_step_tolerance_arg, step_tolerance
from contactcal.infer.parser import folder_arg
from contactcal.infer.pipeline.args import (
    bit_depth_arg,
    check_bit_depth,
    check_change_gate,
    check_out_folder,
    check_output_folder,
    measure_options,
    method_args,
    read_rig,
    run_inputs,
    scale_args,
)
from contactcal.infer.pipeline.overlay_measure import (
    overlay_contents,
    overlay_methods,
    overlay_runs,
)

if TYPE_CHECKING:
    from contactcal.infer.files.atomic import OutputSet
    from contactcal.infer.image.read import ImageFile
    from contactcal.infer.methods.base import Method
    from contactcal.infer.pipeline.measure import Measured
    from contactcal.infer.pipeline.options import MeasureOptions


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``measure`` and ``demo`` to the ``contactcal`` subcommands."""
    m = sub.add_parser("measure", help="measure the contact area in images")
    m.add_argument("images", nargs="+", type=Path, metavar="IMAGE")
    method_args(m)
    m.add_argument("--reference", type=Path, help="the session's zero-pressure frame")
    m.add_argument(
        "--out", type=Path, required=True, help="results JSON (list, one per image); - for stdout"
    )
    scale_args(m)
    m.set_defaults(func=_cmd_measure)
    d = sub.add_parser("demo", help="calibrate the bundled example session with both methods")
    d.add_argument("--out", type=folder_arg, default=Path("out/demo"), help="output folder")
    d.add_argument("--manifest", type=Path, help="another session instead of the example")
    add_step_tolerance_arg(d)
    bit_depth_arg(d)
    d.set_defaults(func=_cmd_demo)


def _cmd_measure(args: argparse.Namespace) -> int:
    """``contactcal measure``: the checks before the work, the run, then its report."""
    from contactcal.infer.calibration.provenance import check_device_id
    from contactcal.infer.pipeline.overlay import overlay_names

    check_device_id(args.device_id)
    check_change_gate(args)
    named_as = tuple(overlay_names(args.images))
    check_output_folder("--overlay", args.overlay, named_as)  # before the work
    to_stdout = _results_to_stdout(args.out)
    replaced = None if to_stdout else earlier_results_note(args.out)
    run = _measure_run(args, to_stdout)
    _print_measured(args, run, to_stdout, replaced)
    return 0


@dataclass(frozen=True)
class _MeasureRun:
    """What a ``measure`` run measured and wrote."""

    measured: list[Measured]  # the frames, as noted by note_self_reference
    warnings: list[str]  # note_self_reference's lines
    text: str  # the results JSON
    written: list[Path]  # the overlay files written (none without --overlay)


def _results_to_stdout(out: Path) -> bool:
    """Whether ``measure --out`` is ``-`` (standard output), once checked before the work.

    Raises:
        ValueError: ``--out -`` with standard output closed, or a file name not ending in .json.
    """
    from contactcal.infer.image.read import SUPPORTED_SUFFIXES

    to_stdout = str(out) == "-"
    if to_stdout and sys.stdout is None:
        raise ValueError(
            "--out -: standard output is closed (the command was started with it closed); "
            "give --out results.json, or run it with standard output open"
        )
    if not to_stdout and out.suffix.lower() != ".json":
        image = out.suffix.lower() in SUPPORTED_SUFFIXES
        raise ValueError(
            f"--out {out}: expected a JSON file name ending in .json (results.json) or - "
            "for standard output"
            + (
                ", got an image name (did the shell expand a pattern right after --out?)"
                if image
                else " (measure writes JSON; a name like a manifest's would replace that file)"
            )
        )
    return to_stdout


def _measure_run(args: argparse.Namespace, to_stdout: bool) -> _MeasureRun:
    """Measure ``args.images`` and write the results (``--out``, unless ``to_stdout``) and the
    overlays (``--overlay``), all or nothing."""
    from contactcal.infer.files.atomic import run_outputs, write_synced
    from contactcal.infer.files.jsonable import json_text
    from contactcal.infer.pipeline.measure import note_self_reference

    named = {"--out": None if to_stdout else args.out, "--overlay": args.overlay}
    with run_outputs([*args.images, *run_inputs(args)], options=named) as outs:
        json_path = None if to_stdout else _stage_results(outs, args.out)  # before the work
        options = measure_options(args, read_rig(args))
        method = options.method(args.method)
        read = overlay_contents(args)  # None: no --overlay; filled as the frames are measured
        # the methods drawing only outlines, built (a --model loaded) before a frame is read
        drawn = {} if read is None else overlay_methods(args, options)
        ref = args.reference
        measured = options.measure(args.images, method, ref, read is not None, read)
        measured, warnings = note_self_reference(measured, args.reference)
        # the models and device_id, per object (the output stays a list of objects)
        made = {
            **_models_used(method, None if read is None else drawn),
            "device_id": args.device_id,
        }
        text = json_text([{**m.to_json(method.name), **made} for m in measured])
        if json_path is not None:
            write_synced(json_path, text)
        written = (
            [] if read is None else _write_overlays(args, options, measured, read, drawn, outs)
        )
    return _MeasureRun(measured, warnings, text, written)


def _models_used(method: Method, drawn: dict[str, Method] | None) -> dict[str, Any]:
    """What each result of ``measure`` records of the models that ran, as ``calibration.json``
    names them (:func:`~contactcal.infer.methods.base.model_identity`): ``model`` and
    ``model_sha256`` of ``method`` (None: a method without a model), and ``overlay_methods``:
    each method that only drew the overlays' outlines (``drawn``) with its own (None: no
    ``--overlay``)."""
    from contactcal.infer.methods.base import model_identity

    overlays = None if drawn is None else {n: model_identity(m) for n, m in drawn.items()}
    return {**model_identity(method), "overlay_methods": overlays}


def _write_overlays(
    args: argparse.Namespace,
    options: MeasureOptions,
    measured: list[Measured],
    read: dict[Path, ImageFile],
    drawn: dict[str, Method],
    outs: OutputSet,
) -> list[Path]:
    """``measure --overlay``: every method's outline (``measured``'s, and those of the methods
    ``drawn`` that only draw) on the frames (from the contents ``read`` as they were measured,
    not read again), staged into ``outs``."""
    from contactcal.infer.image.read import sources_of
    from contactcal.infer.pipeline.overlay import write_overlays

    images = sources_of(args.images, read)  # the contents measured, not read again
    ref = args.reference
    reference = None if ref is None else read[ref]
    runs = overlay_runs(args, options, measured, images, reference, drawn)
    bits = args.bit_depth
    return write_overlays(runs, read, args.overlay, outputs=outs, bit_depth=bits)


def _print_measured(
    args: argparse.Namespace, run: _MeasureRun, to_stdout: bool, replaced: str | None
) -> None:
    """``measure``'s report: the results JSON on standard output with ``--out -``, a line per
    frame (on standard error then), the warnings, and the notes of the files replaced."""
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.pipeline.overlay import earlier_overlays_note

    overlays = [] if args.overlay is None else [args.overlay]
    with printing_after([*([] if to_stdout else [args.out]), *overlays], [replaced]):
        if to_stdout:
            sys.stdout.write(run.text)
        for m in run.measured:
            mm2 = m.area_mm2
            area = f"{mm2:8.1f} mm²" if mm2 is not None else f"{m.result.area_px:10.0f} px"
            line = f"{m.file}  contact={'yes' if m.result.contact else 'no ':3s} area={area}"
            print(line, file=sys.stderr if to_stdout else sys.stdout)
        for line in run.warnings:
            print(line, file=sys.stderr)
        for note in (earlier_overlays_note(run.written), replaced):
            if note is not None:
                print(note, file=sys.stderr if to_stdout else sys.stdout)


def _stage_results(outs: OutputSet, out: Path) -> Path:
    """``measure``'s results file, staged: refused (before the work) where it must not be
    written (``--out OUT: ...``: ``outs`` names ``--out``), a link with the other way to get the
    JSON named."""
    from contactcal.infer.files.destination import LinkOutputError

    try:
        return outs.stage(out)
    except LinkOutputError as exc:
        raise LinkOutputError(f"{exc}, or --out - for standard output") from None


def earlier_results_note(out: Path) -> str | None:
    """A line naming the file ``measure --out`` replaces and how many results it held (None:
    there is none yet; :func:`~contactcal.infer.files.replaced.replaced_file_note`)."""
    from contactcal.infer.files.replaced import replaced_file_note

    return replaced_file_note(out, _results_held)


def _results_held(out: Path) -> str:
    """How many results the file ``out`` holds ("not a results list" when it is not one), read
    as inputs are (a device or pipe put there after the caller's check is not read)."""
    from contactcal.infer.files.regular import read_input_json

    try:
        old = read_input_json(out, "earlier results", ValueError)
    except (OSError, ValueError):
        return "unreadable as results"
    return f"{len(old)} result(s)" if isinstance(old, list) else "not a results list"


def _cmd_demo(args: argparse.Namespace) -> int:
    from contactcal.infer.calibration.calibrate import SessionOptions
    from contactcal.infer.calibration.out_folder import (
        check_same_device,
        check_same_unit,
        earlier_record_note,
        held_record,
    )
    from contactcal.infer.files.atomic import run_outputs
    from contactcal.infer.files.stdout import printing_after
    from contactcal.infer.methods.registry import METHODS
    from contactcal.infer.pipeline.demo import DEMO_FILES, DEMO_SCALE, demo_measure, run_demo
    from contactcal.infer.pipeline.examples import example_manifest

    options = SessionOptions(step_tolerance_kpa=step_tolerance(args))
    check_bit_depth(args.bit_depth)
    check_out_folder(args.out, "demo", DEMO_FILES)  # before the work
    manifest = example_manifest() if args.manifest is None else args.manifest
    measure = demo_measure(manifest, args.bit_depth)  # the scale, for the --out check
    no_scale = DEMO_SCALE if measure.scale is None else None
    held = {d: held_record(d) for d in (args.out / m for m in METHODS)}
    for record in held.values():  # a display's calibration, or one in mm²: as calibrate does
        check_same_device(record, None, takes_device_id=False)
        check_same_unit(record, no_scale, "put the rig.json it used beside the manifest")
    replaced = [earlier_record_note(d, record) for d, record in held.items()]
    with run_outputs(options={"--out": args.out}) as outs:
        summary = run_demo(args.out, manifest, args.argv, options, measure, outs)
    with printing_after([args.out], replaced):
        print(summary)
        for note in replaced:
            if note is not None:
                print(note)
    return 0

"""What an ``--overlay`` run measures: the frames' contents it holds, the methods that only draw
the overlays' outlines, and every method's measurements of the frames."""

from __future__ import annotations

from typing import TYPE_CHECKING

from contactcal.infer.methods.registry import METHODS

if TYPE_CHECKING:
    import argparse
    from collections.abc import Sequence
    from pathlib import Path

    from contactcal.infer.image.read import ImageFile, ImageSource
    from contactcal.infer.methods.base import Method
    from contactcal.infer.pipeline.measure import Measured
    from contactcal.infer.pipeline.options import MeasureOptions


def overlay_contents(args: argparse.Namespace) -> dict[Path, ImageFile] | None:
    """With ``--overlay``: the frames' contents the run holds, empty until its measurement reads
    each frame (and the reference) into it once
    (:func:`~contactcal.infer.pipeline.measure.measure_files`), after the checks a run without
    ``--overlay`` makes before reading a frame (the manifest's, the model's, the boundary
    offset's; the reference first); every method's outlines and the drawing then take that
    content (a frame replaced during the run is taken as it was read). Without it None: each
    frame is read when it is measured, none held."""
    return None if args.overlay is None else {}


def overlay_methods(args: argparse.Namespace, options: MeasureOptions) -> dict[str, Method]:
    """The methods that only draw the overlays' outlines (every method but ``--method``), built
    once, before a frame is read: a run records them (``calibrate`` their ``describe()``,
    ``measure`` their model; the U-Net's model and its sha256, of the content loaded) and
    :func:`overlay_runs` measures with them."""
    return {n: options.method(n, outline=True) for n in METHODS if n != args.method}


def overlay_runs(
    args: argparse.Namespace,
    options: MeasureOptions,
    primary: list[Measured],
    files: Sequence[ImageSource],
    reference: ImageSource | None,
    drawn: dict[str, Method],
) -> dict[str, list[Measured]]:
    """Measurements of every method for the overlays (the primary run, measured with its
    digests, is reused; the others, ``drawn`` (:func:`overlay_methods`), only draw outlines, so
    they get no scale or boundary offset) of ``files`` against ``reference`` (the contents the
    primary run measured: :func:`overlay_contents`), each with the digest of the content
    measured (:func:`~contactcal.infer.pipeline.overlay.measured_frame` checks it)."""
    from dataclasses import replace

    outlines = replace(options, scale=None, boundary=None)
    runs = {args.method: primary}
    for name, method in drawn.items():
        runs[name] = outlines.measure(files, method, reference, digest=True)
    return runs

"""Reading a calibration back: :func:`load_curve` (for a controller), format versions 1 to 3."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from contactcal.infer.calibration.band import Band
from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.parametric import Saturating
from contactcal.infer.calibration.phases import LOADING

FORMAT = "contactcal.calibration"
FORMAT_VERSION = 3
#: Versions :func:`load_curve` reads: 2 added the run's provenance; 3 phases (loading and
#: unloading), steps of repeated frames, the parametric model, the band and hysteresis.
READABLE_VERSIONS = (1, 2, 3)


def _curve(fit: dict[str, Any], onset: Any, unit: Any, inverse: Any, **more: Any) -> Curve:
    return Curve(
        np.asarray(fit["pressure_kpa"], dtype=np.float64),
        np.asarray(fit["area"], dtype=np.float64),
        onset,
        unit,
        (inverse or {}).get("step"),
        **more,
    )


def _phase_curve(data: dict[str, Any], phase: str | None, allow_unresolved: bool) -> Curve:
    """The curve of ``phase`` (None: the recorded inverse phase) from a version 3 record."""
    name = (phase or data["inverse_phase"]).lower()
    if name not in data["phases"]:
        raise ValueError(f"no {name} phase (the record has {', '.join(data['phases'])})")
    ph = data["phases"][name]
    res = ph.get("resolution") or {}
    if res.get("resolves") is False and not allow_unresolved:
        # format 3 records written before the rise floor hold no reason: that criterion
        why = res.get("reason") or (
            f"rises {res['rise']:.3g} {data['area_unit']} over its contact steps, no more than "
            f"its own cross-validated error ({res['cv_rmse']:.3g})"
        )
        raise UnresolvedCurveError(
            f"the {name} curve {why}: it cannot tell pressures apart, so a controller would get "
            "arbitrary pressures; recalibrate (check the overlays), or read it anyway with "
            "allow_unresolved=True"
        )
    m, b = ph.get("parametric"), ph.get("band")
    model = None if m is None else Saturating(m["p0_kpa"], m["k_kpa"], m["a_max"])
    band = None
    if b is not None:
        band = Band(b["pressure_kpa"], b["lo"], b["hi"], b["level"], b["n_resamples"], b["seed"])
    return _curve(
        ph["fit"], ph["onset_kpa"], data["area_unit"], ph["inverse"], model=model, band=band
    )


class UnresolvedCurveError(ValueError):
    """The record says the curve does not resolve pressures (``phases.*.resolution``)."""


def load_curve(
    path: str | os.PathLike[str],
    phase: str | None = None,
    allow_unresolved: bool = False,
    area_unit: str | None = None,
) -> Curve:
    """Read a fitted `Curve` back from a ``calibration.json`` (for the controller).

    Args:
        path: the record.
        phase: ``"loading"`` or ``"unloading"`` (any case); None → the phase the run inverted
            (versions 1 and 2 hold the loading pass only). A version 3 curve carries its
            parametric model and its band (`Curve.pressure_interval_for_area`); older ones
            have no band.
        allow_unresolved: read a curve the record says does not resolve pressures (its rise
            over the contact steps no larger than its cross-validated error; ``calibrate``
            warned); by default that is an error, not a silently flat curve.
        area_unit: the unit the caller's areas are in (``"mm²"`` or ``"px"``): a record in
            another unit is refused (a session calibrated without a pixel scale holds px, and
            an area in mm² looked up in it would be wrong by the scale squared, silently).
            None: not checked (``Curve.area_unit`` says which).

    Raises:
        UnresolvedCurveError: the curve does not resolve pressures (and not allowed).
        ValueError: unreadable file, not a contactcal calibration, no such phase, or another
            unit than ``area_unit``.
    """
    curve = _read_curve(path, phase, allow_unresolved)
    if area_unit is not None and curve.area_unit != area_unit:
        raise ValueError(
            f"{path}: its areas are in {curve.area_unit}, expected {area_unit} (a session "
            "calibrated without a pixel scale is in px: put a rig.json beside its manifest, or "
            "give --mm-per-px or --rig, and calibrate it again)"
        )
    return curve


def _read_curve(path: str | os.PathLike[str], phase: str | None, allow_unresolved: bool) -> Curve:
    """:func:`load_curve` without the unit check."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        if data.get("format") != FORMAT:
            raise ValueError(f"format {data.get('format')!r}, expected {FORMAT!r}")
        version = data.get("format_version")
        if version not in READABLE_VERSIONS:
            raise ValueError(
                f"format_version {version!r}, expected one of "
                f"{', '.join(map(str, READABLE_VERSIONS))} (written by a newer contactcal?)"
            )
        if version == 3:
            return _phase_curve(data, phase, allow_unresolved)
        if phase is not None and phase.lower() != LOADING:
            raise ValueError(f"format_version {version} holds the loading pass only, not {phase}")
        return _curve(data["fit"], data["onset_kpa"], data["area_unit"], data.get("inverse"))
    except UnresolvedCurveError as exc:
        raise UnresolvedCurveError(f"{path}: {exc}") from exc
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"{path}: not a readable contactcal calibration ({exc})") from exc

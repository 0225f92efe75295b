"""Reading a calibration back: :func:`load_curve` (for a controller), format versions 1 to 3."""

from __future__ import annotations

import errno
import json
import os
import warnings
from typing import Any

import numpy as np

from contactcal.infer.calibration.band import Band
from contactcal.infer.calibration.curve import MM2, PX, Curve
from contactcal.infer.calibration.parametric import Saturating
from contactcal.infer.calibration.phases import LOADING
from contactcal.infer.files.regular import read_input_json

FORMAT = "contactcal.calibration"
FORMAT_VERSION = 3
#: Versions :func:`load_curve` reads: 2 added the run's provenance; 3 phases (loading and
#: unloading), steps of repeated frames, the parametric model, the band and hysteresis.
READABLE_VERSIONS = (1, 2, 3)
#: What :func:`load_curve` expects at its path, for its refusals.
_EXPECTED = "the calibration.json that `contactcal calibrate` wrote"


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
        raise NoSuchPhaseError(
            f"no {name} pass: the record has {', '.join(data['phases'])}; give phase= one of them"
        )
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
    if "resolves" in res and res["resolves"] is None and not allow_unresolved:
        why = str(res.get("reason") or "not assessed").removeprefix("not assessed: ")
        warnings.warn(
            f"whether the {name} curve tells pressures apart was not assessed: {why} (pass "
            "allow_unresolved=True to read it without this warning)",
            UnassessedCurveWarning,
            stacklevel=4,
        )
    m, b = ph.get("parametric"), ph.get("band")
    model = None if m is None else Saturating(m["p0_kpa"], m["k_kpa"], m["a_max"])
    band = None
    if b is not None:
        band = Band(b["pressure_kpa"], b["lo"], b["hi"], b["level"], b["n_resamples"], b["seed"])
    curve = _curve(
        ph["fit"], ph["onset_kpa"], data["area_unit"], ph["inverse"], model=model, band=band
    )
    return _check_contact(curve, name)


def _check_contact(curve: Curve, name: str) -> Curve:
    """``curve``, or :class:`NoContactCurveError` when it has no contact (no inverse)."""
    if not curve.has_contact:
        raise NoContactCurveError(
            f"the {name} curve has no contact in any step, so it cannot be inverted (the record "
            "holds no inverse); recalibrate with steps up into contact"
        )
    return curve


class UnresolvedCurveError(ValueError):
    """The record says the curve does not resolve pressures (``phases.*.resolution``)."""


class NoContactCurveError(ValueError):
    """The curve asked for has no contact (no onset, no inverse): nothing to invert."""


class UnassessedCurveWarning(UserWarning):
    """The record could not assess whether the curve tells pressures apart (too few steps)."""


class CalibrationNotFoundError(FileNotFoundError, ValueError):
    """No file at the path given: a :class:`FileNotFoundError` for a controller that catches
    that, and a :class:`ValueError` as every other unreadable record."""

    def __str__(self) -> str:
        return str(self.strerror)


class NoSuchPhaseError(ValueError):
    """A readable record without the pass asked for (``phase=``): the message names the passes
    it holds."""


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
            warned); by default that is an error, not a silently flat curve. A curve whose
            resolution the record could not assess (fewer than two steps in contact above the
            onset, or no cross-validated error: few steps, as in a short unloading pass) is
            read with an :class:`UnassessedCurveWarning` unless this is True.
        area_unit: the unit the caller's areas are in (``"mm²"``, also written ``"mm2"``, or
            ``"px"``): a record in
            another unit is refused (a session calibrated without a pixel scale holds px, and
            an area in mm² looked up in it would be wrong by the scale squared, silently).
            None: not checked (``Curve.area_unit`` says which).

    Raises:
        UnresolvedCurveError: the curve does not resolve pressures (and not allowed).
        NoContactCurveError: the curve has no contact in any step (it cannot be inverted;
            ``calibrate`` refuses to write such a record for the pass it inverts).
        NoSuchPhaseError: the record holds no ``phase`` pass (e.g. a loading-only session).
        CalibrationNotFoundError: no file at ``path`` (a FileNotFoundError and a ValueError).
        ValueError: a folder, not a regular file (a device or pipe: refused unread), an
            unreadable file, not a contactcal calibration, an unknown
            ``area_unit``, or another unit than ``area_unit``.
    """
    unit = _check_unit(area_unit)
    curve = _read_curve(path, phase, allow_unresolved)
    if unit is not None and curve.area_unit != unit:
        fix = (
            "a session calibrated without a pixel scale is in px: put a rig.json beside its "
            "manifest, or give --mm-per-px or --rig, and calibrate it again"
            if unit == MM2
            else f"give area_unit={MM2!r} and areas in mm², or leave area_unit out"
        )
        raise ValueError(f"{path}: its areas are in {curve.area_unit}, expected {unit} ({fix})")
    return curve


def _check_unit(area_unit: str | None) -> str | None:
    """``area_unit`` as a curve states it (``"mm2"``, the ASCII spelling, is ``"mm²"``).

    Raises:
        ValueError: any other unit.
    """
    if area_unit is None or area_unit in (MM2, PX):
        return area_unit
    if area_unit == "mm2":
        return MM2
    raise ValueError(f"area_unit {area_unit!r}: expected {MM2!r} (or 'mm2'), {PX!r} or None")


def _not_a_record(path: str | os.PathLike[str], why: Exception) -> ValueError:
    """The refusal of the record file ``path``, which ``why`` shows is no contactcal record."""
    return ValueError(f"{path}: not a readable contactcal calibration ({why})")


def _read_record(path: str | os.PathLike[str]) -> Any:
    """The JSON value in the record file ``path``, read as every input is (a folder, device or
    pipe refused unread: :func:`~contactcal.infer.files.regular.read_input_json`).

    Raises:
        CalibrationNotFoundError: no file at ``path``.
        ValueError: a folder, not a regular file, unreadable, not UTF-8 or not JSON; one line
            naming ``path``.
    """
    try:
        return read_input_json(path, _EXPECTED, ValueError)
    except FileNotFoundError:
        raise CalibrationNotFoundError(
            errno.ENOENT, f"{path}: no such file; expected {_EXPECTED}"
        ) from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the calibration ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _not_a_record(path, exc) from exc


def _read_curve(path: str | os.PathLike[str], phase: str | None, allow_unresolved: bool) -> Curve:
    """:func:`load_curve` without the unit check."""
    data = _read_record(path)
    try:
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
            raise NoSuchPhaseError(
                f"format_version {version} holds the loading pass only, not {phase}"
            )
        curve = _curve(data["fit"], data["onset_kpa"], data["area_unit"], data.get("inverse"))
        return _check_contact(curve, LOADING)
    except (UnresolvedCurveError, NoContactCurveError, NoSuchPhaseError) as exc:
        raise type(exc)(f"{path}: {exc}") from exc
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise _not_a_record(path, exc) from exc

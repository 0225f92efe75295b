"""Fitting a whole session: per phase its steps, the chosen curve and its band; hysteresis."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from contactcal.infer.calibration.bootstrap import bootstrap_band
from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.fit import CurveConfig
from contactcal.infer.calibration.hysteresis import hysteresis
from contactcal.infer.calibration.phases import LOADING, PHASES, UNLOADING
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.select import MIN_CV_STEPS, choose_model, fit_model
from contactcal.infer.calibration.steps import Step, group_steps

#: Fraction of a curve's largest fitted area its rise over the contact steps must exceed to
#: resolve pressures: below it the whole calibrated range spans a few per cent of the area, the
#: order of one frame's measurement scatter (e.g. the example session's band, about ±2.5 %).
MIN_RISE_FRACTION = 0.05


@dataclass(frozen=True, eq=False)
class PhaseFit:
    """One pass of a session: its steps, its curve (with band) and how the model was chosen."""

    phase: str
    steps: list[Step]
    curve: Curve
    selection: dict[str, Any]  # select.choose_model's record

    def resolution(self) -> dict[str, Any] | None:
        """Whether the curve can tell pressures apart: its rise over the steps in contact above
        its onset against a floor and its own cross-validated error (None without contact).

        The step at the onset is left out (the fit is 0 there by construction, so a constant
        "contact" from the lowest step would seem to rise). A curve that fails (e.g. the
        classical routine reporting the membrane's glow as a constant "contact" from 0 kPa, or
        a frozen camera giving the same area at every pressure) has an inverse that cannot tell
        pressures apart, whatever its band says. A perfect fit of a flat curve has a zero error,
        so the rise must also exceed :data:`MIN_RISE_FRACTION` of the largest fitted area.

        Returns:
            ``rise`` (curve unit, from the first to the last such step), ``cv_rmse`` (the
            chosen model's, curve unit, or None), ``floor`` (curve unit), ``resolves``: the
            rise exceeds both (False: it does not; None, "not assessed": fewer than two such
            steps, or no cross-validated error with fewer than :data:`MIN_CV_STEPS` contact
            steps) and ``reason``: why not, said of the curve ("rises ... no more than ...",
            "not assessed: ..."; None when it resolves).
        """
        c = self.curve
        if not c.has_contact or c.onset_kpa is None:
            return None
        above = [s.pressure_kpa for s in self.steps if s.contact and s.pressure_kpa > c.onset_kpa]
        cv = self.selection["cv_rmse"].get(self.selection["model"])
        rise = float(c.area_at(max(above)) - c.area_at(min(above))) if above else 0.0
        floor = MIN_RISE_FRACTION * float(c.area_range()[1])
        rises = (
            f"rises {rise:.3g} {c.area_unit} from its first to its last step in contact, no more "
            "than "
        )
        more = "; record more steps above the onset"
        resolves: bool | None = None
        if len(above) < 2:
            reason = f"not assessed: {len(above)} step(s) in contact above the onset" + more
        elif rise <= floor:
            resolves = False
            reason = rises + (
                f"{MIN_RISE_FRACTION:.0%} of its largest area ({floor:.3g} of "
                f"{float(c.area_range()[1]):.4g} {c.area_unit})"
            )
        elif cv is None:
            reason = (
                "not assessed: no cross-validated error to compare its rise with (fewer than "
                f"{MIN_CV_STEPS} steps in contact, or a leave-one-out refit failed)" + more
            )
        elif rise <= cv:
            resolves = False
            reason = rises + f"its cross-validated error ({cv:.3g})"
        else:
            resolves, reason = True, None
        return {"rise": rise, "cv_rmse": cv, "floor": floor, "resolves": resolves, "reason": reason}


@dataclass(frozen=True, eq=False)
class SessionFit:
    """A fitted session."""

    phases: dict[str, PhaseFit]  # loading, and unloading when recorded
    inverse_phase: str  # the phase whose curve is inverted for the controller
    phase_source: str  # how the phases were determined (phases.FROM_COLUMN, ...)
    hysteresis: dict[str, Any] | None  # hysteresis.hysteresis, None without an unloading pass

    @property
    def curve(self) -> Curve:
        """The curve used for the inverse."""
        return self.phases[self.inverse_phase].curve


def fit_phase(steps: list[Step], cfg: CurveConfig, unit: str) -> PhaseFit:
    """Choose and fit the curve of one phase's steps, with its bootstrap band."""
    p = np.asarray([s.pressure_kpa for s in steps], dtype=np.float64)
    a = np.asarray([s.median for s in steps], dtype=np.float64)
    c = np.asarray([s.contact for s in steps], dtype=bool)
    curve, selection = choose_model(p, a, c, cfg, unit)
    if curve.has_contact:
        kind = selection["model"]

        def refit(pp: np.ndarray, aa: np.ndarray, cc: np.ndarray) -> Curve | None:
            return fit_model(kind, pp, aa, cc, cfg, unit)

        band = bootstrap_band(steps, curve, refit, cfg.n_bootstrap, cfg.seed)
        curve = replace(curve, band=band)
    return PhaseFit(steps[0].phase, steps, curve, selection)


def fit_session(
    points: Sequence[CalibrationPoint],
    unit: str,
    config: CurveConfig | None = None,
    inverse_phase: str = LOADING,
    phase_source: str = "as given with the points",
) -> SessionFit:
    """Group the points into steps, fit each phase, compare the phases.

    Args:
        points: per-frame measurements (with phase and pressure), any order.
        unit: the curve's area unit.
        config: fit settings (None: defaults).
        inverse_phase: ``"loading"`` (default) or ``"unloading"``: the curve to invert.
        phase_source: how the phases were determined, recorded.

    Raises:
        ValueError: an unknown ``inverse_phase`` or one the session does not have, or points
            without an area in ``unit``.
    """
    cfg = config or CurveConfig()
    if inverse_phase not in PHASES:
        raise ValueError(f"inverse phase {inverse_phase!r}: expected one of {', '.join(PHASES)}")
    grouped = group_steps(points, unit)
    if inverse_phase not in grouped:
        raise ValueError(
            f"--inverse-phase {inverse_phase}: the session has no {inverse_phase} pass (it has "
            f"{', '.join(grouped)}); use --inverse-phase {LOADING}"
        )
    phases = {ph: fit_phase(steps, cfg, unit) for ph, steps in grouped.items()}
    hyst = None
    if UNLOADING in phases and LOADING in phases:
        up, down = phases[LOADING], phases[UNLOADING]
        hyst = hysteresis((up.steps, up.curve), (down.steps, down.curve))
    return SessionFit(phases, inverse_phase, phase_source, hyst)

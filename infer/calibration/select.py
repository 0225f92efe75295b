"""Choosing a session's curve model by cross-validation: isotonic or parametric.

Leave-one-step-out on the contact steps: each contact step in turn is left out, both models are
refitted on the other steps and predict its median area; the model with the lower root mean
square prediction error (the curve's unit) is used. The isotonic fit is kept when the parametric
one cannot be cross-validated (fewer than 4 contact steps) or fails to fit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.fit import CurveConfig, fit_monotone, fit_parametric

ISOTONIC = "isotonic"
PARAMETRIC = "parametric"
#: Contact steps needed to cross-validate the parametric form (3 parameters, one left out).
MIN_CV_STEPS = 4


def fit_model(
    kind: str, p: np.ndarray, a: np.ndarray, c: np.ndarray, cfg: CurveConfig, unit: str
) -> Curve | None:
    """The curve of model ``kind`` (``"isotonic"`` or ``"parametric"``); None if it cannot fit."""
    if kind == ISOTONIC:
        return fit_monotone(p, a, c, cfg, area_unit=unit)
    return fit_parametric(p, a, c, cfg, area_unit=unit)


def cv_rmse(
    kind: str, p: np.ndarray, a: np.ndarray, c: np.ndarray, cfg: CurveConfig, unit: str
) -> float | None:
    """Leave-one-step-out RMS prediction error of ``kind`` on the contact steps, or None.

    Args:
        kind: ``"isotonic"`` or ``"parametric"``.
        p: ``(S,)`` step pressures, kPa, ascending; a: ``(S,)`` step medians; c: ``(S,)`` bool.
        cfg: fit settings; unit: the area unit.

    Returns:
        The RMS error (unit), or None with fewer than :data:`MIN_CV_STEPS` contact steps or a
        refit that fails.
    """
    full = fit_monotone(p, a, c, cfg, area_unit=unit)
    held = [j for j in range(p.size) if c[j] and full.area_at(p[j]) > 0]
    if len(held) < MIN_CV_STEPS:
        return None
    errors = []
    for j in held:
        keep = np.arange(p.size) != j
        curve = fit_model(kind, p[keep], a[keep], c[keep], cfg, unit)
        if curve is None or not curve.has_contact:
            return None
        errors.append(curve.area_at(float(p[j])) - float(a[j]))
    return float(math.sqrt(np.mean(np.square(errors))))


def choose_model(
    p: np.ndarray, a: np.ndarray, c: np.ndarray, cfg: CurveConfig, unit: str
) -> tuple[Curve, dict[str, Any]]:
    """The session's curve and the record of the choice.

    ``cfg.curve_model`` ``"auto"`` chooses by `cv_rmse` (parametric only when strictly lower);
    ``"isotonic"`` / ``"parametric"`` force a model (parametric falls back to isotonic, with the
    reason, when it cannot fit).

    Returns:
        ``(curve, {"model", "requested", "cv_rmse": {"isotonic", "parametric"}, "reason"})``.
    """
    cv = {kind: cv_rmse(kind, p, a, c, cfg, unit) for kind in (ISOTONIC, PARAMETRIC)}
    requested = cfg.curve_model
    kind, reason = ISOTONIC, "requested"
    if requested == "auto":
        iso, par = cv[ISOTONIC], cv[PARAMETRIC]
        if iso is None or par is None:
            reason = f"fewer than {MIN_CV_STEPS} contact steps or no parametric fit: isotonic"
        elif par < iso:
            kind, reason = PARAMETRIC, "lower cross-validated error"
        else:
            reason = "lower or equal cross-validated error"
    elif requested == PARAMETRIC:
        kind = PARAMETRIC
    curve = fit_model(kind, p, a, c, cfg, unit)
    if curve is None:
        kind, reason = ISOTONIC, "the parametric form could not be fitted (< 3 contact steps)"
        curve = fit_monotone(p, a, c, cfg, area_unit=unit)
    return curve, {"model": kind, "requested": requested, "cv_rmse": cv, "reason": reason}

"""Fitting a session's points: robust monotone fit and contact onset (pure numpy).

Pipeline (`fit_monotone`): sort by pressure -> find the contact range from the per-frame contact
flags (`estimate_onset` rule) -> isolated outliers among the contact frames' areas replaced by a
running median (`despike`) -> isotonic (PAVA) fit -> area forced to 0 below the onset ->
:class:`~contactcal.infer.calibration.curve.Curve`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from contactcal.infer.calibration.curve import MM2, Curve
from contactcal.infer.calibration.isotonic import despike, isotonic_fit
from contactcal.infer.calibration.onset import (
    FITTED_BELOW_LOWEST_RULE,
    FITTED_RULE,
    MIDPOINT_BELOW_RULE,
    onset_bracket,
    onset_index,
    refine_onset,
)
from contactcal.infer.calibration.parametric import fit_saturating
from contactcal.infer.calibration.points import prepare_points

#: Curve models: the isotonic fit, the saturating parametric one, or chosen per session by
#: cross-validation (:mod:`contactcal.infer.calibration.select`).
CURVE_MODELS = ("auto", "isotonic", "parametric")
#: Fraction of the onset's bracket within which a parametric onset counts as pinned to the
#: bracket's low end (the grid search's final cell is ~4e-6 of the bracket).
PINNED_FRACTION = 1e-5


@dataclass(frozen=True)
class CurveConfig:
    """Settings of the area-vs-pressure fit."""

    # frames, odd >= 1: running-median width before PAVA. 3 removes isolated outliers; 5 also
    # pairs of them, but flattens genuine knees sharper than the window. 1 disables.
    median_window: int = 3
    # area unit (mm² or px) per inverse-table row; None = a 1-2-5 step giving <= table_max_rows
    # rows. Finer only makes the table longer: the controller interpolates linearly anyway.
    table_step: float | None = None
    # rows: size target of the automatic inverse-table step (readability vs resolution).
    table_max_rows: int = 100
    # "auto" picks the model with the lower leave-one-step-out error; "isotonic" follows any
    # monotone shape, "parametric" (onset + saturation) is smooth but assumes that shape.
    curve_model: str = "auto"
    # bootstrap resamples of the band: its 5th/95th percentiles wobble by ~1/sqrt(n) of the
    # spread (200: edges stable to ~10 %, ~0.5 s a phase with parametric refits; 50 for a look).
    n_bootstrap: int = 200
    # seed of the bootstrap's numpy Generator: the same seed gives the same band.
    seed: int = 0

    def __post_init__(self) -> None:
        if self.curve_model not in CURVE_MODELS:
            raise ValueError(
                f"curve_model: expected one of {CURVE_MODELS}, got {self.curve_model!r}"
            )
        if self.n_bootstrap < 20:
            raise ValueError(f"n_bootstrap: expected >= 20 (a 90 % band), got {self.n_bootstrap}")
        if self.median_window < 1 or self.median_window % 2 == 0:
            raise ValueError(
                f"median_window: expected an odd integer >= 1, got {self.median_window}"
            )
        if self.table_step is not None and not (
            math.isfinite(self.table_step) and self.table_step > 0
        ):
            raise ValueError(
                f"table_step: expected a finite value > 0 or None, got {self.table_step}"
            )
        if self.table_max_rows < 2:
            raise ValueError(f"table_max_rows: expected >= 2, got {self.table_max_rows}")


def estimate_onset(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    contact: ArrayLike | None = None,
    config: CurveConfig | None = None,
) -> float | None:
    """Contact onset pressure (kPa), or None when the frames show no contact.

    Rule: the frames sorted by pressure are split at index ``s`` minimising (contact frames
    below ``s``) + (no-contact frames at or above ``s``); ties go to the highest ``s`` below
    ``N``. So frame ``s`` is in contact and frame ``s - 1`` is not; every run of frames
    starting at ``s`` and ending below the top has a strict majority of contacts (at least
    half over the whole range), so an isolated miss inside the contact range does not reset
    it; every run ending at ``s - 1`` has at least as many misses as contacts, so an isolated
    false contact at low pressure does not count (nor does a lone contact followed by a miss
    just below the contact range). ``s == N`` (no contact range) gives None, also when the
    only contact flags are such false positives.

    Refinement: the line through the fitted areas of the first two contact frames of the
    range is extrapolated to zero area. The onset always lies in the bracket ``(pressure at
    s - 1, pressure at s]`` (never at or below a pressure whose frame shows no contact): an
    extrapolation at or below its low end (a concave start, e.g. coarse steps on a saturating
    curve), or no usable slope, gives the bracket's midpoint. With no frame below ``s`` the
    onset is the lowest pressure (not calibrated below it). On a convex start (area growing
    faster than linearly) the extrapolation is biased towards the first contact frame: for
    ``area ∝ (p - p0)²`` with ``p0`` on a frame it gives ``p0 + 2/3`` of a step.

    Args:
        pressures_kpa: ``(N,)`` frame pressures, kPa, any order, distinct.
        areas: ``(N,)`` contact areas >= 0 (mm² or px).
        contact: ``(N,)`` bool per frame; None means ``areas > 0``.
        config: fit settings (the refinement uses the fitted curve).
    """
    return fit_monotone(pressures_kpa, areas, contact, config).onset_kpa


def fit_monotone(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    contact: ArrayLike | None = None,
    config: CurveConfig | None = None,
    *,
    area_unit: str = MM2,
) -> Curve:
    """Robust non-decreasing fit of contact area vs pressure.

    Why a running median before PAVA: PAVA alone averages an outlier spike with the points
    after it, lifting those neighbours (and a false dip drags earlier points down). The
    median of three consecutive points is the identity on monotone data, so a genuine curve
    is not biased (but for `despike`'s end rule on the last step), while an isolated spike or
    dip is replaced by a neighbour first (`despike`: worst point first, so the spike's
    neighbours keep their values); PAVA then removes the remaining small non-monotone noise in
    the least-squares sense.

    Steps: sort by pressure; contact range by the `estimate_onset` rule; the contact frames in
    that range are despiked (``config.median_window``) and fitted with PAVA; misses inside the
    range are interpolated from the fit; areas below the onset are 0.

    Args:
        pressures_kpa: ``(N,)`` frame pressures, kPa, any order, distinct, N >= 2.
        areas: ``(N,)`` measured areas >= 0, same order (mm² or px).
        contact: ``(N,)`` bool per frame, same order; None means ``areas > 0``.
        config: fit settings; None uses the defaults.
        area_unit: unit of ``areas``, stored in the curve (``"mm²"`` or ``"px"``).

    Returns:
        The `Curve` (flat zero with ``onset_kpa=None`` if no frame is in contact: the caller
        decides whether that is an error).

    Raises:
        ValueError: mismatched lengths, fewer than 2 frames, duplicate or non-finite
            pressures, NaN/inf/negative areas.
    """
    cfg = config or CurveConfig()
    p, a, c = prepare_points(pressures_kpa, areas, contact)
    fit = np.zeros_like(a)
    s = onset_index(c)
    if s is None:
        return Curve(p, fit, None, area_unit, cfg.table_step, cfg.table_max_rows)
    idx = np.flatnonzero(c[s:]) + s
    smooth = despike(a[idx], cfg.median_window)
    iso = isotonic_fit(p[idx], smooth)
    fit[s:] = np.interp(p[s:], p[idx], iso)
    onset, rule = refine_onset(p, fit, idx)
    return Curve(
        p,
        fit,
        onset,
        area_unit,
        cfg.table_step,
        cfg.table_max_rows,
        onset_bracket_kpa=onset_bracket(p, s),
        onset_rule=rule,
    )


def fit_parametric(
    pressures_kpa: ArrayLike,
    areas: ArrayLike,
    contact: ArrayLike | None = None,
    config: CurveConfig | None = None,
    *,
    area_unit: str = MM2,
) -> Curve | None:
    """Least-squares saturating fit (:mod:`.parametric`) of the contact range's points.

    The contact range is found as in `fit_monotone`; its contact points are fitted with the
    onset bounded to ``[pressure at s - 1, pressure at s]`` (``s``: first frame of the range;
    without a frame below it, one step lower, >= 0 kPa). A fitted onset pinned to the low
    bound of a frame without contact (within :data:`PINNED_FRACTION` of the bracket: the
    least-squares form wants an earlier onset than that frame allows) is replaced, as in
    `fit_monotone`, by the bracket's midpoint, with ``K`` and ``A_max`` refitted for it.
    Arguments as `fit_monotone`.

    Returns:
        The `Curve` with its ``model``, or None with fewer than 3 contact points in the range.
    """
    cfg = config or CurveConfig()
    p, a, c = prepare_points(pressures_kpa, areas, contact)
    s = onset_index(c)
    if s is None:
        return None
    idx = np.flatnonzero(c[s:]) + s
    # onset range: between the last frame without contact and the first with; with none
    # below, one step below the first frame but not below 0 kPa (no suction onset).
    lo = float(p[s - 1]) if s > 0 else max(0.0, float(2 * p[0] - p[1]))
    hi = float(p[s])
    model = fit_saturating(p[idx], a[idx], (lo, hi))
    rule = FITTED_BELOW_LOWEST_RULE if s == 0 else FITTED_RULE
    if model is not None and s > 0 and model.p0_kpa - lo <= PINNED_FRACTION * (hi - lo):
        mid = 0.5 * (lo + hi)
        model, rule = fit_saturating(p[idx], a[idx], (mid, mid)), MIDPOINT_BELOW_RULE
    if model is None:
        return None
    return Curve(
        p,
        model.area(p),
        model.p0_kpa,
        area_unit,
        cfg.table_step,
        cfg.table_max_rows,
        model=model,
        onset_bracket_kpa=onset_bracket(p, s),
        onset_rule=rule,
    )

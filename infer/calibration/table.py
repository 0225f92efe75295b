"""The text table ``contactcal calibrate`` prints: one row per pressure step, then the fits."""

from __future__ import annotations

from typing import Any

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.onset import MIDPOINT_RULES
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.calibration.session import PhaseFit, SessionFit


def _rows(results: list[CalibrationPoint], fit: SessionFit) -> list[list[str]]:
    notes: dict[tuple[str, float], list[str]] = {}  # a step's notes' parts, each once
    for r in results:
        said = notes.setdefault((r.phase, r.pressure_kpa), [])
        said += [part for part in r.note.split("; ") if part and part not in said]
    rows = []
    for ph in fit.phases.values():
        band = ph.curve.band
        for s in ph.steps:
            sp = s.spread()
            lo, hi = band.at(s.pressure_kpa) if band is not None else (None, None)
            rows.append(
                [
                    s.phase,
                    f"{s.pressure_kpa:.2f}",
                    str(s.n),
                    f"{s.median:.1f}",
                    f"{sp['min']:.1f}-{sp['max']:.1f}" if s.n > 1 else "",
                    f"{sp['q75'] - sp['q25']:.1f}" if s.n > 1 else "",
                    f"{ph.curve.area_at(s.pressure_kpa):.1f}",
                    "" if lo is None else f"{lo:.1f}-{hi:.1f}",
                    "yes" if s.contact else "no",
                    "; ".join(notes.get((s.phase, s.pressure_kpa), [])),
                ]
            )
    return rows


def _onset(name: str, curve: Curve) -> tuple[str, list[str]]:
    """The onset as the summary line shows it (with its bracket), and its warnings."""
    onset, bracket = curve.onset_kpa, curve.onset_bracket_kpa
    if onset is None:
        return "no contact", []
    at = f"onset {onset:.2f} kPa"
    if bracket is None:
        return at, []
    lo, hi = bracket
    if lo is None:
        return f"{at}; in contact from the lowest pressure, {hi:g} kPa: not calibrated below", []
    at += f", between {lo:g} kPa (no contact) and {hi:g} kPa (contact)"
    if curve.onset_rule not in MIDPOINT_RULES:
        return at, []
    return at, [
        f"warning: the {name} onset is the {curve.onset_rule}; it is known only to lie in "
        f"({lo:g}, {hi:g}] kPa, and the inverse's band spans that bracket for areas below the "
        f"one at {hi:g} kPa (record finer steps between {lo:g} and {hi:g} kPa to place it)"
    ]


def _resolution(name: str, ph: PhaseFit) -> list[str]:
    """The warning line of a curve that does not resolve pressures or was not assessed."""
    res = ph.resolution()
    if res is None or res["resolves"] is True:
        return []
    if res["resolves"] is False:
        return [
            f"warning: the {name} curve {res['reason']}: its inverse cannot tell pressures "
            "apart (do the areas grow with pressure? check the overlays)"
        ]
    return [f"warning: whether the {name} curve resolves pressure is {res['reason']}"]


def _summary(fit: SessionFit) -> list[str]:
    """One line per phase (model, CV errors, onset and its bracket) with its warnings, and the
    hysteresis."""
    unit = fit.curve.area_unit
    lines = [f"phases: {fit.phase_source}; inverse: {fit.inverse_phase} curve"]
    for name, ph in fit.phases.items():
        cv = ph.selection["cv_rmse"]
        shown = ", ".join(f"{k} {'–' if v is None else f'{v:.2f}'}" for k, v in cv.items())
        at, warnings = _onset(name, ph.curve)
        lines.append(f"{name}: {ph.selection['model']} fit ({at}; CV RMSE {unit}: {shown})")
        lines += warnings + _resolution(name, ph)
    h = fit.hysteresis
    if h is not None and h["max_abs_difference"] is not None:
        mean = round(h["mean_difference"], 1) + 0.0  # no "-0.0"
        lines.append(
            f"hysteresis (unloading - loading): mean {mean:.1f} {unit}, max |.| "
            f"{h['max_abs_difference']:.1f} {unit} at {h['max_abs_at_kpa']:g} kPa, over "
            f"{len(h['pressures_kpa'])} common pressure(s)"
        )
    elif h is not None:
        lines.append(
            "hysteresis: not measured (no unloading step within "
            f"{h['matched_within_kpa']:g} kPa of a loading step)"
        )
    return lines + _onset_shift(h)


def _onset_shift(h: dict[str, Any] | None) -> list[str]:
    """The line of the onset shift between the passes, with the range the steps allow."""
    if h is None or h["onset_shift_kpa"] is None:
        return []
    line = f"onset shift (unloading - loading): {h['onset_shift_kpa']:+.2f} kPa"
    rng = h["onset_shift_range_kpa"]
    if rng is None:
        return [line + " (a pass is in contact from its lowest pressure: range unknown)"]
    return [line + f", known to lie between {rng[0]:+g} and {rng[1]:+g} kPa from the steps"]


def format_table(
    results: list[CalibrationPoint], fit: SessionFit, device_id: str | None = None
) -> str:
    """Aligned text table of the steps: phase, pressure (kPa), frames, median area, spread
    (min-max and interquartile range, with repeated frames), fit and its 90 % band (curve
    unit), contact, notes; then each phase's model, CV errors and onset, and the hysteresis.
    With ``device_id``, a first line names the calibrated display."""
    u = fit.curve.area_unit
    head = ["phase", "pressure (kPa)", "n", f"median ({u})", "min-max", "IQR", f"fit ({u})"]
    head += ["90 % band", "contact", "note"]
    rows = _rows(results, fit)
    widths = [max([len(h), *(len(row[i]) for row in rows)]) for i, h in enumerate(head)]

    def line(cells: list[str]) -> str:
        out = [
            c.rjust(w) if 0 < i < 8 else c.ljust(w)
            for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        ]
        return "  ".join(out).rstrip()

    body = [line(head), line(["-" * w for w in widths]), *(line(r) for r in rows)]
    device = [] if device_id is None else [f"device: {device_id}"]
    return "\n".join([*device, *body, "", *_summary(fit)])

"""The text table ``contactcal calibrate`` prints: pressure, area, fit, contact, note."""

from __future__ import annotations

from contactcal.infer.calibration.curve import Curve
from contactcal.infer.calibration.points import CalibrationPoint
from contactcal.infer.files.jsonable import finite_or_none


def format_table(results: list[CalibrationPoint], curve: Curve) -> str:
    """Aligned text table: pressure (kPa), area (mm² if every frame has it, else px), fit
    (curve unit), contact yes/no, and a note column when any frame has a note."""
    ordered = sorted(results, key=lambda r: r.pressure_kpa)
    use_mm2 = bool(ordered) and all(finite_or_none(r.area_mm2) is not None for r in ordered)
    head = [
        "pressure (kPa)",
        "area (mm²)" if use_mm2 else "area (px)",
        f"fit ({curve.area_unit})",
        "contact",
    ]
    notes = any(r.note for r in ordered)
    if notes:
        head.append("note")
    rows = []
    for r in ordered:
        area = r.area_mm2 if use_mm2 else r.area_px
        row = [
            f"{r.pressure_kpa:.2f}",
            f"{float(area):.1f}",
            f"{curve.area_at(r.pressure_kpa):.1f}",
            "yes" if r.contact else "no",
        ]
        if notes:
            row.append(r.note)
        rows.append(row)
    widths = [max([len(h), *(len(row[i]) for row in rows)]) for i, h in enumerate(head)]

    def line(cells: list[str]) -> str:
        out = [
            c.rjust(w) if i < 3 else c.ljust(w)
            for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        ]
        return "  ".join(out).rstrip()

    return "\n".join([line(head), line(["-" * w for w in widths]), *(line(r) for r in rows)])

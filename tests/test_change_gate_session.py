"""The change gate in a session: ``calibrate`` names the gate when it removed every contact,
notes gated frames above a contact of their pass, and records ``--no-change-gate``; the flag is
refused where no U-Net would run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_change_gate import _gated


def test_calibrate_says_when_the_gate_removed_every_contact(tmp_path: Path) -> None:
    from contactcal.infer.calibration.calibrate import calibrate_session
    from contactcal.infer.errors import RunError
    from contactcal.infer.pipeline.options import MeasureOptions

    manifest = Path(__file__).resolve().parents[1] / "examples" / "session" / "manifest.csv"
    strict = _gated(tmp_path / "strict.onnx", 100.0)
    with pytest.raises(RunError, match=r"change gate called \d+ of them.*--no-change-gate"):
        calibrate_session(manifest, tmp_path / "a", "unet", MeasureOptions(model=strict))
    assert not (tmp_path / "a").exists()
    off = MeasureOptions(model=strict, change_gate=False)
    rep = calibrate_session(manifest, tmp_path / "b", "unet", off)
    assert any(m.result.contact for m in rep.measured)
    record = json.loads((tmp_path / "b" / "calibration.json").read_text())
    assert record["method_config"]["change_gate"] == "off (--no-change-gate)"


def test_cli_refuses_a_gate_flag_it_would_ignore_and_records_it_otherwise(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from contactcal.infer.cli import main

    example = Path(__file__).resolve().parents[1] / "examples" / "session"
    frames = [str(example / "p00.0kpa.jpg"), str(example / "p08.0kpa.jpg")]
    out = tmp_path / "r.json"
    code = main(
        ["measure", "--method", "classical", "--no-change-gate", "--out", str(out), *frames]
    )
    err = capsys.readouterr().err
    assert code == 2 and "--no-change-gate applies to the U-Net only" in err and not out.exists()
    cal = tmp_path / "cal"
    manifest = str(example / "manifest.csv")
    assert main(["calibrate", manifest, "--no-change-gate", "--out", str(cal)]) == 0
    record = json.loads((cal / "calibration.json").read_text())
    assert record["method_config"]["change_gate"] == "off (--no-change-gate)"
    ev = tmp_path / "ev"
    labels = str(example / "masks")
    assert (
        main(["evaluate", manifest, "--labels", labels, "--no-change-gate", "--out", str(ev)]) == 0
    )
    assert (
        json.loads((ev / "evaluation.json").read_text())["change_gate"] == "off (--no-change-gate)"
    )


def test_gated_frames_above_a_contact_of_their_pass_are_flagged() -> None:
    from contactcal.infer.calibration.gate_check import flag_gated_above_contact
    from contactcal.infer.calibration.points import CalibrationPoint
    from contactcal.infer.methods.base import UNCHANGED_NOTE

    gated = f"{UNCHANGED_NOTE} (change 0.050 < 0.061)"

    def pt(p: float, contact: bool, note: str = "", phase: str = "loading") -> CalibrationPoint:
        return CalibrationPoint(f"p{p}", p, contact, 100.0 * contact, None, note, phase)

    points = [
        pt(2.0, False, gated),  # below the first contact: the gate is plausible there
        pt(4.0, True),
        pt(6.0, False, gated),  # above a contact of its pass: flagged
        pt(8.0, False, "no contact"),  # not the gate's doing
        pt(3.0, False, gated, "unloading"),  # its pass has no contact
    ]
    out, n = flag_gated_above_contact(points)
    assert n == 1 and [r.file for r in out] == [r.file for r in points]
    assert out[2].note.startswith(gated + "; above 4 kPa, which is in contact")
    assert "--no-change-gate" in out[2].note and not out[2].contact and out[2].area_px == 0.0
    assert [out[i] for i in (0, 1, 3, 4)] == [points[i] for i in (0, 1, 3, 4)]
    assert flag_gated_above_contact([]) == ([], 0)


def test_calibrate_records_gated_frames_above_contact(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from contactcal.infer.calibration import calibrate as calibrate_module
    from contactcal.infer.image.read import ImageFile
    from contactcal.infer.methods import registry
    from contactcal.infer.methods.base import UNCHANGED_NOTE, AreaResult, Started

    manifest = Path(__file__).resolve().parents[1] / "examples" / "session" / "manifest.csv"
    # 21 frames, 0-20 kPa: contact from 3 kPa, the gate removes the frame at 12 kPa.
    areas = [0.0, 0.0, 0.0, *(1e4 * (i + 1) for i in range(18))]

    class Scripted:
        """A stub U-Net: contact from 3 kPa, the frame at 12 kPa called unchanged by the gate."""

        name = "unet"
        NO_REFERENCE = "no reference"

        def start(
            self, files: list[Path], reference: ImageFile | None, bit_depth: int | None = None
        ):
            return Started(1, None if reference is None else reference.decode())

        def set_reference(self, reference: np.ndarray | None, reduction: int = 1) -> None:
            return None

        def measure(self, image: np.ndarray) -> AreaResult:
            i = 21 - len(areas)
            a = areas.pop(0)
            if i == 12:
                return AreaResult(False, 0.0, f"{UNCHANGED_NOTE} (change 0.05 < 0.06)", None)
            return AreaResult(a > 0, a, "" if a > 0 else "no contact", None, None, (a, a))

        def describe(self) -> dict[str, str]:
            return {"name": self.name}

    monkeypatch.setattr(registry, "make_method", lambda *a, **k: Scripted())
    rep = calibrate_module.calibrate_session(manifest, tmp_path / "cal", "unet")
    record = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert record["extra"]["gated_above_contact"] == 1
    assert "which is in contact" in rep.table and "--no-change-gate" in rep.table
    lost = record["extra"]["no_contact_above_contact"]
    assert [Path(f).name for f in lost] == ["p12.0kpa.jpg"]
    assert "warning: 1 frame(s) without contact above a pressure in contact of their pass " in (
        rep.table
    )


def test_a_blank_frame_in_the_sweep_is_warned(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A dark frame at 10 kPa (no ring, no contact) among contacts: the fit moves; it is said."""
    import shutil

    import cv2

    from contactcal.infer.cli import main

    session = tmp_path / "s"
    shutil.copytree(Path(__file__).resolve().parents[1] / "examples" / "session", session)
    cv2.imwrite(str(session / "p10.0kpa.jpg"), np.zeros((300, 400), np.uint8))
    assert main(["calibrate", str(session / "manifest.csv"), "--out", str(tmp_path / "c")]) == 0
    out = capsys.readouterr().out
    assert "warning: 1 frame(s) without contact above a pressure in contact" in out
    assert "(p10.0kpa.jpg)" in out


def test_a_session_starting_in_contact_is_said(tmp_path: Path) -> None:
    """A manifest starting at 5 kPa: its reference frame is compared with itself, so the gate
    removes its contact; the table and the record say so (the calibration still runs)."""
    from contactcal.infer.calibration.calibrate import calibrate_session

    example = Path(__file__).resolve().parents[1] / "examples" / "session"
    rows = [f"{example}/p{p:04.1f}kpa.jpg,{p}" for p in range(5, 21)]
    manifest = tmp_path / "from5.csv"
    manifest.write_text("file,pressure_kpa\n" + "\n".join(rows) + "\n")
    rep = calibrate_session(manifest, tmp_path / "cal", "unet")
    assert "warning: this is the session's reference frame, compared with itself" in rep.table
    record = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert record["extra"]["reference_gated_above_zero"] is True
    assert "record a 0 kPa frame first" in record["points"][0]["note"]
    full = calibrate_session(example / "manifest.csv", tmp_path / "full", "unet")
    assert "compared with itself" not in full.table  # 0 kPa reference: nothing to say


def test_a_reference_at_rest_is_not_flagged() -> None:
    """A video step's rest pressure is a noisy gauge's median (0.00x kPa): at rest, not flagged."""
    from contactcal.infer.calibration.gate_check import REST_KPA, flag_gated_reference
    from contactcal.infer.calibration.points import CalibrationPoint
    from contactcal.infer.methods.base import UNCHANGED_NOTE

    def ref(p: float) -> CalibrationPoint:
        return CalibrationPoint("f.png", p, False, 0.0, None, f"{UNCHANGED_NOTE} (change 0.000)")

    for p, flagged in ((0.0, False), (0.01, False), (REST_KPA, False), (1.0, True)):
        assert flag_gated_reference([ref(p)])[1] is flagged


@pytest.mark.parametrize("method", ["classical", "unet"])
def test_a_reference_above_rest_is_said_with_or_without_the_gate(
    tmp_path: Path, method: str
) -> None:
    """A session from 1 kPa whose reference has no contact (so nothing was gated): still a
    warning and extra.reference_above_rest_kpa, for either method (both compare with it)."""
    from contactcal.infer.calibration.calibrate import calibrate_session

    example = Path(__file__).resolve().parents[1] / "examples" / "session"
    rows = [f"{example}/p{p:04.1f}kpa.jpg,{p}" for p in range(1, 21)]
    manifest = tmp_path / "from1.csv"
    manifest.write_text("file,pressure_kpa\n" + "\n".join(rows) + "\n")
    rep = calibrate_session(manifest, tmp_path / "cal", method)
    assert "reference frame (its lowest loading frame, p01.0kpa.jpg) is at 1 kPa" in rep.table
    assert "compared with itself" not in rep.table
    record = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert record["extra"]["reference_above_rest_kpa"] == 1.0
    full = calibrate_session(example / "manifest.csv", tmp_path / "full", method)
    assert "not at rest" not in full.table
    assert (
        json.loads((tmp_path / "full" / "calibration.json").read_text())["extra"][
            "reference_above_rest_kpa"
        ]
        is None
    )

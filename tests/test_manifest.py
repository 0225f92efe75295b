"""Tests of contactcal.infer.manifest."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from contactcal.infer.calibration.phases import (
    FROM_COLUMN,
    FROM_ORDER,
    SINGLE_PASS,
    misplaced_rows,
)
from contactcal.infer.pipeline.manifest import Frame, ManifestError, read_manifest, read_session


def _session(tmp_path: Path, text: str, images: tuple[str, ...] = ("a.png", "b.png", "c.png")):
    for name in images:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(b"x")
    path = tmp_path / "manifest.csv"
    path.write_text(text, encoding="utf-8")
    return path


def _fails(path: Path, *needles: str) -> str:
    with pytest.raises(ManifestError) as info:
        read_manifest(path)
    msg = str(info.value)
    assert str(path) in msg
    for needle in needles:
        assert needle in msg, msg
    return msg


def test_sorted_and_resolved(tmp_path: Path) -> None:
    (tmp_path / "img").mkdir()
    path = _session(
        tmp_path,
        "file,pressure_kpa\nimg/c.png,4\nimg/a.png,0\n\nimg/b.png,2.5\n",
        ("img/a.png", "img/b.png", "img/c.png"),
    )
    frames = read_manifest(path)
    assert [f.pressure_kpa for f in frames] == [0.0, 2.5, 4.0]
    assert [f.row for f in frames] == [2, 3, 1]
    assert frames[0] == Frame(file=(tmp_path / "img" / "a.png").resolve(), pressure_kpa=0.0, row=2)
    assert all(f.file.is_absolute() and f.file.is_file() for f in frames)


def test_bom_whitespace_and_absolute_paths(tmp_path: Path) -> None:
    path = _session(tmp_path, "", ())
    (tmp_path / "a.png").write_bytes(b"x")
    other = tmp_path / "elsewhere"
    other.mkdir()
    (other / "b.png").write_bytes(b"x")
    path.write_text(f"\ufeff file , pressure_kpa \na.png, 0\n{other / 'b.png'},1\n", "utf-8")
    frames = read_manifest(path)
    assert [f.file for f in frames] == [(tmp_path / "a.png").resolve(), (other / "b.png").resolve()]


def test_columns_in_other_order(tmp_path: Path) -> None:
    path = _session(tmp_path, "pressure_kpa,file\n2,b.png\n0,a.png\n")
    assert [f.file.name for f in read_manifest(path)] == ["a.png", "b.png"]


def test_missing_manifest(tmp_path: Path) -> None:
    _fails(tmp_path / "nope.csv", "not found")


def test_manifest_is_a_folder(tmp_path: Path) -> None:
    _fails(tmp_path, "folder")


def test_empty_and_header_only(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "\n\n"), "empty", "file,pressure_kpa")
    _fails(_session(tmp_path, "file,pressure_kpa\n"), "no frames")


def test_missing_column(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "file\na.png\n"), "missing required column 'pressure_kpa'")


def test_extra_columns_are_kept(tmp_path: Path) -> None:
    path = _session(tmp_path, "file,pressure_kpa,timestamp\na.png,0,12:00\nb.png,1,12:01\n")
    frames = read_manifest(path)
    assert [f.extras for f in frames] == [(("timestamp", "12:00"),), (("timestamp", "12:01"),)]


def test_bad_columns(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "file;pressure_kpa\na.png;0\n"), "comma-separated")
    _fails(_session(tmp_path, "File,pressure_kpa\na.png,0\n"), "did you mean 'file'")
    _fails(_session(tmp_path, "file,pressure_kpa,PHASE\na.png,0,x\n"), "did you mean 'phase'")
    _fails(_session(tmp_path, "file,pressure_kpa,file\na.png,0,b.png\n"), "['file'] appear twice")
    _fails(_session(tmp_path, "file,pressure_kpa,\na.png,0,\n"), "column 3 has no name")
    # Two trailing separators (a spreadsheet's export): the same advice, not "appear twice".
    _fails(
        _session(tmp_path, "file,pressure_kpa,,\na.png,0,,\n"), "trailing separator (as a spread"
    )


def test_wrong_cell_count(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "file,pressure_kpa\na.png,0\nb.png,1,2\n"), "row 2", "got 3")


def test_empty_file_cell(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "file,pressure_kpa\na.png,0\n ,1\n"), "row 2", "empty 'file'")


@pytest.mark.parametrize(
    ("cell", "problem"),
    [
        ("abc", "not a number"),
        ("nan", "not finite"),
        ("inf", "not finite"),
        ("-1", "below -0.5 kPa"),
        ("-0.51", "a sign error or a bad zero"),
        ("", "not a number"),
        ("2 kPa", "not a number"),
        ("1e308", "above the plausible 100 kPa"),
        ("20000", "above the plausible 100 kPa"),
        ("200", "not mbar"),  # a 0-20 kPa sweep's top in mbar
        ("100.0001", "pressure_kpa 100.0001 is above"),  # the cell as written, not rounded
    ],
)
def test_bad_pressure(tmp_path: Path, cell: str, problem: str) -> None:
    _fails(_session(tmp_path, f"file,pressure_kpa\na.png,0\nb.png,{cell}\n"), "row 2", problem)


def test_repeated_pressures_are_steps(tmp_path: Path) -> None:
    path = _session(tmp_path, "file,pressure_kpa\na.png,2\nb.png,0\nc.png,2.0\n")
    session = read_session(path)
    assert [(f.file.name, f.step) for f in session.frames] == [
        ("b.png", 0),
        ("a.png", 1),
        ("c.png", 1),
    ]
    assert {f.phase for f in session.frames} == {"loading"}
    assert session.phase_source == SINGLE_PASS


def test_phase_column(tmp_path: Path) -> None:
    names = ("a.png", "b.png", "c.png", "d.png")
    text = "file,pressure_kpa,phase\na.png,0,Loading\nb.png,4,LOADING\n"
    text += "c.png,2, unloading\nd.png,0,unloading\n"
    session = read_session(_session(tmp_path, text, names))
    assert [(f.file.name, f.phase, f.step) for f in session.frames] == [
        ("a.png", "loading", 0),
        ("b.png", "loading", 1),
        ("d.png", "unloading", 0),
        ("c.png", "unloading", 1),
    ]
    assert session.phase_source == FROM_COLUMN
    _fails(
        _session(tmp_path, "file,pressure_kpa,phase\na.png,0,loading\nb.png,1,up\n"),
        "row 2",
        "'up'",
    )
    _fails(
        _session(tmp_path, "file,pressure_kpa,phase\na.png,0,unloading\nb.png,1,unloading\n"),
        "no loading frame",
    )
    text = "file,pressure_kpa,phase\na.png,0,loading\nb.png,1,loading\nc.png,1,unloading\n"
    _fails(_session(tmp_path, text), "unloading pass has 1 frame", ">= 2 pressure steps")


@pytest.mark.parametrize("name", ["phases", "pass", "Direction"])
def test_passes_in_a_column_of_another_name_are_refused(tmp_path: Path, name: str) -> None:
    """A misspelt or renamed phase column was an extra column: the passes it states were
    silently read from the row order (here: one pass, merging loading and unloading)."""
    names = ("a.png", "b.png", "c.png", "d.png")
    text = f"file,pressure_kpa,{name}\na.png,0,loading\nb.png,2,unloading\n"
    text += "c.png,2,loading\nd.png,0,Unloading\n"
    _fails(_session(tmp_path, text, names), f"column '{name}' holds loading/unloading", "'phase'")
    other = "file,pressure_kpa,note\na.png,0,loading\nb.png,2,dusty\nc.png,4,\n"
    assert [f.pressure_kpa for f in read_manifest(_session(tmp_path, other))] == [0, 2, 4]


def test_phases_from_row_order(tmp_path: Path) -> None:
    names = ("a.png", "b.png", "c.png", "d.png", "e.png", "f.png")
    text = "file,pressure_kpa\na.png,0\nb.png,2\nc.png,4\nd.png,4\ne.png,2\nf.png,0\n"
    session = read_session(_session(tmp_path, text, names))
    assert [(f.file.name, f.phase) for f in session.frames] == [
        ("a.png", "loading"),
        ("b.png", "loading"),
        ("c.png", "loading"),
        ("d.png", "loading"),
        ("f.png", "unloading"),
        ("e.png", "unloading"),
    ]
    assert session.phase_source == FROM_ORDER
    text = "file,pressure_kpa\na.png,0\nb.png,2\nc.png,4\nd.png,0\n"
    _fails(_session(tmp_path, text, names), "unloading pass has 1 frame", "'phase' column")
    descending = "file,pressure_kpa\na.png,4\nb.png,2\nc.png,0\n"
    assert read_session(_session(tmp_path, descending)).phase_source == SINGLE_PASS


def test_pressure_range_bounds_are_accepted(tmp_path: Path) -> None:
    frames = read_manifest(_session(tmp_path, "file,pressure_kpa\na.png,0\nb.png,100\n"))
    assert [f.pressure_kpa for f in frames] == [0.0, 100.0]


def test_same_file_on_two_rows(tmp_path: Path) -> None:
    _fails(
        _session(tmp_path, "file,pressure_kpa\na.png,0\nb.png,2\n./b.png,4\n"),
        "rows 2",
        "and 3",
        "same image file",
        str((tmp_path / "b.png").resolve()),
    )


def test_one_file_on_many_rows(tmp_path: Path) -> None:
    rows = "".join(f"a.png,{(p % 40) / 2:g}\n" for p in range(1000))  # 0-19.5 kPa
    _fails(_session(tmp_path, "file,pressure_kpa\n" + rows), "rows 1", "and 2", "same image")


def test_link_to_a_listed_file(tmp_path: Path) -> None:
    path = _session(tmp_path, "file,pressure_kpa\na.png,0\nb.png,2\nlink.png,4\n")
    (tmp_path / "link.png").symlink_to(tmp_path / "a.png")
    _fails(path, "rows 1", "and 3", "same image file")
    (tmp_path / "link.png").unlink()
    os.link(tmp_path / "a.png", tmp_path / "link.png")  # a hard link: another path, one file
    _fails(path, "rows 1", "and 3", "same image file")


def test_single_frame(tmp_path: Path) -> None:
    _fails(_session(tmp_path, "file,pressure_kpa\na.png,0\n"), ">= 2 pressure steps")


def test_missing_image(tmp_path: Path) -> None:
    path = _session(tmp_path, "file,pressure_kpa\na.png,0\nmissing.png,2\n")
    _fails(path, "not found", "row 2", str((tmp_path / "missing.png").resolve()))


def test_not_utf8(tmp_path: Path) -> None:
    path = _session(tmp_path, "")
    path.write_bytes(b"file,pressure_kpa\n\xff\xfe.png,0\n")
    _fails(path, "UTF-8")


def test_a_windows_path_gets_a_hint(tmp_path: Path) -> None:
    """A manifest written on Windows (backslashes) names the likely cause on POSIX."""
    if os.sep == "\\":
        pytest.skip("backslashes are separators here")
    (tmp_path / "frames").mkdir()
    manifest = tmp_path / "m.csv"
    manifest.write_text("file,pressure_kpa\nframes\\p00.png,0\nframes\\p05.png,5\n")
    with pytest.raises(ManifestError, match=r"not found: .*written with '\\' as on Windows"):
        read_manifest(manifest)


def _rows(tmp_path: Path, pressures: list[float]) -> Path:
    names = tuple(f"f{i:02d}.png" for i in range(len(pressures)))
    body = "".join(f"{n},{p:g}\n" for n, p in zip(names, pressures, strict=True))
    return _session(tmp_path, "file,pressure_kpa\n" + body, names)


def test_a_row_breaking_an_otherwise_rising_order_is_named(tmp_path: Path) -> None:
    """A mistyped pressure (16 for 6 kPa) was read silently as one pass in pressure order."""
    typo = [0, 1, 2, 3, 4, 5, 16, 7, 8, 9, 10]
    session = read_session(_rows(tmp_path, typo))
    assert session.phase_source == SINGLE_PASS
    assert session.out_of_order == ("row 7 (f06.png, 16 kPa)",)
    loop = [0, 5, 10, 15, 20, 15, 12, 10, 17, 5, 0]  # a typo in the unloading pass
    assert read_session(_rows(tmp_path, loop)).out_of_order == ("row 9 (f08.png, 17 kPa)",)
    for fine in (
        [0, 2, 4, 6, 8, 10],  # rising
        [0, 4, 8, 4, 0],  # rising, then falling (two passes)
        [10, 8, 6, 4, 2, 0],  # falling: one pass
        [6, 0, 10, 2, 8, 4],  # no particular order: one pass, nothing to name
    ):
        assert read_session(_rows(tmp_path, fine)).out_of_order == (), fine


@pytest.mark.parametrize(
    ("levels", "misplaced"),
    [
        ([0, 1, 2, 3, 4, 5, 16, 7, 8, 9], [6]),
        ([0, 0, 5, 5, 3, 10], [4]),  # ties: the longer rise (a loading session's typo)
        ([0, 5, 10, 20, 10, 5, 0], []),
        ([5, 3, 8, 1, 9, 2], [0, 3]),
        ([], []),
    ],
)
def test_misplaced_rows_reference_values(levels: list[float], misplaced: list[int]) -> None:
    assert misplaced_rows(levels) == misplaced


def test_a_jpeg_reference_width_is_read_from_its_header_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import cv2
    import numpy as np

    from contactcal.infer.image.read import ImageFile
    from contactcal.infer.pipeline.manifest import reference_width

    for name in ("a.jpg", "b.png"):
        assert cv2.imwrite(str(tmp_path / name), np.zeros((30, 40), np.uint8))
    path = tmp_path / "manifest.csv"
    path.write_text("file,pressure_kpa\na.jpg,0\nb.png,1\n", encoding="utf-8")
    session = read_session(path)
    monkeypatch.setattr(ImageFile, "read", lambda *_: pytest.fail("the whole file read"))
    assert reference_width(session, None) == 40

"""``read_input_json``: the one reader of a JSON input (an earlier record, a run's or a set's
``config.json``, an evaluation) behind every caller's own wording of its refusals."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from unreadable_json import UNREADABLE_JSON

from contactcal.infer.files.regular import read_input_json, read_record_json


class _Refusal(Exception):
    """A caller's own error type."""


def test_the_json_value_is_read(tmp_path: Path) -> None:
    path = tmp_path / "r.json"
    path.write_text('{"a": [1, "\u00b2"]}', encoding="utf-8")
    assert read_input_json(path, "the R file", _Refusal) == {"a": [1, "\u00b2"]}


def test_a_folder_is_refused_in_the_callers_type(tmp_path: Path) -> None:
    with pytest.raises(_Refusal, match=f"^{tmp_path}: is a folder; expected the R file$"):
        read_input_json(tmp_path, "the R file", _Refusal)


@pytest.mark.parametrize(
    ("content", "raised"),
    [
        (b'{"a": 1,', json.JSONDecodeError),
        (b'{"a": "\xff"}', UnicodeDecodeError),
        *((text.encode(), json.JSONDecodeError) for text in UNREADABLE_JSON.values()),
    ],
)
def test_damaged_content_is_left_to_the_caller_unwrapped(
    tmp_path: Path, content: bytes, raised: type[ValueError]
) -> None:
    """A syntax or decode error is Python's own, not the caller's type: each caller words it
    (or reads it as no record) in its own except clause."""
    path = tmp_path / "r.json"
    path.write_bytes(content)
    with pytest.raises(raised):
        read_input_json(path, "the R file", _Refusal)


def test_a_missing_file_is_the_open_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        read_input_json(tmp_path / "none.json", "the R file", _Refusal)


@pytest.mark.parametrize(
    ("content", "found"),
    [
        (None, "cannot be read (No such file or directory)"),
        (b'{"a": 1,', "not valid JSON (Expecting property name enclosed in double quotes: line 1 "),
        (b'{"a": "\xff"}', "not valid JSON (not UTF-8 text)"),
    ],
)
def test_a_record_is_refused_in_one_line_naming_it_and_what_to_do(
    tmp_path: Path, content: bytes | None, found: str
) -> None:
    """``read_record_json``: the one wording of a damaged record, whichever reads it (an
    earlier ``calibration.json`` worded its own: "('utf-8' codec can't decode byte ...)")."""
    path = tmp_path / "r.json"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(ValueError) as exc:
        read_record_json(path, "the R file; remove it")
    assert str(exc.value).startswith(f"{path}: {found}"), exc.value
    assert str(exc.value).endswith("; expected the R file; remove it")

"""Safe file reading: size and nesting limits, BOM, numbers that cannot be floats."""

from __future__ import annotations

import json
import os

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError
from subtask_opt.base.files import json_depth, parse_json, read_text

FUZZ = int(os.environ.get("FUZZ_EXAMPLES", "60"))


def test_read_text_drops_a_bom_and_refuses_oversize_files(tmp_path):
    path = tmp_path / "a.csv"
    path.write_bytes(b"\xef\xbb\xbfx,y\n")
    assert read_text(path, "file") == "x,y\n"
    with pytest.raises(InputDataError, match="limit is 3"):
        read_text(path, "file", max_bytes=3)
    with pytest.raises(InputDataError, match="not found"):
        read_text(tmp_path / "missing.csv", "file")
    with pytest.raises(InputDataError, match="folder"):
        read_text(tmp_path, "file")
    (tmp_path / "b.bin").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputDataError, match="UTF-8"):
        read_text(tmp_path / "b.bin", "file")


@pytest.mark.parametrize("depth", [1, 5, 40])
def test_json_depth_counts_brackets_outside_strings(depth):
    text = "[" * depth + "]" * depth
    assert json_depth(text) == depth
    assert json_depth('{"a": "[[[[", "b": [1]}') == 2


def test_parse_json_refuses_deep_nesting_huge_numbers_and_nan():
    with pytest.raises(InputDataError, match="nested 33 deep, deeper than the limit of 32"):
        parse_json("[" * 33 + "]" * 33, "x")
    with pytest.raises(InputDataError, match="digits"):
        parse_json("[" + "9" * 5000 + "]", "x")
    with pytest.raises(InputDataError, match="out of range"):
        parse_json("[1e999]", "x")
    with pytest.raises(InputDataError, match="NaN"):
        parse_json("[NaN]", "x")
    assert parse_json('{"a": [1, 2.5]}', "x") == {"a": [1, 2.5]}


@settings(max_examples=FUZZ, deadline=None)
@given(st.text(max_size=300))
def test_parse_json_answers_any_text_with_a_value_or_our_error(text):
    try:
        value = parse_json(text, "fuzz")
    except InputDataError:
        return
    assert json.dumps(value) is not None

"""Subtask files and sets: bad input is refused with one clear error, never another exception."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.arm.targets import DUPLICATE_TOL, Targets
from subtask_opt.arm.tasks import load_subtasks
from subtask_opt.base.errors import InputDataError, SubtaskOptError
from tests.conftest import examples

FUZZ = int(os.environ.get("FUZZ_EXAMPLES", "60"))


def test_a_bom_csv_is_read(tmp_path):
    path = tmp_path / "p.csv"
    path.write_bytes("\ufeffx,y\n0.3,0.1\n0.35,0.2\n0.25,0.3\n".encode())
    assert len(load_subtasks(path)) == 3


@pytest.mark.parametrize("gap", [0.3 * DUPLICATE_TOL, 0.999 * DUPLICATE_TOL])
def test_points_closer_than_the_tolerance_are_duplicates_wherever_they_sit(gap):
    # a 1e-9 rounding grid used to accept or refuse such pairs depending on where they fell
    for base in (0.3, 0.3 + 0.5e-9, 0.123456789123):
        pts = [[base, 0.1], [base + gap, 0.1], [0.2, 0.2]]
        with pytest.raises(InputDataError, match="duplicates"):
            Targets(pts)


def test_points_farther_than_the_tolerance_are_distinct():
    Targets([[0.3, 0.1], [0.3 + 1.001 * DUPLICATE_TOL, 0.1], [0.2, 0.2]])


@pytest.mark.parametrize("points", [
    [[1j, 0], [0, 1], [1, 1]],                    # complex
    [["0.1", "0.2"], [0, 1], [1, 1]],             # strings
    [[10**400, 0], [0, 1], [1, 1]],               # an int no float holds
    [[1e7, 0], [0, 1], [1, 1]],                   # beyond the coordinate range
])
def test_non_real_or_out_of_range_points_are_refused(points):
    with pytest.raises(InputDataError):
        Targets(points)


def test_a_huge_json_number_and_a_long_csv_line_are_refused(tmp_path):
    j = tmp_path / "p.json"
    j.write_text('{"points": [[' + "9" * 5000 + ', 0], [0, 1], [1, 1]]}')
    with pytest.raises(InputDataError, match="digits"):
        load_subtasks(j)
    c = tmp_path / "p.csv"
    c.write_text("x,y\n" + "1" * 5000 + ",2\n")
    with pytest.raises(InputDataError, match="line 2"):
        load_subtasks(c)
    deep = tmp_path / "d.json"
    deep.write_text('{"points": ' + "[" * 100 + "]" * 100 + "}")
    with pytest.raises(InputDataError, match="nested"):
        load_subtasks(deep)


@settings(max_examples=examples(FUZZ), deadline=None)
@given(st.text(max_size=200), st.sampled_from([".csv", ".json"]))
def test_any_file_content_gives_a_set_or_our_error(tmp_path_factory, text, suffix):
    path = tmp_path_factory.mktemp("fuzz") / f"s{suffix}"
    path.write_text(text)
    try:
        s = load_subtasks(path)
    except SubtaskOptError:
        return
    assert len(s) >= 3 and np.isfinite(s.points).all()


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None)
@given(st.lists(st.lists(st.one_of(st.floats(), st.integers(), st.text(max_size=3),
                                   st.none()), min_size=0, max_size=3), max_size=8))
def test_any_points_give_a_set_or_our_error(points):
    try:
        s = Targets(points)
    except SubtaskOptError:
        return
    assert len(s) >= 3

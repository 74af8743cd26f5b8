"""RoboTSP's benchmark with our search's stall and kicks set (``-m bench`` for the run)."""

from __future__ import annotations

import pytest

from subtask_opt.base.errors import ParameterError
from tests.conftest import SHARED_DATA

DATA = SHARED_DATA / "robotsp"
needs_data = pytest.mark.skipif(not (DATA / "targets.csv").is_file(),
                                reason="RoboTSP data missing")


@needs_data
@pytest.mark.parametrize(("option", "value", "message"), [
    ("stall", 0, r"NoImprovement.generations must be an integer in \[1, .*got 0"),
    ("kicks", -1, r"kicks must be an integer in \[0, 1000\], got -1"),
])
def test_bad_search_options_name_the_value(option, value, message) -> None:
    from subtask_opt.papers.robotsp import run

    with pytest.raises(ParameterError, match=message):
        run(DATA, sizes=[25], peers=(), **{option: value})


@pytest.mark.bench
@needs_data
def test_short_search_is_recorded_and_valid() -> None:
    from subtask_opt.papers.robotsp import run, table

    report = run(DATA, sizes=[25], peers=(), stall=1, kicks=0)
    ours = report["subsets"]["25"]["methods"]["ours"]
    assert ours["valid"], ours["violations"]
    assert ours["legs_in_collision"] == 0
    assert (report["stall"], report["kicks"]) == (1, 0)
    assert "stall 1, kicks 0" in table(report).splitlines()[0]
    # numba's compilation and loading apart from every phase, in the table too
    assert set(ours["cpu_s"]) == {"ik", "collision", "matrix", "compile", "search"}
    assert "compile s" in table(report).splitlines()[1]

"""``subtask-opt reproduce``: every paper at a reduced size, its table, and bad input.

The checks that can be made exactly are made exactly: Fig. 2.4 and Table 1 of
paper 001 must equal the print, Table 1 of paper 003 must come within 0.05 % (on its
fitted start and goal). Paper 000's DT and MDT rows share one corner rule, and the MDT is
never longer than the DT.
"""

from __future__ import annotations

import json

import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.cli import main
from subtask_opt.papers import PAPERS, reproduce
from subtask_opt.papers.report import PaperReport, Row


def _check_000(rows):
    """Fig. 2.4 value for value; on every map the DT and MDT rows name the same corner rule
    (the thesis') and the MDT is not longer where both found a path."""
    assert rows["Fig. 2.4: values equal to the print"]["ours"] == 94
    assert rows["Fig. 2.4: largest |ours - print|"]["ours"] == 0
    compared = 0
    for table in ("4.2", "4.3", "4.4", "4.5", "4.6", "4.7"):
        dt, mdt, ga = (rows[f"Table {table}: {k} length"] for k in ("DT", "MDT", "GA"))
        rule = dt["note"].split("; ")[-1]
        assert rule.startswith("thesis corner rule") and mdt["note"].split("; ")[-1] == rule
        assert ga["note"].split("; ")[-1].startswith("closed-square rule")
        if isinstance(dt["ours"], float) and isinstance(mdt["ours"], float):
            assert mdt["ours"] <= dt["ours"], table
            compared += 1
    assert compared == 6  # the DT and MDT find a path on every map
    count = rows["Tables 4.2-4.7: maps where the MDT is not longer than the DT"]
    assert count["ours"] == count["paper"] == 6


def _check_001(rows):
    """Table 1 exactly."""
    for i in range(1, 8):
        row = rows[f"Table 1: muD of candidate {i}"]
        assert row["ours"] == pytest.approx(row["paper"], abs=1e-12)
    assert rows["Table 1: chosen candidate"]["ours"] == 4


def _check_002(rows):
    """The optimum's generation is reported with the runs that reached the MILP optimum."""
    for case in ("square20", "random30"):
        hits = rows[f"{case}: runs reaching the optimum"]["ours"]
        median = rows[f"{case}: generation of the optimum (median)"]["ours"]
        assert (median is None) == hits.startswith("0/")


def _check_003(rows):
    """Table 1 within 0.05 % on the fitted start and goal, and the rows say "fitted"."""
    for item in ("Dijkstra", "improved Dijkstra", "improved Dijkstra + PSO"):
        row = rows[f"Table 1: {item} length"]
        assert row["ours"] == pytest.approx(row["paper"], rel=5e-4)
        assert "fitted" in row["note"] and "reproduc" not in row["note"]


def _check_004(rows):
    """Experiment 2-2's obstacle crosses the route in the event log."""
    assert rows["exp. 2-2: the obstacle crosses the route while the AGV approaches"]["ours"] \
        == "yes"


CHECKS = {"000": _check_000, "001": _check_001, "002": _check_002, "003": _check_003,
          "004": _check_004}


@pytest.mark.parametrize("paper", list(PAPERS))
def test_quick_reproduction_exits_0_and_writes_its_table_and_figures(paper, tmp_path, capsys):
    # 004's suite on two local workers; the other papers run here and refuse the option
    workers = ["--workers", "2"] if paper == "004" else []
    code = main(["reproduce", paper, "--out", str(tmp_path), "--quick", *workers,
                 "--no-progress"])
    text = capsys.readouterr().out
    assert code == 0
    table = json.loads((tmp_path / f"table_{paper}.json").read_text())
    assert table["paper"] == paper and table["quick"] and table["rows"]
    assert (tmp_path / f"table_{paper}.txt").read_text().strip() in text
    assert (tmp_path / f"table_{paper}.md").read_text().startswith("| item | paper | ours |")
    assert table["files"]
    for f in table["files"]:
        with open(f, "rb") as fh:
            assert fh.read(4) == b"\x89PNG", f
    # every row names the paper's value beside ours (the suite rows of 004 are ours only)
    assert all(r["paper"] is not None for r in table["rows"] if not r["item"].startswith("suite"))
    CHECKS[paper]({r["item"]: r for r in table["rows"]})


@pytest.mark.parametrize("argv", [["reproduce", "005"], ["reproduce", "1"], ["reproduce"],
                                  ["reproduce", "001", "--seed", "-1"],
                                  ["reproduce", "004", "--workers", "-2"],
                                  ["reproduce", "002", "--workers", "2"],
                                  ["reproduce", "000", "--scheduler", "tcp://head:8786"]])
def test_bad_input_exits_2_in_one_line(argv, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_reproduce_refuses_an_unknown_paper(tmp_path):
    with pytest.raises(ParameterError, match="000, 001, 002, 003, 004"):
        reproduce("007", tmp_path)


@pytest.mark.parametrize("paper, ours, expected", [
    (200.0, 201.0, "+0.50%"), (4, 3, "-25.00%"), (0, 2, "+2"), ("yes", "yes", "same"),
    ("yes", "no", "differs"), (1.0, None, "-"), (None, 3, "-"),
])
def test_row_deviation(paper, ours, expected):
    assert Row("x", paper, ours).deviation == expected


@pytest.mark.parametrize("kwargs", [{"item": ""}, {"paper": float("nan")}, {"ours": True},
                                    {"ours": [1]}])
def test_row_rejects_bad_fields(kwargs):
    with pytest.raises(ParameterError):
        Row(**{"item": "x", "paper": 1.0, "ours": 1.0, **kwargs})


def test_a_report_needs_rows():
    with pytest.raises(ParameterError, match="at least one row"):
        PaperReport("000", "t", ())


def test_markdown_escapes_pipes_in_cells():
    text = PaperReport("000", "t", (Row("largest |x - y|", 0, 0),)).markdown()
    assert text.splitlines()[-1] == "| largest \\|x - y\\| | 0 | 0 | +0 |  |"


def test_optimal_tours_finds_every_optimum_against_brute_force():
    """Five points: a unit square and one point above it (one optimal tour), then the fifth
    point moved onto a corner (two tours of equal time); brute force over all 12 tours
    is the oracle."""
    import itertools

    import numpy as np

    from subtask_opt.papers.p002_sequencing import canonical, optimal_tours
    from subtask_opt.tour.exact import milp_optimum, tour_length

    tours = {canonical(np.array((0, *p))) for p in itertools.permutations(range(1, 5))}
    for top, expected in (((0.5, 2.0), 1), ((0.0, 1.0), 2)):
        pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], top], dtype=float)
        m = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        value, order = milp_optimum(m)
        best = min(tour_length(m, np.array(t)) for t in tours)
        brute = {t for t in tours if tour_length(m, np.array(t)) <= best * (1 + 1e-9)}
        assert len(brute) == expected
        assert optimal_tours(m, order, float(value)) == brute

"""`subtask-opt solve` with tour shapes and precedence: JSON fields and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from subtask_opt.cli.app import main

BASE = ["solve", "--case", "square20", "--time-model", "trapezoid", "--quiet", "--no-progress"]


def test_open_path_with_precedence_writes_the_shape(tmp_path, capsys) -> None:
    prec = tmp_path / "prec.txt"
    prec.write_text("# drill before deburr\n3,7\n7,12\n")
    out = tmp_path / "r.json"
    code = main([*BASE, "--tour", "open", "--first", "2", "--end", "9", "--precedence",
                 str(prec), "--json", str(out), "--seed", "4"])
    assert code == 0
    assert "shape: open tour, from 2 to 9, 2 precedence constraints" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert (data["tour"], data["start"], data["end"], data["home"], data["precedence"]) == (
        "open", 2, 9, None, 2)
    order = data["order"]
    assert order[0] == 2 and order[-1] == 9 and sorted(order) == list(range(20))
    assert order.index(3) < order.index(7) < order.index(12)
    m = np.array(data["matrix"])
    path = sum(m[order[k], order[k + 1]] for k in range(19))  # no return leg
    assert data["total_time"] == pytest.approx(path)
    assert data["lower_bound"] <= data["total_time"] and data["gap_bound"] >= 0


def test_closed_tour_json_has_the_shape_fields(tmp_path, capsys) -> None:
    out = tmp_path / "r.json"
    assert main([*BASE, "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert (data["tour"], data["start"], data["end"], data["home"], data["precedence"]) == (
        "closed", 0, None, None, 0)
    for key in ("order", "total_time", "lower_bound", "gap_bound"):
        assert key in data


def test_home_point(tmp_path, capsys) -> None:
    out = tmp_path / "r.json"
    assert main([*BASE, "--home", "0.3,0.3", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["home"] == [0.3, 0.3] and data["start"] is None
    assert sorted(data["order"]) == list(range(20)) and len(data["leg_times"]) == 21


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize(("lines", "args", "message"), [
    ("1,2\n2,5\n5,1\n", [], "lines 1, 2, 3 form a cycle of 3 subtasks: 1 -> 2 -> 5 -> 1"),
    ("1,40\n", [], "names subtask 40; subtasks are numbered 0..19"),
    ("1;2\n", [], "line 1: expected 'a,b'"),
    ("3,0\n", [], "before the start 0"),
    ("", ["--end", "3"], "end=3 needs tour='open'"),
    ("", ["--home", "9,9"], "home point (9, 9) is unreachable: is beyond the reach"),
    ("", ["--home", "0.3,0.3", "--first", "2"], "first=2 and a home contradict"),
    ("", ["--home", "1,2,3"], "--home takes a point X,Y"),
    ("", ["--tour", "open", "--plot", "x.png"], "--plot draws closed tours"),
])
def test_bad_shape_input_is_one_line_and_exit_2(tmp_path, capsys, lines, args,
                                                message) -> None:
    argv = [*BASE, *args]
    if lines:
        prec = tmp_path / "p.txt"
        prec.write_text(lines)
        argv += ["--precedence", str(prec)]
    if "--plot" in args:
        argv[argv.index("x.png")] = str(tmp_path / "x.png")
    assert main(argv) == 2
    assert message in _one_error_line(capsys)


def test_missing_precedence_file_is_exit_2(tmp_path, capsys) -> None:
    assert main([*BASE, "--precedence", str(tmp_path / "none.txt")]) == 2
    assert "none.txt" in _one_error_line(capsys)

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
])
def test_bad_shape_input_is_one_line_and_exit_2(tmp_path, capsys, lines, args,
                                                message) -> None:
    argv = [*BASE, *args]
    if lines:
        prec = tmp_path / "p.txt"
        prec.write_text(lines)
        argv += ["--precedence", str(prec)]
    assert main(argv) == 2
    assert message in _one_error_line(capsys)


def test_missing_precedence_file_is_exit_2(tmp_path, capsys) -> None:
    assert main([*BASE, "--precedence", str(tmp_path / "none.txt")]) == 2
    assert "none.txt" in _one_error_line(capsys)


@pytest.mark.parametrize("shape", [["--tour", "open"], ["--home", "0.3,0.3"],
                                   ["--home", "0.3,0.3", "--tour", "open"]])
def test_plot_draws_open_paths_and_homes(tmp_path, shape) -> None:
    png = tmp_path / "tour.png"
    assert main([*BASE, *shape, "--plot", str(png)]) == 0
    from PIL import Image

    with Image.open(png) as image:
        assert image.size[0] > 1000 and image.getextrema() != ((255, 255),) * 3


@pytest.mark.parametrize(("tour", "home"), [("open", None), ("closed", (0.3, 0.3)),
                                            ("open", (0.3, 0.3))])
def test_the_drawn_legs_are_the_legs_the_report_drives(tour, home) -> None:
    # oracle: the report's legs (an open path has no return leg; a home starts and ends
    # the tour) and the points themselves at each drawn leg's ends
    import subtask_opt as so
    from subtask_opt.plotting.sequencing import report_stops, tour_legs

    robot = so.load_robot("planar_2r")
    problem = so.ArmProblem(so.builtin_case("square20", robot.model), robot,
                            time_model="trapezoid")
    result = so.solve(problem, seed=1, stop=so.MaxGenerations(30),
                      constraints=so.TourConstraints(tour=tour, home=home))
    drawn, stops, home_index = report_stops(result)
    legs = tour_legs(drawn, result.order, result.report.configurations, stops=stops)
    n = 20 + (home is not None) - (tour == "open")
    assert len(legs) == len(result.report.legs) == n
    pts = drawn.subtasks.points
    for leg, reported in zip(legs, result.report.legs, strict=True):
        assert (leg.start, leg.end) == tuple(home_index if v < 0 else v
                                             for v in (reported.start, reported.end))
        np.testing.assert_allclose(leg.xy[[0, -1]], pts[[leg.start, leg.end]], atol=1e-12)
    if home is None:
        assert home_index is None and legs[0].start != legs[-1].end
    else:
        np.testing.assert_allclose(pts[home_index], home)
        assert legs[0].start == home_index and (legs[-1].end == home_index) == (
            tour == "closed")

"""CLI: ``plan polygon`` and ``bench maklink``, outputs and one-line errors."""

from __future__ import annotations

import json

import pytest

from subtask_opt.cli.app import main
from subtask_opt.planners.polygon.world import PolygonWorld


@pytest.mark.parametrize("planner", ["dijkstra", "improved", "pso", "visibility"])
def test_plan_polygon(planner, tmp_path, capsys):
    out = tmp_path / "r.json"
    rc = main(["plan", "polygon", "--world", "seed003", "--start", "20,20", "--goal", "320,320",
               "--planner", planner, "--seed", "1", "--json", str(out), "--no-progress"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "exact optimum 425.4666" in text
    d = json.loads(out.read_text())
    assert {"length", "path", "runtime_s"} <= set(d)
    assert d["success"] and d["optimum"] == pytest.approx(425.4666, abs=1e-4)
    assert d["path"][0] == [20.0, 20.0] and d["path"][-1] == [320.0, 320.0]
    if planner == "visibility":
        assert d["length"] == pytest.approx(425.4666, abs=1e-4)
    assert d["planner"] == planner and d["outcome"] == "success"
    assert d["gap_pct"] >= -1e-9


def test_plan_polygon_pso_json_has_seed_and_history(tmp_path):
    out = tmp_path / "r.json"
    assert main(["plan", "polygon", "--start", "20,20", "--goal", "320,320", "--seed", "5",
                 "--iterations", "30", "--json", str(out), "--no-progress"]) == 0
    d = json.loads(out.read_text())
    assert d["info"]["seed"] == 5 and len(d["history"]["best_cost"]) == 30


def test_planner_choices_come_from_the_registry(capsys):
    from subtask_opt.planners.base import planners

    assert main(["plan", "polygon", "--help"]) == 0
    text = capsys.readouterr().out
    for name, info in planners("polygon").items():
        assert name in text and info.description.split()[0] in text


POCKET = {"bounds": [0, 0, 10, 10], "obstacles": [[[6, 6], [10, 6], [6, 10]]]}


@pytest.mark.parametrize("planner", ["dijkstra", "improved", "pso", "visibility"])
def test_plan_polygon_no_path_exits_1(tmp_path, capsys, planner):
    world = tmp_path / "pocket.json"
    world.write_text(json.dumps(POCKET))
    out = tmp_path / "r.json"
    rc = main(["plan", "polygon", "--world", str(world), "--start", "1,1", "--goal", "9.5,9.5",
               "--planner", planner, "--json", str(out), "--no-progress"])
    assert rc == 1
    _one_line_error(capsys, "no collision-free path")
    d = json.loads(out.read_text())
    assert d["success"] is False and d["outcome"] == "no_path" and d["optimum"] is None


def test_bench_maklink_no_path_exits_1(tmp_path, capsys):
    world = tmp_path / "pocket.json"
    world.write_text(json.dumps(POCKET))
    rc = main(["bench", "maklink", "--world", str(world), "--pair", "1,1", "9.5,9.5",
               "--pair", "1,1", "5,1", "--runs", "1", "--no-progress"])
    assert rc == 1
    assert "no collision-free path" in capsys.readouterr().out


def test_plan_polygon_json_world_and_plot(tmp_path, capsys):
    world = tmp_path / "w.json"
    PolygonWorld((0, 0, 10, 10), ([[4, 2], [6, 2], [6, 8], [4, 8]],)).to_json(world)
    png = tmp_path / "fig.png"
    rc = main(["plan", "polygon", "--world", str(world), "--start", "1,5", "--goal", "9,5",
               "--planner", "pso", "--iterations", "30", "--plot", str(png), "--no-progress"])
    assert rc == 0 and png.stat().st_size > 0
    assert "world w:" in capsys.readouterr().out


def test_bench_maklink(tmp_path, capsys):
    out = tmp_path / "b.json"
    png = tmp_path / "b.png"
    rc = main(["bench", "maklink", "--pair", "20,20", "320,320", "--pair", "145,290", "5,130",
               "--runs", "2", "--json", str(out), "--plot", str(png), "--no-progress"])
    assert rc == 0 and png.stat().st_size > 0
    text = capsys.readouterr().out
    header = next(line for line in text.splitlines() if "Dijkstra" in line and "start" in line)
    assert header.split()[-1] == "optimum"
    assert "425.4666" in text and "NO" in text and "not stated" in text
    rows = json.loads(out.read_text())["rows"]
    assert len(rows) == 2 and rows[0]["same_sides"] and not rows[1]["same_sides"]


def _one_line_error(capsys, match: str) -> None:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and match in err, err


@pytest.mark.parametrize("argv, match", [
    (["--start", "50,200", "--goal", "320,320"], "start (50, 200) is inside obstacle 0"),
    (["--start", "20,20", "--goal", "400,320"], "goal (400, 320) is outside the world bounds"),
    (["--start", "20,20", "--goal", "320,320", "--world", "moon"], "world must be one of"),
    (["--start", "20,20", "--goal", "320,320", "--world", "missing.json"], "missing.json"),
    (["--start", "20,20", "--goal", "320,320", "--seed", "-3"], "a seed must be in [0, 2**63)"),
    (["--start", "20,20", "--goal", "320,320", "--seed", str(2**63)], "a seed must be in"),
    (["--start", "20,20", "--goal", "320,320", "--seed", "1.5"], "expected a whole number"),
    (["--start", "40,200", "--goal", "320,320"], "start (40, 200) is on the boundary of obst"),
    (["--start", "20,20", "--goal", "320,320", "--plot", "x.txt"], "must end in .png"),
    (["--start", "20;20", "--goal", "320,320"], "expected 2 comma-separated numbers"),
    (["--start", "20,20", "--goal", "320,320", "--planner", "astar"], "invalid choice"),
    (["--start", "20,20", "--goal", "320,320", "--swarm", "1"], "PSOParams.swarm"),
    (["--start", "20,20", "--goal", "320,320", "--iterations", "0"], "whole number >= 1"),
])
def test_plan_polygon_errors(argv, match, capsys):
    assert main(["plan", "polygon", "--no-progress", *argv]) == 2
    _one_line_error(capsys, match)


def test_bad_world_files(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2")
    assert main(["plan", "polygon", "--world", str(bad), "--start", "1,1", "--goal", "2,2"]) == 2
    _one_line_error(capsys, "not valid JSON")
    overlap = tmp_path / "overlap.json"
    overlap.write_text(json.dumps({"bounds": [0, 0, 10, 10], "obstacles": [
        [[1, 1], [5, 1], [5, 5]], [[2, 2], [6, 2], [6, 6]]]}))
    assert main(["plan", "polygon", "--world", str(overlap), "--start", "1,1",
                 "--goal", "2,2"]) == 2
    _one_line_error(capsys, "obstacles 0 and 1 overlap")


def test_outputs_may_not_overwrite_the_world(tmp_path, capsys):
    world = tmp_path / "w.json"
    PolygonWorld((0, 0, 10, 10), ()).to_json(world)
    assert main(["plan", "polygon", "--world", str(world), "--start", "1,1", "--goal", "2,2",
                 "--json", str(world)]) == 2
    _one_line_error(capsys, "is also an input file")


def test_bench_errors(tmp_path, capsys):
    world = tmp_path / "w.json"
    PolygonWorld((0, 0, 10, 10), ()).to_json(world)
    assert main(["bench", "maklink", "--world", str(world), "--no-progress"]) == 2
    _one_line_error(capsys, "--pair")
    assert main(["bench", "maklink", "--pair", "50,200", "1,1", "--no-progress"]) == 2
    _one_line_error(capsys, "pair 1 start (50, 200) is inside obstacle 0")
    assert main(["bench", "maklink", "--seed", "-1", "--no-progress"]) == 2
    _one_line_error(capsys, "a seed must be in")

"""plan_against_optimum: any registered planner against the exact optimum."""

from __future__ import annotations

import json
import math

import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.polygon.compare import plan_against_optimum
from subtask_opt.planners.polygon.world import PolygonWorld, load_world


def test_gap_is_measured_against_the_visibility_optimum(seed003):
    run = plan_against_optimum(seed003, "dijkstra", (20, 20), (320, 320), seed=5,
                               stop=MaxGenerations(3))  # ignored: dijkstra takes neither
    exact = plan_against_optimum(seed003, "visibility", (20, 20), (320, 320))
    assert run.optimum == pytest.approx(exact.result.length)
    assert run.gap_pct == pytest.approx(100 * (run.result.length / exact.result.length - 1))
    assert exact.gap_pct == 0.0 and exact.graph is None and run.graph is not None
    d = json.loads(json.dumps(run.to_dict()))
    assert d["world"] == "seed003" and d["start"] == [20.0, 20.0] and d["gap_pct"] > 0


def test_pso_gets_seed_and_stop(seed003):
    run = plan_against_optimum(seed003, "pso", (20, 20), (320, 320), seed=4,
                               stop=MaxGenerations(7))
    assert run.result.info["seed"] == 4 and run.result.history.generations == 7


def test_unknown_planner_lists_choices(seed003):
    with pytest.raises(ParameterError, match="dijkstra, improved"):
        plan_against_optimum(seed003, "astar", (20, 20), (320, 320))


def test_no_path_has_infinite_optimum():
    world = PolygonWorld((0, 0, 10, 10), ([[0, 4], [10, 4], [10, 6], [0, 6]],))
    run = plan_against_optimum(world, "visibility", (5, 2), (5, 8))
    assert not run.result.success and math.isinf(run.optimum) and run.gap_pct is None
    assert run.to_dict()["optimum"] is None
    assert "no collision-free path exists" in run.report_lines()[-1]


def test_load_world(tmp_path):
    assert load_world("seed003-listed").name == "seed003-listed"
    path = tmp_path / "mine.json"
    PolygonWorld((0, 0, 5, 5), ()).to_json(path)
    assert load_world(path).name == "mine"
    with pytest.raises(InputDataError, match="world must be one of"):
        load_world("moon")

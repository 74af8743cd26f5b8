"""The grid family under the one planner protocol: every registered planner
has the same signature, refuses what it cannot honour, and answers start ==
goal with a zero-length path."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.base import get_planner, planners
from subtask_opt.planners.grid import compare
from subtask_opt.planners.grid.maps import thesis_case
from subtask_opt.planners.grid.world import GridWorld

GRID = planners("grid")
EXPECTED = {"dt", "dt-octile", "mdt", "ga", "ga-paper", "vff", "vfh"}


def test_every_grid_planner_is_registered_once():
    assert set(GRID) == EXPECTED
    assert compare.planner_names() == tuple(GRID)
    assert {n for n, i in GRID.items() if i.stochastic} == {"ga", "ga-paper"}
    assert {n for n, i in GRID.items() if i.iterative} == {"ga", "ga-paper"}
    for info in GRID.values():
        assert info.description and info.family == "grid"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_protocol_signature(name):
    sig = inspect.signature(GRID[name].plan)
    assert list(sig.parameters)[:3] == ["world", "start", "goal"]
    for kw in ("params", "seed", "stop"):
        p = sig.parameters[kw]
        assert p.kind is inspect.Parameter.KEYWORD_ONLY and p.default is None


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_seed_and_stop_rules(name):
    info = GRID[name]
    case = thesis_case("open")
    if info.stochastic:
        res = info.plan(case.world, case.start, case.goal, seed=3, stop=MaxGenerations(3))
        assert res.history.generations == 3 and res.info["seed"] == 3
        with pytest.raises(ParameterError, match="seed"):
            info.plan(case.world, case.start, case.goal, seed=-1)
    else:
        with pytest.raises(ParameterError, match="deterministic"):
            info.plan(case.world, case.start, case.goal, seed=0)
        with pytest.raises(ParameterError, match="stop"):
            info.plan(case.world, case.start, case.goal, stop=MaxGenerations(3))


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_start_equals_goal_is_a_zero_length_success(name):
    world = GridWorld.from_ascii("...\n.#.\n...")
    res = GRID[name].plan(world, (2, 1), (2, 1))
    assert res.success and res.outcome == "success" and res.length == 0.0
    assert np.allclose(res.path, [2, 1])


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_cells_raise(name):
    world = GridWorld.from_ascii("...\n.#.\n...")
    with pytest.raises(UnreachableError, match=r"start \(1, 1\) is on an obstacle"):
        GRID[name].plan(world, (1, 1), (0, 0))
    with pytest.raises(UnreachableError, match="goal .* is outside"):
        GRID[name].plan(world, (0, 0), (3, 0))


def test_plan_grid_passes_seed_only_where_it_belongs():
    case = thesis_case("open")
    dt = compare.plan_grid(case.world, case.start, case.goal, "dt", seed=5)
    assert dt.success  # a deterministic planner is not handed the seed
    ga = compare.plan_grid(case.world, case.start, case.goal, "ga", seed=5,
                           stop=MaxGenerations(2))
    assert ga.info["seed"] == 5 and ga.history.generations == 2
    with pytest.raises(ParameterError, match="choose one of dt, dt-octile, mdt"):
        get_planner("grid", "astar")


def test_no_parameter_class_clashes_with_the_reactive_family():
    import subtask_opt.planners.grid.vff as grid_vff
    import subtask_opt.planners.grid.vfh as grid_vfh
    import subtask_opt.planners.reactive.baselines as reactive

    grid_names = set(grid_vff.__all__) | set(grid_vfh.__all__)
    reactive_names = {n for n in dir(reactive) if n.endswith("Params")}
    assert not grid_names & reactive_names


def test_plan_report_field_is_the_work_space():
    case = thesis_case("walls")  # bordered: 16 x 11
    rep = compare.plan_report(case.world, case.start, case.goal, "dt", border=case.border)
    assert rep.field is not None and rep.field.shape == (9, 14)
    d = rep.to_dict()
    assert len(d["field"]) == 9 and len(d["field"][0]) == 14
    x, y = case.goal[0] - 1, case.goal[1] - 1
    assert d["field"][y][x] == 0 and d["seed"] is None
    ga = compare.plan_report(case.world, case.start, case.goal, "ga", seed=2,
                             stop=MaxGenerations(2), warm_up=False)
    assert ga.field is None and "field" not in ga.to_dict() and ga.to_dict()["seed"] == 2

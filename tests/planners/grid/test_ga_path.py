"""GA path planner on the shared GA core: success rate and quality against the
MDT optimum, collision-freedom by an independent segment test, operator
invariants, reproducibility and parameter checks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.planners.grid import _waypoint_kernels as wp
from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid import ga_path
from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.grid.test_grid_oracles import path_free


@pytest.mark.parametrize("name", THESIS_MAPS)
def test_success_in_19_of_20_seeds_within_5_percent_of_mdt(name):
    case = thesis_case(name)
    best = dt.plan(case.world, case.start, case.goal, params=dt.DTParams("anyangle")).length
    good = 0
    for seed in range(20):
        res = ga_path.plan(case.world, case.start, case.goal, seed=seed)
        if res.success:
            # never through an obstacle, by an independent test
            assert path_free(case.world.occupancy, res.path)
            assert tuple(res.path[0]) == case.start and tuple(res.path[-1]) == case.goal
            assert res.length >= best - 1e-9  # the MDT is the any-angle optimum
            good += res.length <= 1.05 * best
    assert good >= 19, f"{name}: {good}/20"


def test_paper_preset_runs_the_thesis_ga_and_reports_failure_honestly():
    case = thesis_case("cluttered")
    res = ga_path.plan(case.world, case.start, case.goal, seed=0,
                       params=ga_path.GAPathParams.paper())
    assert res.planner == "ga-paper" and res.history.generations == 100
    if res.success:
        assert path_free(case.world.occupancy, res.path)
    else:
        assert "crosses obstacles" in res.message and res.path.shape == (0, 2)
    easy = thesis_case("open")
    res = ga_path.plan(easy.world, easy.start, easy.goal, seed=0,
                       params=ga_path.GAPathParams.paper())
    assert res.success and path_free(easy.world.occupancy, res.path)


def test_same_seed_same_result():
    case = thesis_case("rooms")
    a = ga_path.plan(case.world, case.start, case.goal, seed=7)
    b = ga_path.plan(case.world, case.start, case.goal, seed=7)
    assert np.array_equal(a.path, b.path)
    assert np.array_equal(a.history.best_cost, b.history.best_cost)


def test_no_path_gives_success_false():
    world = GridWorld.from_ascii("""
        .....
        .###.
        .#.#.
        .###.
    """)
    res = ga_path.plan(world, (0, 0), (2, 2), seed=0,
                       params=ga_path.GAPathParams(max_generations=5, init_tries=2))
    assert not res.success and res.length == float("inf")


def test_start_is_goal_bad_cells_and_big_grid():
    world = GridWorld.from_ascii("...\n.#.")
    assert ga_path.plan(world, (0, 0), (0, 0)).length == 0.0
    with pytest.raises(ParameterError, match="max_free_cells=2"):
        ga_path.plan(world, (0, 0), (2, 0), params=ga_path.GAPathParams(max_free_cells=2))
    with pytest.raises(UnreachableError, match="goal"):
        ga_path.plan(world, (0, 0), (1, 1))


@pytest.mark.parametrize("field, value", [
    ("population", 1), ("elite", 50), ("crossover_rate", 1.5), ("mutation_rate", -0.1),
    ("tournament", 1), ("max_generations", 0), ("stall_generations", 0), ("max_genes", 1),
    ("penalty", 0), ("init", "greedy"), ("init_tries", 0), ("shortcut", 1),
    ("max_free_cells", 0),
])
def test_params_validation_names_field(field, value):
    with pytest.raises(ParameterError, match=field):
        ga_path.GAPathParams(**{field: value})


# -- operator invariants (the numba kernels called directly) -------------------------
_CASE = thesis_case("cluttered")
_DATA = _CASE.world.occupancy.astype(np.float64)
_W = _CASE.world.width
_START = _CASE.start[1] * _W + _CASE.start[0]
_GOAL = _CASE.goal[1] * _W + _CASE.goal[0]


def _aux(init=wp.INIT_VISIBILITY):
    return wp.make_aux(_CASE.start, _CASE.goal, penalty=100.0, init=init, init_tries=5,
                       shortcut=True)


def _valid(genes, length, cap):
    assert 2 <= length <= cap
    assert genes[0] == _START and genes[length - 1] == _GOAL
    cells = genes[:length]
    assert np.all((cells >= 0) & (cells < _DATA.size))


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(4, 24), st.floats(0.0, 1.0))
def test_operators_keep_start_goal_and_capacity(seed, cap, strength):
    rng = np.random.default_rng(seed)
    aux = _aux(wp.INIT_VISIBILITY if seed % 2 else wp.INIT_RANDOM)
    a = np.zeros(cap, dtype=np.int64)
    b = np.zeros(cap, dtype=np.int64)
    la = wp.random_path(a, _DATA, aux, rng, a, 0)
    lb = wp.random_path(b, _DATA, aux, rng, a, 0)
    _valid(a, la, cap)
    _valid(b, lb, cap)
    child = np.zeros(cap, dtype=np.int64)
    lc = wp.one_point_crossover(a, la, b, lb, _DATA, aux, rng, child)
    _valid(child, lc, cap)
    lc = wp.nonuniform_mutation(child, lc, _DATA, aux, rng, strength)
    _valid(child, lc, cap)
    before = wp.path_cost(child, lc, _DATA, aux)
    lc = wp.shortcut(child, lc, _DATA, aux)
    _valid(child, lc, cap)
    assert wp.path_cost(child, lc, _DATA, aux) <= before + 1e-9


def test_cost_counts_blocked_cells():
    world = GridWorld.from_ascii("...\n.#.\n...")
    data = world.occupancy.astype(np.float64)
    aux = wp.make_aux((0, 1), (2, 1), penalty=10.0, init=0.0, init_tries=1, shortcut=False)
    genes = np.array([3, 5], dtype=np.int64)
    assert wp.path_cost(genes, 2, data, aux) == pytest.approx(2 + 10)
    genes = np.array([3, 0, 2, 5], dtype=np.int64)
    assert wp.path_cost(genes, 4, data, aux) == pytest.approx(1 + 2 + 1)


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(4, 9), st.integers(4, 9), st.floats(0.0, 0.4))
def test_reported_paths_never_cross_obstacles(seed, w, h, density):
    rng = np.random.default_rng(seed)
    occ = rng.random((h, w)) < density
    occ[0, 0] = occ[h - 1, w - 1] = False
    world = GridWorld(occ)
    params = ga_path.GAPathParams(population=10, max_generations=15, stall_generations=None,
                                  init_tries=3)
    for preset in (params, ga_path.GAPathParams.paper(population=10, max_generations=15)):
        res = ga_path.plan(world, (0, 0), (w - 1, h - 1), seed=seed, params=preset)
        reachable = np.isfinite(dt.distance_field(world, (w - 1, h - 1), "anyangle")[0, 0])
        if res.success:
            assert reachable and path_free(occ, res.path)

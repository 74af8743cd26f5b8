"""Elbow configurations chosen with the order: exact decoding and the GA against brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.arm.planar_problem import PlanarProblem, solve
from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import random_subtasks
from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.chromosomes import use
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.configurations import best_configurations, induced_matrix, pack_data
from subtask_opt.tour.solve import SolverParams
from tests.conftest import size

_ARMS: dict = {}


def _arm(name: str):
    if name not in _ARMS:
        _ARMS[name] = load_planar_arm(name)
    return _ARMS[name]


def _brute_force(t: np.ndarray) -> float:
    """Minimum over all cyclic orders (first subtask fixed) and all 2**N configurations."""
    n = t.shape[0]
    configs = np.array(list(itertools.product((0, 1), repeat=n)))  # (2**N, N)
    best = np.inf
    for rest in itertools.permutations(range(1, n)):
        order = np.array((0, *rest))
        nxt = np.roll(order, -1)
        c = configs[:, order]
        cost = t[order[None, :], c, nxt[None, :], np.roll(c, -1, axis=1)].sum(axis=1)
        best = min(best, float(cost.min()))
    return best


def _random_tensor(rng: np.random.Generator, n: int, p_inf: float = 0.0) -> np.ndarray:
    t = rng.uniform(0.1, 2.0, size=(n, 2, n, 2))
    t = 0.5 * (t + t.transpose(2, 3, 0, 1))
    for i in range(n):
        t[i, :, i, :] = 0.0
    if p_inf:
        dead = rng.random(n) < p_inf  # a subtask that one branch cannot reach
        for i in np.flatnonzero(dead):
            t[i, 1, :, :] = np.inf
            t[:, :, i, 1] = np.inf
    return t


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 7), st.integers(0, 2**32 - 1), st.booleans())
def test_decode_equals_brute_force_over_configurations(n: int, seed: int, dead: bool) -> None:
    rng = np.random.default_rng(seed)
    t = _random_tensor(rng, n, 0.3 if dead else 0.0)
    order = rng.permutation(n)
    cost, configs = best_configurations(order, t)
    nxt = np.roll(order, -1)
    brute = min(t[order, np.array(c)[order], nxt, np.array(c)[nxt]].sum()
                for c in itertools.product((0, 1), repeat=n))
    assert cost == pytest.approx(brute, rel=1e-12)
    assert induced_matrix(t, configs)[order, nxt].sum() == pytest.approx(cost, rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_ga_equals_brute_force_on_random_tensors(seed: int) -> None:
    t = _random_tensor(np.random.default_rng(seed), 8, p_inf=0.2)
    assert _ga_on_tensor(t, seed) == pytest.approx(_brute_force(t), rel=1e-12)


def _ga_on_tensor(t: np.ndarray, seed: int) -> float:
    """The configured-permutation GA run directly on a branch-time tensor."""
    from subtask_opt.base.stop import MaxGenerations, NoImprovement
    from subtask_opt.ga.config import GAConfig
    from subtask_opt.ga.kinds import Kind
    from subtask_opt.ga.loop import run_ga
    from subtask_opt.tour.permutation import SEARCH_FAST, make_aux, neighbour_table

    n = t.shape[0]
    data, _ = pack_data(t)
    aux = make_aux(neighbour_table(data.dist), nearest_fallback=True, search=SEARCH_FAST)
    out = run_ga(use(Kind.CONFIGURED_PERMUTATION), GAConfig(), data, aux, max_genes=n, seed=seed,
                 criteria=[NoImprovement(15), MaxGenerations(50_000)])
    cost, _ = best_configurations(out.genes, t)
    return cost


@pytest.mark.parametrize(("robot", "model", "n", "seed"), [
    ("planar_2r", "joint", 8, 0), ("asr_twodof", "joint", 8, 1),
    ("planar_2r", "line", size(7, 4), 2), ("asr_twodof", "line", size(8, 4), 3),
])
def test_joint_aware_solution_equals_brute_force(robot: str, model: str, n: int,
                                                 seed: int) -> None:
    arm = _arm(robot)
    problem = PlanarProblem(random_subtasks(arm, n, seed=seed), arm, time_model=model,
                            configurations="optimize")
    result = solve(problem, seed=seed)
    assert result.total_time == pytest.approx(_brute_force(problem.timing.branch_times),
                                              rel=1e-12)
    # the answer is consistent: configurations reach their subtasks, legs add up
    configs = result.report.configurations
    q = problem.timing.branch_joints[np.arange(n), configs]
    assert np.isfinite(q).all()
    np.testing.assert_allclose(result.leg_times,
                               result.matrix[result.order, np.roll(result.order, -1)])
    assert result.total_time == pytest.approx(result.leg_times.sum())
    assert result.total_time == pytest.approx(problem.tour_time(result.order))
    d = result.to_dict()["report"]
    assert d["configurations"] == configs.tolist()
    assert d["configurations_mode"] == "optimize" and len(d["leg_moves"]) == n


def test_optimizing_is_never_worse_than_a_fixed_branch() -> None:
    arm = _arm("planar_2r")
    s = random_subtasks(arm, 20, seed=4)
    fixed = solve(PlanarProblem(s, arm, time_model="joint", configurations="fixed"), seed=0)
    free = solve(PlanarProblem(s, arm, time_model="joint", configurations="optimize"),
                 seed=0)
    assert free.total_time <= fixed.total_time * (1 + 1e-12)
    assert free.report.configurations_mode == "optimize"
    assert fixed.report.configurations_mode == "fixed"


def test_same_seed_same_configured_result() -> None:
    arm = _arm("asr_twodof")
    problem = PlanarProblem(random_subtasks(arm, size(25, 6), seed=1), arm,
                            time_model="line", configurations="optimize")
    gens = MaxGenerations(size(60, 15))
    for params in (SolverParams(), SolverParams.paper()):
        a = solve(problem, seed=5, params=params, stop=gens)
        b = solve(problem, seed=5, params=params, stop=gens)
        np.testing.assert_array_equal(a.order, b.order)
        np.testing.assert_array_equal(a.report.configurations, b.report.configurations)
        np.testing.assert_array_equal(a.history.best_cost, b.history.best_cost)


def test_a_subtask_with_one_configuration_gets_it() -> None:
    arm = _arm("planar_2r")
    # (-0.545, -0.198) lies behind the base: the shoulder limit leaves only elbow-up.
    pts = np.array([[-0.545, -0.198], [0.3, 0.1], [0.4, -0.2], [0.25, 0.3]])
    assert np.isnan(arm.ik(pts[0])[0]).all() and np.isfinite(arm.ik(pts[0])[1]).all()
    problem = PlanarProblem(Targets(pts), arm, time_model="joint",
                            configurations="optimize")
    result = solve(problem, seed=0)
    assert result.report.configurations[0] == 1
    assert result.total_time == pytest.approx(_brute_force(problem.timing.branch_times))


def test_subtask_reachable_in_no_configuration_is_named() -> None:
    arm = _arm("asr_twodof")
    bx, by = arm.base_xy
    pts = np.array([[bx + 0.15, by], [bx, by + 0.15], [bx + 0.001, by]])  # inside the inner disc
    with pytest.raises(UnreachableError, match="subtask 2"):
        PlanarProblem(Targets(pts), arm, time_model="joint", configurations="optimize")


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"configurations": "sometimes"}, "configurations"),
    ({"configurations": "optimize", "time_model": "trapezoid"}, "joint or line"),
    ({"line_fallback": "hop", "time_model": "line"}, "line_fallback"),
])
def test_bad_configuration_options(kwargs: dict, match: str) -> None:
    arm = _arm("planar_2r")
    with pytest.raises(ParameterError, match=match):
        PlanarProblem(random_subtasks(arm, 4, seed=0), arm, **kwargs)


def test_bad_tensors_and_orders() -> None:
    t = _random_tensor(np.random.default_rng(0), 4)
    with pytest.raises(InputDataError, match="shape"):
        pack_data(np.zeros((4, 3, 4, 2)))
    with pytest.raises(InputDataError, match="NaN"):
        pack_data(np.where(t > 1.0, np.nan, t))
    with pytest.raises(ParameterError, match="permutation"):
        best_configurations([0, 1, 1, 2], t)

"""Sequencing API: optimality against exact oracles, reproducibility, validation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from subtask_opt import MaxGenerations, NoImprovement, SolverParams, TargetCost, builtin_case, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import random_subtasks
from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.exact import held_karp, milp_optimum
from subtask_opt.tour.problem import MatrixProblem
from subtask_opt.tour.solve import CONFIGURED_RUNS, proven_configured_optimum
from tests.conftest import size


def _euclidean(seed: int, n: int) -> np.ndarray:
    pts = np.random.default_rng(seed).random((n, 2))
    return np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))


@pytest.fixture(scope="module")
def arm():
    return load_planar_arm("planar_2r")


@pytest.mark.parametrize("seed", range(8))
def test_default_preset_matches_held_karp_on_small_instances(seed):
    n = 5 + seed
    m = _euclidean(seed, n)
    result = solve(MatrixProblem(m), seed=seed)
    assert result.total_time == pytest.approx(held_karp(m)[0], rel=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_default_preset_matches_held_karp_on_asymmetric_instances(seed):
    rng = np.random.default_rng(seed)
    m = rng.random((8, 8)) * 5
    np.fill_diagonal(m, 0)
    problem = MatrixProblem(m)
    assert not problem.symmetric
    result = solve(problem, seed=seed)
    assert result.total_time == pytest.approx(held_karp(m)[0], rel=1e-12)


def test_paper_preset_reaches_the_optimum_of_a_small_instance():
    m = _euclidean(11, 8)
    result = solve(MatrixProblem(m), seed=3, params=SolverParams.paper(),
                   stop=[MaxGenerations(3000)])
    assert result.total_time == pytest.approx(held_karp(m)[0], rel=1e-12)
    assert result.restarts > 0


@pytest.mark.parametrize(("case", "model"), [("square20", "trapezoid"), ("random30", "joint"),
                                             ("random30", "paper")])
def test_builtin_cases_reach_the_certified_optimum(arm, case, model):
    # fixed configurations: the MILP certifies the optimum of this very matrix
    problem = PlanarProblem(builtin_case(case, arm, seed=0), arm, time_model=model,
                            configurations="fixed")
    optimum, _ = milp_optimum(problem.matrix)
    result = solve(problem, seed=0)
    assert result.total_time == pytest.approx(optimum, rel=1e-9)


def test_result_is_consistent(arm):
    problem = PlanarProblem(builtin_case("square20", arm), arm, time_model="trapezoid",
                            first=7)
    r = solve(problem, seed=4, params=SolverParams(bound_max_nodes=0))  # no early bound stop
    assert r.order[0] == 7
    assert sorted(r.order.tolist()) == list(range(20))
    np.testing.assert_allclose(r.leg_times, problem.matrix[r.order, np.roll(r.order, -1)])
    assert r.total_time == pytest.approx(r.leg_times.sum())
    assert r.total_time == pytest.approx(problem.tour_time(r.order))
    assert r.history.generations == r.generations
    assert r.history.best_cost[-1] == pytest.approx(r.total_time)
    assert r.report.robot == "planar_2r" and r.report.time_model == "trapezoid"
    d = r.to_dict()
    assert d["order"][0] == 7 and len(d["matrix"]) == 20
    assert "total time" in r.summary()


def test_same_seed_same_result(arm):
    problem = PlanarProblem(builtin_case("random30", arm, seed=2), arm)
    for params in (SolverParams(), SolverParams.paper()):
        gens = MaxGenerations(size(200, 15))
        a = solve(problem, seed=9, params=params, stop=gens)
        b = solve(problem, seed=9, params=params, stop=gens)
        np.testing.assert_array_equal(a.order, b.order)
        np.testing.assert_array_equal(a.history.best_cost, b.history.best_cost)
        assert (a.generations, a.restarts) == (b.generations, b.restarts)


def test_choosing_configurations_makes_several_shorter_runs(arm):
    problem = PlanarProblem(builtin_case("random30", arm, seed=2), arm)
    assert problem.optimizes_configurations  # the default joint model chooses the elbows
    fixed_stall = SolverParams().default_stop(30)[0]
    stall = SolverParams().default_stop(30, configured=True)[0]
    assert isinstance(fixed_stall, NoImprovement) and isinstance(stall, NoImprovement)
    assert stall.generations == 2 * fixed_stall.generations // 3
    assert SolverParams().default_runs(30, configured=True) == CONFIGURED_RUNS > 1
    assert SolverParams().default_runs(30) == 1
    assert SolverParams(runs=3).default_runs(30, configured=True) == 3
    one = solve(problem, seed=0, params=SolverParams(bound_max_nodes=0, runs=1))
    assert one.generations - one.history.generation_of_best() == stall.generations
    several = solve(problem, seed=0, params=SolverParams(bound_max_nodes=0))
    # the first run is the same one: more runs can only find a shorter tour
    assert several.total_time <= one.total_time
    assert several.history.best_cost[one.generations - 1] == one.history.best_cost[-1]
    assert several.generations >= CONFIGURED_RUNS * stall.generations  # each run stalls
    assert (one.runs, several.runs) == (1, CONFIGURED_RUNS)
    assert several.to_dict()["runs"] == CONFIGURED_RUNS
    # from 100 nodes on every child carries kicks of its own: the stall stays
    assert SolverParams().default_stop(200, configured=True) == SolverParams().default_stop(200)


def test_the_default_stop_caps_the_generations_from_1000_nodes():
    from subtask_opt.tour.solve import generation_cap

    def cap(n: int) -> int:
        (limit,) = [c for c in SolverParams().default_stop(n) if isinstance(c, MaxGenerations)]
        return limit.generations

    assert [cap(n) for n in (30, 999, 1000, 1280, 1600, 3200, 20_000)] == [
        50_000, 50_000, 64, 50, 40, 20, 20]
    assert generation_cap(3200) == 20 and generation_cap(2400) == 26
    assert SolverParams.paper().default_stop(3200)[1] == MaxGenerations(50_000)


def test_stopping_criteria_are_honoured():
    m = _euclidean(5, 25)
    problem = MatrixProblem(m)
    assert solve(problem, seed=0, stop=MaxGenerations(17),
                 params=SolverParams.paper()).generations == 17
    r = solve(problem, seed=0, stop=[NoImprovement(5), MaxGenerations(10_000)])
    assert r.generations - r.history.generation_of_best() == 5
    loose = solve(problem, seed=0, stop=[TargetCost(1e9), MaxGenerations(100)])
    assert loose.generations <= 1


@pytest.mark.parametrize(("matrix", "match"), [
    (np.ones((3, 4)), "square"),
    (np.ones((2, 2)), "at least 3"),
    (np.array([[0, 1, np.nan], [1, 0, 1], [1, 1, 0]]), "from subtask 0 to 2"),
    (np.array([[0, 1, np.inf], [1, 0, 1], [1, 1, 0]]), "must be finite"),
    (np.array([[0, -1, 1], [1, 0, 1], [1, 1, 0.0]]), "negative"),
])
def test_bad_matrices_are_rejected(matrix, match):
    with pytest.raises(InputDataError, match=match):
        MatrixProblem(matrix)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"seed": -1}, "seed"), ({"seed": 1.5}, "seed"), ({"stop": []}, "at least one"),
    ({"stop": TargetCost(1.0)}, "TargetCost alone"),
])
def test_bad_solve_arguments_are_rejected(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        solve(MatrixProblem(_euclidean(0, 5)), **kwargs)


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"preset": "fast"}, "preset"), ({"population": 2}, "population"),
    ({"grasp_share": 2.0}, "grasp_share"), ({"max_segment": 0}, "max_segment"),
    ({"neighbours": 0}, "neighbours"), ({"convergence_tol": -1.0}, "convergence_tol"),
    ({"runs": 0}, "runs"), ({"runs": 1001}, "runs"), ({"runs": True}, "runs"),
    ({"runs": 2.0}, "runs"),
])
def test_bad_solver_params_name_the_field(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        SolverParams(**kwargs)


def test_bad_first_subtask_and_missing_inputs(arm):
    with pytest.raises(ParameterError, match="first"):
        MatrixProblem(_euclidean(0, 5), first=5)
    with pytest.raises(ParameterError, match="subtasks must be planar Targets"):
        PlanarProblem(None, arm)
    with pytest.raises(ParameterError, match="load_planar_arm"):
        PlanarProblem(builtin_case("square20", arm), "planar_2r")
    with pytest.raises(ParameterError, match="permutation"):
        MatrixProblem(_euclidean(0, 5)).tour_time(np.array([0, 1, 1, 2, 3]))


@pytest.mark.parametrize("seed", range(4))
def test_lower_bound_is_below_the_certified_optimum_and_the_answer(arm, seed):
    problem = PlanarProblem(random_subtasks(arm, 12 + seed, seed=seed), arm,
                            time_model="trapezoid")
    optimum, _ = milp_optimum(problem.matrix)
    result = solve(problem, seed=seed, certify=True)
    assert result.lower_bound is not None
    assert result.lower_bound <= optimum * (1 + 1e-12)
    assert optimum <= result.total_time * (1 + 1e-12) + 1e-12
    assert result.certified == "optimal (proven)"
    assert result.gap_bound == pytest.approx((result.total_time - result.lower_bound)
                                             / result.lower_bound)
    d = result.to_dict()
    assert d["lower_bound"] == result.lower_bound and d["gap_bound"] == result.gap_bound


def _gtsp_brute_force(problem) -> float:
    """Every cyclic order and every choice of reachable configurations."""
    t = problem.timing.branch_times
    reach = np.isfinite(problem.timing.branch_joints).all(axis=2)
    n = t.shape[0]
    combos = np.array(list(itertools.product(*[np.flatnonzero(reach[i]) for i in range(n)])))
    best = np.inf
    for rest in itertools.permutations(range(1, n)):
        if rest[0] > rest[-1]:  # symmetric legs: each cycle once
            continue
        o = (0, *rest)
        total = sum(t[o[k], combos[:, o[k]], o[(k + 1) % n], combos[:, o[(k + 1) % n]]]
                    for k in range(n))
        best = min(best, float(total.min()))
    return best


@pytest.mark.parametrize(("robot", "seed"), [("planar_2r", 3), ("asr_twodof", 4)])
def test_chosen_configurations_are_certified_against_brute_force(robot, seed):
    arm = load_planar_arm(robot)
    problem = PlanarProblem(random_subtasks(arm, 7, seed=seed), arm, time_model="joint")
    assert problem.optimizes_configurations
    optimum = _gtsp_brute_force(problem)
    result = solve(problem, seed=0, certify=True)
    assert result.lower_bound is not None and result.lower_bound <= result.total_time
    assert result.total_time == pytest.approx(optimum, rel=1e-12)
    assert result.certified == "optimal (proven)"
    # a poor incumbent (the index order, first reachable configurations) changes nothing
    first = np.argmax(np.isfinite(problem.timing.branch_joints).all(axis=2), axis=1)
    proven = proven_configured_optimum(problem.tour_problem, np.arange(7), first, 60.0)
    assert proven == pytest.approx(optimum, rel=1e-12)


def test_no_bound_above_the_size_limit(arm):
    problem = PlanarProblem(random_subtasks(arm, 12, seed=1), arm, time_model="trapezoid")
    result = solve(problem, seed=0, params=SolverParams(bound_max_nodes=0))
    assert result.lower_bound is None and result.gap_bound is None


@pytest.mark.parametrize(("robot", "model", "n", "seed"), [
    ("planar_2r", "trapezoid", 40, 0), ("asr_twodof", "joint", 40, 1),
    ("asr_twodof", "trapezoid", 60, 2), ("planar_2r", "joint", 60, 3),
])
def test_default_settings_reach_the_certified_optimum_of_new_40_and_60_subtask_sets(
        robot, model, n, seed):
    # held-out sets (not the built-in cases the defaults were tuned on); the MILP
    # certifies the optimum of the fixed-configuration matrix
    arm = load_planar_arm(robot)
    problem = PlanarProblem(random_subtasks(arm, n, seed=1000 + seed), arm, time_model=model,
                            configurations="fixed")
    optimum, _ = milp_optimum(problem.matrix)
    result = solve(problem, seed=seed)
    assert result.total_time == pytest.approx(optimum, rel=1e-9)


def test_report_checks_the_tour_legs_and_all_pairs_only_when_asked():
    arm = load_planar_arm("asr_twodof")
    subtasks = builtin_case("random30", arm, seed=1)
    problem = PlanarProblem(subtasks, arm, time_model="trapezoid")
    r = solve(problem, seed=0, stop=MaxGenerations(2))
    # oracle: the all-pairs check of the same problem read at the tour's legs
    check = problem.timing.leg_check
    a, b = r.order, np.roll(r.order, -1)
    impossible = check.outside_annulus[a, b]
    over = ~impossible & (check.speed_ratio[a, b] > 1)
    report = r.report.to_dict()
    assert [leg["leg"] for leg in report["infeasible_legs"]] == np.flatnonzero(
        impossible | over).tolist()
    assert report["tour_leg_check"]["n_impossible"] == int(impossible.sum()) > 0
    assert report["tour_leg_check"]["n_overspeed"] == int(over.sum())
    assert "all_pairs_leg_check" not in report["diagnostics"]
    asked = PlanarProblem(subtasks, arm, time_model="trapezoid", check_all_legs=True)
    diag = solve(asked, seed=0, stop=MaxGenerations(2)).report.diagnostics
    assert diag["all_pairs_leg_check"]["n_infeasible"] == check.n_infeasible
    with pytest.raises(ParameterError, match="check_all_legs"):
        PlanarProblem(subtasks, arm, time_model="trapezoid", check_all_legs=1)

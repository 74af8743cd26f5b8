"""The serial-arm sequencing pipeline: IK -> collision filter -> leg matrix -> GTSP ->
ruckig execution, on a UR5 drilling a tilted panel."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.arm.poses import make_targets
from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem
from subtask_opt.arm.trajectory import from_serial_report, validate
from subtask_opt.base.errors import InputDataError, NoPathError, ParameterError
from subtask_opt.cell.scene import Scene
from subtask_opt.kinematics.serial import load_serial_arm
from subtask_opt.tour.solve import SolverParams
from tests.conftest import size

HOME = np.radians([0, -90, 90, -90, -90, 0])
ROWS = np.array([[0.45, -0.15, 0.20, 1, 0, -0.3], [0.45, -0.05, 0.20, 1, 0, -0.3],
                 [0.45, 0.05, 0.20, 1, 0, -0.3], [0.45, 0.15, 0.20, 1, 0, -0.3],
                 [0.42, -0.10, 0.35, 1, 0, -0.3], [0.42, 0.00, 0.35, 1, 0, -0.3]])
PANEL = Scene.from_dict({"boxes": [{"name": "panel", "center": [0.55, 0.0, 0.28],
                                    "half_extents": [0.02, 0.3, 0.2]}]})


@pytest.fixture(scope="module")
def arm():
    return load_serial_arm("ur5", limits={"acceleration": [3.0] * 6})


@pytest.fixture(scope="module")
def solved(arm):
    # kernels as Python (coverage): a 90 degree axis step covers the same lines
    targets = make_targets(ROWS, standoff=0.01, axis_step=size(45.0, 90.0))
    problem = SerialProblem(targets, arm, HOME, scene=PANEL)
    return problem, solve_serial_problem(problem, seed=0).report


def test_result_is_consistent_and_executes(solved) -> None:
    problem, result = solved
    n = len(ROWS)
    assert sorted(result.order.tolist()) == list(range(n))
    assert result.configurations.shape == (n, 6)
    for i in range(n):
        np.testing.assert_array_equal(
            result.configurations[i], problem.configurations[i][result.configuration_index[i]])
    assert result.total_time == pytest.approx(result.leg_times.sum())
    assert result.collision_checked
    assert result.counts["legs_checked"] >= n + 1
    traj = from_serial_report(result)
    check = validate(traj, dt=0.005)
    assert check.ok, check.violations
    assert abs(traj.duration - result.total_time) <= 0.005 * result.total_time
    assert check.max_position_error <= 1e-5 and check.max_axis_error <= 1e-4
    assert check.collisions == 0


def test_answer_is_optimal_over_orders_and_configurations_of_checked_legs(solved) -> None:
    """Brute force over 4 of the targets with all their configurations (trapezoid times)."""
    problem, _ = solved
    arm = problem.arm
    targets = make_targets(ROWS[:4], standoff=0.01, axis_step=90.0)
    small = SerialProblem(targets, arm, HOME, check_collisions=False)
    result = solve_serial_problem(small, seed=3).report
    assert result.planned_time == pytest.approx(_brute_force(small), rel=1e-9)


def test_same_seed_same_answer(solved) -> None:
    problem, result = solved
    again = solve_serial_problem(problem, seed=0).report
    np.testing.assert_array_equal(again.order, result.order)
    assert again.total_time == result.total_time


def test_csv_header_and_duration(solved, tmp_path) -> None:
    problem, result = solved
    traj = from_serial_report(result)
    path = traj.to_csv(tmp_path / "t.csv", dt=0.05)
    lines = path.read_text().splitlines()
    assert lines[0] == "t,q1,q2,q3,q4,q5,q6,dq1,dq2,dq3,dq4,dq5,dq6,x,y,z"
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert table[-1, 0] == pytest.approx(result.total_time)
    # the tool tip column is FK of the joint columns
    np.testing.assert_allclose(table[3, 13:16], problem.arm.fk(table[3, 1:7])[:3, 3], atol=1e-8)


def test_bad_inputs_name_the_value(arm) -> None:
    targets = make_targets(ROWS[:2], standoff=0.01)
    with pytest.raises(InputDataError, match="home joint 2"):
        SerialProblem(targets, arm, np.radians([0, -400, 90, -90, -90, 0]))
    with pytest.raises(ParameterError, match="home must be 6"):
        SerialProblem(targets, arm, [0.0, 0.0])
    far = make_targets(np.array([[3.0, 0, 0.2, 1, 0, 0]]))
    with pytest.raises(InputDataError, match=r"target 0 \(row 1.*no IK solution"):
        SerialProblem(far, arm, HOME)
    with pytest.raises(InputDataError, match=r"target 0 .*no collision-free configuration"):
        SerialProblem(targets, arm, HOME, scene=Scene.from_dict(
            {"boxes": [{"name": "around_target_0", "center": [0.45, -0.15, 0.2],
                        "half_extents": [0.08, 0.06, 0.08]}]}))
    with pytest.raises(InputDataError, match="in collision"):
        SerialProblem(targets, arm, HOME, scene=Scene.from_dict(
            {"boxes": [{"name": "block", "center": [0.0, 0.0, 0.4],
                        "half_extents": [0.3, 0.3, 0.3]}]}))


class _BlockingChecker:
    """Stands in for the collision checker: a leg collides iff its two end configurations
    are in ``legs`` (pairs of joint vectors, either way round); configurations never do."""

    def __init__(self, legs) -> None:
        self.legs = [(np.asarray(a), np.asarray(b)) for a, b in legs]
        self.calls = 0

    def leg_in_collision(self, q0, q1, clearance) -> bool:
        self.calls += 1
        return any((np.array_equal(q0, a) and np.array_equal(q1, b))
                   or (np.array_equal(q0, b) and np.array_equal(q1, a)) for a, b in self.legs)


def _small_problem(arm, rows=4):
    targets = make_targets(ROWS[:rows], standoff=0.01, axis_step=90.0)
    return SerialProblem(targets, arm, HOME, check_collisions=False)


def _brute_force(problem, blocked=()):
    """Shortest home-to-home tour (trapezoid times) over every order and configuration
    without the ``blocked`` legs (pairs of flat configuration indices, either way round):
    for each order, the sum of the legs of every configuration tuple at once."""
    legs = problem.legs.copy()
    for a, b in blocked:
        legs[a, b] = legs[b, a] = math.inf
    off = problem.offsets
    n = problem.size
    best = math.inf
    for perm in itertools.permutations(range(n)):
        idx = [np.arange(off[i], off[i + 1]) for i in perm]
        total = problem.home_out[idx[0]].reshape((-1,) + (1,) * (n - 1))
        for k in range(1, n):
            shape = [1] * n
            shape[k - 1], shape[k] = idx[k - 1].size, idx[k].size
            total = total + legs[np.ix_(idx[k - 1], idx[k])].reshape(shape)
        last = [1] * n
        last[-1] = idx[-1].size
        total = total + problem.home_in[idx[-1]].reshape(last)
        best = min(best, float(total.min()))
    return best


def test_blocked_legs_are_avoided_and_the_answer_is_optimal_without_them(arm) -> None:
    """Every target-to-target leg of the unchecked answer collides: the GA blocks each as a
    new best tour meets it and searches on (no repair, no second search); brute force over
    the legs left is the oracle."""
    problem = _small_problem(arm)
    legs_before = problem.legs.copy()
    free = solve_serial_problem(problem, seed=0).report
    path = free.tour_configurations()[1:-1]
    blocked = list(zip(path[:-1], path[1:], strict=True))
    checker = _BlockingChecker(blocked)
    object.__setattr__(problem, "checker", checker)
    object.__setattr__(problem, "detours", False)  # forbidding, as --no-detours
    result = solve_serial_problem(problem, seed=0).report
    chosen = result.tour_configurations()[1:-1]
    assert not any(checker.leg_in_collision(a, b, 0.01)
                   for a, b in zip(chosen[:-1], chosen[1:], strict=True))
    assert result.counts["legs_infeasible"] == len(blocked)
    assert result.counts["search_rounds"] == result.counts["ga_rounds"] == 1

    flat = problem.flat
    pairs = [(a, b) for a in range(len(flat)) for b in range(a + 1, len(flat))
             if checker.leg_in_collision(flat[a], flat[b], 0.01)]
    assert len(pairs) == len(blocked)
    assert result.planned_time == pytest.approx(_brute_force(problem, pairs), rel=1e-9)
    assert result.planned_time > free.planned_time
    # the blocked legs were restored
    np.testing.assert_array_equal(problem.legs, legs_before)
    again = solve_serial_problem(problem, seed=0).report
    np.testing.assert_array_equal(again.order, result.order)
    np.testing.assert_array_equal(again.configuration_index, result.configuration_index)


def test_no_collision_free_tour_raises_and_restores_the_legs(arm) -> None:
    targets = make_targets(ROWS[:2], standoff=0.01, axis_step=180.0)
    problem = SerialProblem(targets, arm, HOME, check_collisions=False)
    legs_before = problem.legs.copy()
    # every leg between the two targets collides: no tour is left
    a, b = problem.configurations
    object.__setattr__(problem, "checker", _BlockingChecker(
        [(qa, qb) for qa in a for qb in b]))
    object.__setattr__(problem, "detours", False)  # forbidding, as --no-detours
    with pytest.raises(NoPathError, match="no tour avoids the legs in collision"):
        solve_serial_problem(problem, seed=0)
    np.testing.assert_array_equal(problem.legs, legs_before)


@pytest.mark.parametrize("kicks", [-1, 1001, 2.5, True])
def test_bad_kicks_name_the_value(solved, kicks) -> None:
    problem, _ = solved
    with pytest.raises(ParameterError, match=rf"kicks must be an integer in \[0, 1000\], "
                                             rf"got {kicks!r}"):
        solve_serial_problem(problem, params=SolverParams(kicks=kicks))


def test_kicks_zero_still_reaches_the_optimum(arm) -> None:
    problem = _small_problem(arm)
    result = solve_serial_problem(problem, seed=1, params=SolverParams(kicks=0)).report
    assert result.planned_time == pytest.approx(_brute_force(problem), rel=1e-9)


def test_search_limit_keeps_the_answer_or_raises(arm, monkeypatch) -> None:
    """With one GA search allowed, its answer stands (collision-free: the GA checks its new
    bests); with no collision-free tour the limit raises."""
    import subtask_opt.tour.lazy as lazy

    monkeypatch.setattr(lazy, "MAX_ROUNDS", 1)
    problem = _small_problem(arm)
    path = solve_serial_problem(problem, seed=0).report.tour_configurations()[1:-1]
    checker = _BlockingChecker(list(zip(path[:-1], path[1:], strict=True)))
    object.__setattr__(problem, "checker", checker)
    object.__setattr__(problem, "detours", False)
    result = solve_serial_problem(problem, seed=0).report
    assert result.counts["ga_rounds"] == result.counts["search_rounds"] == 1
    chosen = result.tour_configurations()
    assert not any(checker.leg_in_collision(a, b, 0.01)
                   for a, b in zip(chosen[:-1], chosen[1:], strict=True))

    targets = make_targets(ROWS[:2], standoff=0.01, axis_step=180.0)
    blocked = SerialProblem(targets, arm, HOME, check_collisions=False)
    a, b = blocked.configurations
    object.__setattr__(blocked, "checker", _BlockingChecker(
        [(qa, qb) for qa in a for qb in b]))
    object.__setattr__(blocked, "detours", False)
    # the GA met every leg in collision while it searched: its answer is still blocked
    with pytest.raises(NoPathError, match="no tour avoids the legs in collision"):
        solve_serial_problem(blocked, seed=0)


def test_cpu_split_reports_compilation_apart(solved) -> None:
    # every phase is timed; numba's compile (or cache load) is its own entry, not search
    _, result = solved
    assert set(result.cpu) == {"ik", "collision", "matrix", "search", "compile", "planner"}
    assert all(v >= 0.0 for v in result.cpu.values())


def test_the_planned_leg_time_is_the_executed_one_with_jerk_limits() -> None:
    """The joint model the search optimises is ruckig's jerk-limited time-synchronised
    move (the Panda has jerk limits), not a trapezoid that ignores them."""
    from subtask_opt.kinematics.joint_moves import (
        joint_leg_times,
        joint_limits,
        ruckig_leg_time,
    )
    from subtask_opt.kinematics.serial import load_serial_arm

    arm = load_serial_arm("panda")
    lim = arm.limits
    assert lim.jerk is not None
    model = joint_limits(lim.velocity, lim.acceleration, lim.jerk)
    rng = np.random.default_rng(11)
    qa = rng.uniform(lim.lower, lim.upper, (40, 7))
    qb = np.clip(qa + rng.normal(0, 0.4, (40, 7)) * rng.random((40, 1)), lim.lower, lim.upper)
    planned = np.array([joint_leg_times(a, b, model)[0, 0]
                        for a, b in zip(qa, qb, strict=True)])
    executed = np.array([ruckig_leg_time(a, b, lim.velocity, lim.acceleration, lim.jerk)
                         for a, b in zip(qa, qb, strict=True)])
    np.testing.assert_allclose(planned, executed, rtol=1e-6)
    without = np.array([joint_leg_times(a, b, joint_limits(lim.velocity,
                                                                lim.acceleration))[0, 0]
                        for a, b in zip(qa, qb, strict=True)])
    assert np.all(without <= executed * (1 + 1e-9)) and np.any(without < 0.99 * executed)


@pytest.mark.parametrize("phase", [True, False])
def test_executed_joint_moves_take_the_planned_time(phase: bool) -> None:
    """ruckig's executed move against the closed forms, random limits with and without
    jerk: phase-synchronised (serial arms) it is the straight line and takes
    joint_leg_times; time-synchronised (planar arms) it takes the slowest joint's own time
    and never longer; either way every joint goes monotonically from start to goal."""
    from subtask_opt.kinematics._kernels import scurve_time_nb, trapezoid_time_nb
    from subtask_opt.kinematics.joint_moves import joint_leg_times, joint_limits, joint_move

    rng = np.random.default_rng(5)
    for k in range(60):
        n = int(rng.integers(2, 8))
        v, a = rng.uniform(0.3, 3.5, n), rng.uniform(0.5, 15.0, n)
        jerk = rng.uniform(2.0, 300.0, n) if k % 2 else None
        q0 = rng.uniform(-3, 3, n)
        q1 = q0 + rng.uniform(-3, 3, n) * (rng.random(n) < 0.8)
        move = joint_move(q0, q1, v, a, jerk, phase=phase)
        straight = joint_leg_times(q0, q1, joint_limits(v, a, jerk))[0, 0]
        d = np.abs(q1 - q0)
        own = max(scurve_time_nb(d[i], v[i], a[i], jerk[i]) if jerk is not None
                  else trapezoid_time_nb(d[i], v[i], a[i]) for i in range(n))
        assert move.duration == pytest.approx(straight if phase else own, rel=1e-9, abs=1e-12)
        assert own <= straight * (1 + 1e-12)
        q, qd, _ = move.states(np.linspace(0.0, move.duration, 301))
        towards = np.sign(q1 - q0)
        assert np.all(qd * towards >= -1e-12)
        assert np.all((q - q0) * towards >= -1e-12) and np.all((q1 - q) * towards >= -1e-12)
        if phase and d.any():  # on the line: every joint at the same fraction of its way
            i = int(np.argmax(d))
            share = (q[:, i] - q0[i]) / (q1[i] - q0[i])
            np.testing.assert_allclose(q, q0 + share[:, None] * (q1 - q0), atol=1e-12)


def test_serial_search_defaults_from_kicks_from_targets() -> None:
    from subtask_opt.base.stop import NoImprovement
    from subtask_opt.tour.lazy import LAZY_KICKS, LAZY_STALL_SHARE, _search_defaults
    from subtask_opt.tour.permutation import KICKS_FROM
    from subtask_opt.tour.solve import SolverParams

    params = SolverParams()

    def stall(criteria):
        return next(c.generations for c in criteria if isinstance(c, NoImprovement))

    small, kicks = _search_defaults(params, KICKS_FROM - 1)
    assert kicks is None and stall(small) == stall(params.default_stop(KICKS_FROM - 1))
    n = 2 * KICKS_FROM + 45
    large, kicks = _search_defaults(params, n)
    assert kicks == LAZY_KICKS
    assert stall(large) == round(stall(params.default_stop(n)) * LAZY_STALL_SHARE)
    assert _search_defaults(SolverParams(kicks=7), n)[1] == 7  # given kicks are kept
    paper = SolverParams(preset="paper")
    assert _search_defaults(paper, n) == (paper.default_stop(n), None)

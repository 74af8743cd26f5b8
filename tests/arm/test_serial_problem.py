"""The serial-arm sequencing pipeline: IK -> collision filter -> leg matrix -> GTSP ->
ruckig execution, on a UR5 drilling a tilted panel."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.arm.poses import make_targets
from subtask_opt.arm.scene import Scene
from subtask_opt.arm.serial import load_serial_arm
from subtask_opt.arm.serial_problem import SerialProblem, solve_serial
from subtask_opt.arm.serial_trajectory import serial_trajectory, validate_serial_trajectory
from subtask_opt.base.errors import InputDataError, ParameterError
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
    return problem, solve_serial(problem, seed=0)


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
    traj = serial_trajectory(problem, result)
    check = validate_serial_trajectory(traj, result, dt=0.005)
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
    result = solve_serial(small, seed=3)
    off = small.offsets
    best = math.inf
    for perm in itertools.permutations(range(4)):
        for choice in itertools.product(*[range(off[i], off[i + 1]) for i in perm]):
            c = np.array(choice)
            best = min(best, small.home_out[c[0]] + small.legs[c[:-1], c[1:]].sum()
                       + small.home_in[c[-1]])
    assert result.planned_time == pytest.approx(best, rel=1e-9)


def test_same_seed_same_answer(solved) -> None:
    problem, result = solved
    again = solve_serial(problem, seed=0)
    np.testing.assert_array_equal(again.order, result.order)
    assert again.total_time == result.total_time


def test_csv_header_and_duration(solved, tmp_path) -> None:
    problem, result = solved
    traj = serial_trajectory(problem, result)
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

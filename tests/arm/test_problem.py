"""One API for every arm: load_robot, load_targets, ArmProblem, solve, trajectory, validate.

Oracles: brute force over every order and (by a layered shortest path) every configuration
for the certificate and the lower bound; positions in the order for precedence and ends;
the trajectory's own states for where an open path ends.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest

import subtask_opt as so
from subtask_opt.arm.trajectory import HOME as AT_HOME
from subtask_opt.cli import main
from subtask_opt.kinematics.joint_moves import joint_leg_times

DATA = Path(__file__).resolve().parents[2] / "examples" / "data"
CASE = DATA / "ur5_panel.csv"
SCENE = DATA / "ur5_panel_scene.json"
HOME = np.radians([0, -90, 90, -90, -90, 0])


@pytest.fixture(scope="module")
def ur5() -> so.Robot:
    return so.load_robot("ur5")


def _subset(tmp_path: Path, rows: int) -> Path:
    lines = CASE.read_text().splitlines()
    path = tmp_path / f"holes{rows}.csv"
    path.write_text("\n".join(lines[:rows + 1]) + "\n")
    return path


@pytest.fixture(scope="module")
def panel(ur5: so.Robot) -> so.ArmProblem:
    return so.ArmProblem(so.load_targets(CASE, standoff=0.01), ur5, scene=SCENE, home=HOME)


def test_the_readme_example_runs_for_a_ur5_and_a_planar_arm(panel, tmp_path) -> None:
    result = so.solve(panel, seed=0,
                      constraints=so.TourConstraints(tour="open", precedence=[(0, 5)]))
    assert result.configurations.shape == (20, 6)
    assert result.lower_bound <= result.total_time
    check = so.validate(so.trajectory(result))
    assert check.ok, check.violations
    assert set(result.cpu) >= {"ik", "collision", "matrix", "search", "compile"}

    points = tmp_path / "points.csv"
    planar = so.load_robot("planar_2r")
    so.save_subtasks(so.builtin_case("random30", planar.model, seed=0), points)
    problem = so.ArmProblem(so.load_targets(points), planar)
    result = so.solve(problem, seed=0, constraints=so.TourConstraints(precedence=[(0, 5)]))
    order = list(result.order)
    assert order.index(0) < order.index(5)
    assert result.configurations.shape == (30, 2)
    # the joint angles reach the subtasks (planar forward kinematics)
    fk = np.array([planar.model.fk(q) for q in result.configurations])
    np.testing.assert_allclose(fk[:, :2], problem.targets.points, atol=1e-9)
    assert so.validate(so.trajectory(result)).ok


def test_open_tour_from_home_has_n_legs_and_ends_at_its_last_target(panel) -> None:
    result = so.solve(panel, seed=1, constraints=so.TourConstraints(tour="open"))
    assert result.leg_times.shape == (20,)
    traj = so.trajectory(result)
    q_start, q_end = traj.states([0.0, traj.duration])[0]
    np.testing.assert_allclose(q_start, HOME, atol=1e-12)
    np.testing.assert_allclose(q_end, result.configurations[result.order[-1]], atol=1e-9)
    assert traj.legs[0].from_stop == AT_HOME and traj.legs[-1].to_stop == result.order[-1]
    assert traj.duration == pytest.approx(result.total_time, rel=5e-3)
    closed = so.solve(panel, seed=1)
    assert closed.leg_times.shape == (21,)
    # dropping the return leg of the closed tour gives an open path: the open search
    # may not be worse than that
    assert result.total_time <= closed.total_time - closed.leg_times[-1] + 1e-9


@pytest.mark.parametrize("tour", ["closed", "open"])
def test_precedence_first_and_last_targets_hold(panel, tour) -> None:
    rng = np.random.default_rng(7)
    pairs = []
    for _ in range(8):  # pairs a -> b with a < b in a random relabelling: acyclic
        a, b = sorted(rng.choice(20, 2, replace=False))
        pairs.append((int(a), int(b)))
    constraints = so.TourConstraints(tour=tour, start=3, end=17, precedence=pairs)
    result = so.solve(panel, seed=2, constraints=constraints)
    pos = {int(t): k for k, t in enumerate(result.order)}
    assert sorted(pos) == list(range(20))
    assert all(pos[a] < pos[b] for a, b in pairs)
    assert result.order[0] == 3 and result.order[-1] == 17
    assert result.lower_bound <= result.total_time
    assert so.validate(so.trajectory(result)).ok


def _brute_force_planned(problem, pairs=(), open_path=False) -> float:
    """Minimum planned time over every order (keeping ``pairs``) and every configuration
    (a layered shortest path per order) of a tour from home: back home, or ``open_path``."""
    serial = problem.compiled
    layers = serial.configurations
    lim = serial.limits
    legs = {(i, j): joint_leg_times(layers[i], layers[j], lim)
            for i in range(len(layers)) for j in range(len(layers)) if i != j}
    out = [joint_leg_times(serial.home, q, lim)[0] for q in layers]
    best = np.inf
    for order in itertools.permutations(range(len(layers))):
        pos = {t: k for k, t in enumerate(order)}
        if any(pos[a] > pos[b] for a, b in pairs):
            continue
        cost = out[order[0]].copy()
        for a, b in itertools.pairwise(order):
            cost = np.min(cost[:, None] + legs[a, b], axis=0)
        best = min(best, float(np.min(cost if open_path else cost + out[order[-1]])))
    return best


@pytest.mark.parametrize(("tour", "pairs"), [("closed", ()), ("open", ()),
                                             ("closed", ((1, 0), (4, 2)))])
def test_certify_on_seven_targets_proves_the_brute_force_optimum(ur5, tmp_path, tour,
                                                                 pairs) -> None:
    problem = so.ArmProblem(so.load_targets(_subset(tmp_path, 7), standoff=0.01), ur5,
                            scene=SCENE, home=HOME)
    result = so.solve(problem, seed=0, certify=True,
                      constraints=so.TourConstraints(tour=tour, precedence=pairs))
    assert result.report.counts["legs_infeasible"] == 0  # the oracle knows no collisions
    optimum = _brute_force_planned(problem, pairs, open_path=tour == "open")
    assert result.lower_bound <= optimum * (1 + 1e-12)
    planned = result.report.planned_time
    assert planned >= optimum * (1 - 1e-9)
    # the clustered GA (with pairs: the pinned clustered one) finds the optimum of 7 targets
    assert planned == pytest.approx(optimum, rel=1e-9)
    # the certificate says what the oracle says, for the answer it was given
    expected = ("optimal (proven, planned times)" if planned <= optimum * (1 + 1e-9) else
                f"not optimal: the proven optimum of the planned times is {optimum:.6g} "
                f"({100 * (planned / optimum - 1):.4f}% less)")
    assert result.certified == expected


def test_same_seed_same_serial_answer_and_the_cli_gives_the_api_answer(panel, tmp_path) -> None:
    constraints = so.TourConstraints(tour="open", start=2)
    a = so.solve(panel, seed=5, constraints=constraints)
    b = so.solve(panel, seed=5, constraints=constraints)
    assert np.array_equal(a.order, b.order) and a.total_time == b.total_time
    out = tmp_path / "r.json"
    code = main(["solve", "--robot", "ur5", "--case", str(CASE), "--standoff", "0.01",
                 "--scene", str(SCENE), "--home", "0,-90,90,-90,-90,0", "--tour", "open",
                 "--first", "2", "--seed", "5", "--json", str(out), "--quiet"])
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["order"] == [int(i) for i in a.order]
    assert doc["total_time"] == a.total_time
    assert doc["robot"] == "ur5" and doc["time_model"] == "joint"


def test_speed_scale_scales_the_limits_the_trajectory_keeps(ur5) -> None:
    slow = ur5.with_limits(speed_scale=0.5, accel_scale=0.25)
    np.testing.assert_allclose(slow.model.limits.velocity, 0.5 * ur5.model.limits.velocity)
    np.testing.assert_allclose(slow.model.limits.acceleration,
                               0.25 * ur5.model.limits.acceleration)
    with pytest.raises(so.ParameterError, match="speed_scale"):
        ur5.with_limits(speed_scale=1.5)


@pytest.mark.parametrize(("robot", "option", "value"), [
    ("ur5", "time_model", "line"), ("ur5", "elbow", 1), ("ur5", "k", 0.2),
    ("ur5", "first", 3), ("planar_2r", "scene", str(SCENE)),
    ("planar_2r", "clearance", 0.02),
])
def test_an_option_for_the_other_kind_of_robot_is_refused(robot, option, value,
                                                          tmp_path) -> None:
    r = so.load_robot(robot)
    if r.planar:
        targets = so.builtin_case("square20", r.model)
    else:
        targets = so.load_targets(_subset(tmp_path, 4))
    with pytest.raises(so.ParameterError, match=option):
        so.ArmProblem(targets, r, home=None if r.planar else HOME, **{option: value})


def test_load_targets_refuses_3d_options_for_planar_points(tmp_path) -> None:
    points = tmp_path / "p.csv"
    points.write_text("x,y\n0.3,0.1\n0.2,0.3\n0.1,0.4\n")
    assert isinstance(so.load_targets(points), so.Targets)
    with pytest.raises(so.ParameterError, match="standoff"):
        so.load_targets(points, standoff=0.01)
    with pytest.raises(so.ParameterError, match="tool_frame"):
        so.load_robot("planar_2r", tool_frame="tool0")


def test_a_ur5_batch_of_two_files_equals_the_two_solo_runs(ur5, tmp_path) -> None:
    from subtask_opt.batch import load_jobs, solve_many

    lines = CASE.read_text().splitlines()
    files = []
    for k, rows in enumerate((lines[1:8], lines[8:16])):
        path = tmp_path / f"part{k}.csv"
        path.write_text("\n".join([lines[0], *rows]) + "\n")
        files.append(path)
    jobs = load_jobs(files, robot="ur5", scene=str(SCENE), home=(0, -90, 90, -90, -90, 0),
                     standoff=0.01)
    results = solve_many(jobs, seeds=3, workers=0)
    for path, got in zip(files, results, strict=True):
        solo = so.solve(so.ArmProblem(so.load_targets(path, standoff=0.01), ur5, scene=SCENE,
                                      home=HOME), seed=3)
        assert got.success, got.error
        assert got.order == tuple(int(i) for i in solo.order)
        assert got.total_time == solo.total_time
    with pytest.raises(so.ParameterError, match="elbow applies to planar"):
        load_jobs(files[:1], robot="ur5", elbow=1)


@pytest.mark.parametrize("tour", ["closed", "open"])
@pytest.mark.parametrize("branch", [0, 1])
def test_a_planar_home_configuration_is_the_brute_force_optimum_from_it(tour, branch) -> None:
    """A home given as joints: the tour starts in that elbow; checked against every order
    and every elbow of the targets, from the home built as a subtask by hand."""
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.targets import Targets
    from subtask_opt.arm.tasks import random_subtasks

    robot = so.load_robot("planar_2r")
    arm = robot.model
    targets = random_subtasks(arm, 5, seed=11)
    point = np.array([0.35, 0.2])
    q = arm.ik(point)[branch]
    result = so.solve(so.ArmProblem(targets, robot, home=so.Joints(q)), seed=0,
                      constraints=so.TourConstraints(tour=tour))
    by_hand = PlanarProblem(Targets(np.vstack([targets.points, point])), arm)
    t = by_hand.timing.branch_times  # (6, 2, 6, 2)
    h = 5
    best = np.inf
    for order in itertools.permutations(range(5)):
        for elbows in itertools.product((0, 1), repeat=5):
            c = dict(zip(order, elbows, strict=True))
            cost = t[h, branch, order[0], c[order[0]]] + sum(
                t[a, c[a], b, c[b]] for a, b in zip(order[:-1], order[1:], strict=True))
            if tour == "closed":
                cost += t[order[-1], c[order[-1]], h, branch]
            best = min(best, cost)
    assert result.total_time == pytest.approx(best, rel=1e-9)
    trajectory = so.trajectory(result)
    np.testing.assert_allclose(trajectory.states([0.0])[0][0], q, atol=1e-12)
    assert so.validate(trajectory).ok


def test_a_planar_home_configuration_is_checked() -> None:
    robot = so.load_robot("planar_2r")
    targets = so.builtin_case("square20", robot.model)
    up = so.Joints(robot.model.ik(np.array([0.35, 0.2]))[1])
    with pytest.raises(so.ParameterError, match="elbow up .* fixed configurations"):
        so.solve(so.ArmProblem(targets, robot, home=up, configurations="fixed"), seed=0)
    with pytest.raises(so.InputDataError, match="outside the joint limits"):
        so.ArmProblem(targets, robot, home=so.Joints([3.0, 0.0]))
    with pytest.raises(so.ParameterError, match="2 joint values"):
        so.ArmProblem(targets, robot, home=so.Joints([0.1, 0.2, 0.3]))
    with pytest.raises(so.ParameterError, match="finite joint values"):
        so.Joints([np.nan, 0.0])

"""Executable trajectories of solved tours: validity, duration, sampling, CSV, figures."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from subtask_opt.arm.planar_problem import PlanarProblem, solve
from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import builtin_case, random_subtasks
from subtask_opt.arm.trajectory import HOME, Trajectory, build_trajectory, validate
from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.kinematics.planar import JointLimits, load_planar_arm
from subtask_opt.tour.problem import MatrixProblem
from tests.conftest import REDUCED, size

_ARMS: dict = {}


def _arm(name: str):
    if name not in _ARMS:
        _ARMS[name] = load_planar_arm(name)
    return _ARMS[name]


def _solved(robot: str, case: str, model: str):
    arm = _arm(robot)
    configurations = "optimize" if model in ("joint", "line") else "fixed"
    subtasks = builtin_case(case, arm, seed=0)
    if REDUCED:  # the first 5 subtasks of the case: the same kinds of legs, fewer of them
        subtasks = Targets(subtasks.points[:5], name=subtasks.name)
    problem = PlanarProblem(subtasks, arm, time_model=model, configurations=configurations)
    return problem, solve(problem, seed=0)


@pytest.mark.parametrize("robot", ["planar_2r", "asr_twodof"])
@pytest.mark.parametrize("case", ["square20", "random30"])
@pytest.mark.parametrize("model", ["joint", "line", "trapezoid", "paper"])
def test_every_tour_executes_within_the_limits(robot: str, case: str, model: str) -> None:
    problem, result = _solved(robot, case, model)
    trajectory = build_trajectory(result)
    report = validate(trajectory, dt=2e-3)
    assert report.ok, report.violations
    assert max(report.max_velocity_ratio) <= 1 + report.rtol
    if problem.arm.joint_limits.jerk is None:
        assert report.max_jerk_ratio is None and "jerk not checked" in report.summary()
    else:  # jerk checked by finite differences, on every kind of leg
        assert report.max_jerk_ratio is not None
        assert max(report.max_jerk_ratio) <= 1 + report.jtol
    assert report.position_margin >= -report.qtol
    if model in ("joint", "line"):  # executed as timed: the promised time, to round-off
        assert trajectory.duration == pytest.approx(result.total_time, rel=1e-6)
        assert report.duration_error < 5e-3
    else:  # a Cartesian model's lines, driven within the joint limits
        assert all(leg.kind in ("line", "joint") for leg in trajectory.legs)
    # rest at every subtask, in the chosen configuration, with the tip on the subtask
    pts = problem.subtasks.points
    for leg in trajectory.legs:
        q, qd, _ = trajectory.states([leg.start])
        np.testing.assert_allclose(q[0], leg.q_from, atol=1e-9)
        np.testing.assert_allclose(qd[0], 0.0, atol=1e-6)
        np.testing.assert_allclose(_arm(robot).fk(q[0])[:2], pts[leg.from_stop], atol=1e-9)
        assert leg.from_config == result.report.configurations[leg.from_stop]


def test_joint_moves_are_jerk_limited_when_the_arm_has_jerk_limits() -> None:
    problem, result = _solved("planar_2r", "square20", "joint")
    trajectory = build_trajectory(result)
    s = trajectory.sample(1e-3)
    jerk = np.abs(np.diff(s.qdd, axis=0)) / 1e-3
    # finite differences of a piecewise-linear acceleration: at most the jerk limit (+ a step)
    assert np.all(jerk.max(axis=0) <= problem.arm.joint_limits.jerk * 1.01)
    arm = _arm("asr_twodof")
    assert arm.joint_limits.jerk is None  # asr_twodof: trapezoids, acceleration steps allowed


@pytest.mark.parametrize("robot", ["asr_twodof", "planar_2r"])
def test_line_legs_follow_the_straight_line_and_are_consistent(robot: str) -> None:
    problem, result = _solved(robot, "random30", "line")
    trajectory = build_trajectory(result)
    legs = [leg for leg in trajectory.legs if leg.kind == "line"]
    assert legs
    arm = problem.arm
    pts = problem.subtasks.points
    # reduced case: other legs; without jerk limits their acceleration steps need a finer grid
    samples = size(401, 401 if arm.joint_limits.jerk is not None else 4001)
    for leg in legs[:5]:
        t = np.linspace(0.0, leg.duration, samples)
        q, qd, qdd = leg.states(t)
        xy = np.array([arm.fk(qk)[:2] for qk in q])
        a, b = pts[leg.from_stop], pts[leg.to_stop]
        u = (b - a) / np.linalg.norm(b - a)
        offset = (xy - a) @ np.array([-u[1], u[0]])
        assert np.abs(offset).max() < 1e-9  # on the line
        # velocities are the derivative of positions (central differences)
        h = t[1] - t[0]
        np.testing.assert_allclose((q[2:] - q[:-2]) / (2 * h), qd[1:-1], atol=2e-3 * np.max(
            arm.joint_limits.velocity))
        if arm.joint_limits.jerk is not None:  # accelerations too: they are continuous
            np.testing.assert_allclose((qd[2:] - qd[:-2]) / (2 * h), qdd[1:-1],
                                       atol=2e-2 * np.max(arm.joint_limits.acceleration))
        # tip speed within Kv
        v = np.linalg.norm(np.array([arm.jacobian(qk) @ qdk for qk, qdk in zip(q, qd,
                                                                              strict=True)]),
                           axis=1)
        assert v.max() <= arm.cartesian_limits.kv * (1 + 1e-3)


def test_sampling_and_csv(tmp_path) -> None:
    problem, result = _solved("planar_2r", "square20", "line")
    trajectory = build_trajectory(result)
    s = trajectory.sample(0.05)
    assert s.t[0] == 0.0 and s.t[-1] == pytest.approx(trajectory.duration)
    assert np.all(np.diff(s.t) > 0)
    path = trajectory.to_csv(tmp_path / "traj.csv", dt=0.05)
    lines = path.read_text().splitlines()
    assert lines[0] == "t,q1,q2,dq1,dq2,x,y"
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert table.shape == (len(s.t), 7)
    np.testing.assert_allclose(table[:, 5:], s.tool, atol=1e-8)
    q, qd, qdd = trajectory.at_time(trajectory.duration)
    np.testing.assert_allclose(q, trajectory.legs[0].q_from, atol=1e-9)  # closed tour


@pytest.mark.parametrize("dt", [0.0, -0.1, float("nan")])
def test_non_positive_dt_is_rejected(dt: float) -> None:
    problem, result = _solved("planar_2r", "square20", "joint")
    trajectory = build_trajectory(result)
    with pytest.raises(ParameterError, match="dt"):
        trajectory.sample(dt)
    with pytest.raises(ParameterError, match="dt"):
        validate(trajectory, dt=dt)


def test_validator_catches_the_jerk_of_an_acceleration_limited_tour() -> None:
    # the same tour driven without jerk limits (acceleration steps) breaks planar_2r's jerk
    # limits; the validator must see it, and the jerk-limited trajectory must pass
    arm = _arm("planar_2r")
    jl = arm.joint_limits
    free = load_planar_arm("planar_2r", joint_limits=JointLimits(jl.lower, jl.upper, jl.velocity,
                                                          jl.acceleration))
    problem, result = _solved("planar_2r", "square20", "line")
    free_problem = PlanarProblem(problem.subtasks, free, time_model="line",
                                 configurations="optimize")
    free_result = solve(free_problem, seed=0)
    jerky = build_trajectory(free_result)
    judged = Trajectory(arm, jerky.legs, jerky.predicted_time, "line")
    report = validate(judged, dt=1e-3)
    assert not report.ok
    assert any(v.startswith("jerk limit exceeded") for v in report.violations)
    assert report.max_jerk_ratio is not None and max(report.max_jerk_ratio) > 10
    smooth = validate(build_trajectory(result), dt=1e-3)
    assert smooth.ok, smooth.violations
    # honouring jerk costs time
    assert build_trajectory(result).duration > jerky.duration


@pytest.mark.parametrize("dt", [1e-9, 1e-7, 11.0])
def test_sampling_step_outside_the_range_is_rejected_before_allocating(dt: float) -> None:
    from subtask_opt.arm.trajectory import MAX_DT, MIN_DT

    problem, result = _solved("asr_twodof", "square20", "joint")
    trajectory = build_trajectory(result)
    with pytest.raises(ParameterError, match=r"dt must be in \[") as err:
        trajectory.sample(dt)
    assert f"{MIN_DT:g}" in str(err.value) and f"{MAX_DT:g}" in str(err.value)
    with pytest.raises(ParameterError, match="dt"):
        validate(trajectory, dt=dt)


def test_too_many_samples_are_refused_with_the_estimate(monkeypatch) -> None:
    from subtask_opt.arm import trajectory as tr

    problem, result = _solved("asr_twodof", "square20", "joint")
    trajectory = build_trajectory(result)
    monkeypatch.setattr(tr, "MAX_SAMPLES", 1000)
    dt = trajectory.duration / 5000  # about 5000 samples
    with pytest.raises(ParameterError, match="limit of 1e[+]03") as err:
        trajectory.sample(dt)
    assert "5e+03 samples" in str(err.value)
    with pytest.raises(ParameterError, match="samples"):
        trajectory.to_csv("never_written.csv", dt)
    assert len(trajectory.sample(trajectory.duration / 900).t) <= 1000


def test_validator_reports_exceeded_limits() -> None:
    problem, result = _solved("asr_twodof", "square20", "joint")
    trajectory = build_trajectory(result)
    jl = trajectory.arm.joint_limits
    slower = load_planar_arm("asr_twodof", joint_limits=JointLimits(
        jl.lower, jl.upper, jl.velocity / 2, jl.acceleration / 2))
    strict = Trajectory(slower, trajectory.legs, trajectory.predicted_time, "joint")
    report = validate(strict, dt=5e-3)
    assert not report.ok
    text = " ".join(report.violations)
    assert "velocity limit exceeded" in text and "acceleration limit exceeded" in text
    assert "INVALID" in report.summary()
    narrow = load_planar_arm("asr_twodof", joint_limits=JointLimits(
        jl.lower / 10, jl.upper / 10, jl.velocity, jl.acceleration))
    report = validate(Trajectory(narrow, trajectory.legs, 1.0, "joint"), dt=5e-3)
    assert any("position limit" in v for v in report.violations)


def test_trajectory_needs_an_arm() -> None:
    problem = MatrixProblem(np.ones((4, 4)) - np.eye(4))
    result = solve(problem, seed=0)
    with pytest.raises(ParameterError, match="arm"):
        build_trajectory(result)
    with pytest.raises(ParameterError, match="trajectory"):
        validate(result)


def test_figures_and_animation(tmp_path) -> None:
    from subtask_opt.plotting.trajectory import (
        animate_tour,
        plot_executed_path,
        plot_joint_profiles,
    )

    arm = _arm("planar_2r")
    problem = PlanarProblem(random_subtasks(arm, 6, seed=0), arm, time_model="line",
                            configurations="optimize")
    result = solve(problem, seed=0)
    trajectory = build_trajectory(result)
    fig = plot_joint_profiles(trajectory)
    assert len(fig.axes) == 3
    ax = plot_executed_path(problem, trajectory)
    assert ax.get_title().startswith("executed tour")
    out = animate_tour(problem, trajectory, tmp_path / "tour.gif", max_frames=6)
    assert out.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    with pytest.raises(InputDataError, match=".gif"):
        animate_tour(problem, trajectory, tmp_path / "tour.mp4")
    with pytest.raises(InputDataError, match="does not exist"):
        animate_tour(problem, trajectory, tmp_path / "nowhere" / "tour.gif")
    with pytest.raises(ParameterError, match="fps"):
        animate_tour(problem, trajectory, tmp_path / "t.gif", fps=0)


def test_reachable_region_comes_from_the_joint_limits() -> None:
    from subtask_opt.plotting.sequencing import reachable_raster

    arm = _arm("planar_2r")
    jl = arm.joint_limits
    # brute force over the joint box: the closest tip position to the base
    q1, q2 = np.meshgrid(np.linspace(jl.lower[0], jl.upper[0], 181),
                         np.linspace(jl.lower[1], jl.upper[1], 721))
    tips = np.array([arm.fk(q)[:2] for q in np.column_stack([q1.ravel(), q2.ravel()])[::37]])
    r_true = float(np.hypot(*tips.T).min())
    assert r_true > 3 * arm.r_min  # the joint limits cut far more than |L1 - L2|
    gx, gy, mask = reachable_raster(arm, (-0.65, 0.65, -0.65, 0.65), 261)
    r = np.hypot(gx, gy)
    assert not mask[r < 0.97 * r_true].any()
    assert mask[(r > 1.05 * r_true) & (r < 0.5) & (gx > 0)].all()


def test_tour_legs_follow_the_arm() -> None:
    from subtask_opt.plotting.sequencing import tour_legs

    arm = _arm("planar_2r")
    problem, result = _solved("planar_2r", "random30", "joint")
    configs = result.report.configurations
    legs = tour_legs(problem, result.order, configs, samples=49)
    pts = problem.subtasks.points
    assert [leg.start for leg in legs] == [int(i) for i in result.order]
    for leg in legs:
        np.testing.assert_allclose(leg.xy[0], pts[leg.start], atol=1e-9)
        np.testing.assert_allclose(leg.xy[-1], pts[leg.end], atol=1e-9)
        # a joint move's tip path is the FK (Pinocchio) of the joint interpolation
        qa = arm.ik(pts[leg.start])[configs[leg.start]]
        qb = arm.ik(pts[leg.end])[configs[leg.end]]
        np.testing.assert_allclose(leg.xy[24], arm.fk((qa + qb) / 2)[:2], atol=1e-9)
        assert leg.kind == ("joint" if configs[leg.start] == configs[leg.end] else "elbow")
    # the trapezoid model's legs are straight, and its impossible lines are marked
    trap, trap_result = _solved("planar_2r", "random30", "trapezoid")
    legs = tour_legs(trap, trap_result.order)
    for leg in legs:
        a, b = pts[leg.start], pts[leg.end]
        cross = (leg.xy - a) @ np.array([-(b - a)[1], (b - a)[0]])
        assert np.abs(cross).max() < 1e-12
    bad = {(leg.start, leg.end) for leg in legs if leg.infeasible}
    expected = {(leg.start, leg.end) for leg in trap_result.report.infeasible}
    assert bad == expected


@pytest.mark.parametrize("n", [8, 45])
def test_solution_figure(tmp_path, n: int) -> None:
    import matplotlib.pyplot as plt

    from subtask_opt.plotting.sequencing import save_solution_figure, solution_figure

    arm = _arm("planar_2r")
    problem = PlanarProblem(random_subtasks(arm, n, seed=2), arm, time_model="joint",
                            configurations="optimize")
    result = solve(problem, seed=0)
    fig = solution_figure(result, problem)
    tour_ax = fig.axes[0]
    assert tour_ax.get_xlabel() == "x [m]" and tour_ax.get_ylabel() == "y [m]"
    assert f"N = {n}" in tour_ax.get_title() and "joint model" in tour_ax.get_title()
    assert "planar_2r" in fig.get_suptitle()
    numbers = [t.get_text() for t in tour_ax.texts if t.get_text()]  # not the arrows
    if n <= 40:  # legs numbered on the map
        assert sorted(numbers, key=int) == [str(k) for k in range(1, n + 1)]
    else:  # the order in a side table instead
        assert numbers == []
        table = [t.get_text() for ax in fig.axes for t in ax.texts if ":" in t.get_text()]
        assert len(table) == n
    conv = [ax for ax in fig.axes if ax.get_xlabel() == "generation"]
    assert len(conv) == 1 and conv[0].get_yscale() == "log"
    plt.close(fig)
    out = save_solution_figure(result, problem, tmp_path / "fig.png")
    assert out.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("tour", ["closed", "open"])
@pytest.mark.parametrize("home", [None, (0.35, 0.2)])
def test_open_tours_and_home_points_execute(tour: str, home) -> None:
    """A planar tour from a home point, closed or open: one leg per move the search timed,
    from the home (first stop) to the last target (open) or back to the start."""
    import subtask_opt as so
    from subtask_opt.tour.constraints import TourConstraints

    robot = so.load_robot("planar_2r")
    targets = random_subtasks(robot.model, 6, seed=4)
    result = so.solve(so.ArmProblem(targets, robot, home=home), seed=0,
                      constraints=TourConstraints(tour=tour))
    trajectory = so.trajectory(result)
    n = len(result.order)
    moves = n - (tour == "open") + (home is not None)
    assert len(trajectory.legs) == moves == len(result.leg_times)
    stops = [leg.from_stop for leg in trajectory.legs] + [trajectory.legs[-1].to_stop]
    inner = [int(i) for i in result.order]
    expected = ([HOME] if home is not None else []) + inner
    if tour == "closed":
        expected.append(expected[0])
    assert stops == expected
    if home is not None:  # the tip starts (and, closed, ends) at the home point
        tip = trajectory.tool_positions(trajectory.states([0.0, trajectory.duration])[0])
        np.testing.assert_allclose(tip[0], home, atol=1e-9)
        if tour == "closed":
            np.testing.assert_allclose(tip[1], home, atol=1e-9)
    np.testing.assert_allclose([leg.duration for leg in trajectory.legs], result.leg_times,
                               rtol=1e-6)
    check = so.validate(trajectory)
    assert check.ok, check.violations
    assert check.max_position_error < 1e-9 and check.max_axis_error is None

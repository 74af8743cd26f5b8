"""The ``line`` time model: time-optimal straight lines under joint and Cartesian limits.

Oracles: the closed-form trapezoid when the joint limits are slack, toppra
(an independent TOPP-RA implementation, optional) on random legs, and the
joint-space optimum as a lower bound.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.arm.planar_problem import PlanarProblem, solve
from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import random_subtasks
from subtask_opt.arm.timing.models import MOVE_JOINT, MOVE_LINE, MOVE_NONE, travel_times
from subtask_opt.base.errors import NoPathError, ParameterError
from subtask_opt.kinematics.planar import CartesianLimits, JointLimits, load_planar_arm
from tests.conftest import REDUCED, examples, size

_ARMS: dict = {}


def _arm(name: str):
    if name not in _ARMS:
        _ARMS[name] = load_planar_arm(name)
    return _ARMS[name]


def _no_jerk(name: str):
    """The robot without jerk limits: its lines are the acceleration-limited optimum."""
    arm = _arm(name)
    jl = arm.joint_limits
    return load_planar_arm(name, joint_limits=JointLimits(jl.lower, jl.upper, jl.velocity,
                                                   jl.acceleration))


def _slack_joints(name: str, kw: float = 1e6):
    """The robot with joint limits far above anything the Cartesian limits need."""
    arm = _arm(name)
    jl = arm.joint_limits
    cl = arm.cartesian_limits
    return load_planar_arm(name,
                           joint_limits=JointLimits(jl.lower, jl.upper, [1e6, 1e6], [1e6, 1e6]),
                           cartesian_limits=CartesianLimits(cl.kv, cl.ka, kw, kw))


@pytest.mark.parametrize("robot", ["planar_2r", "asr_twodof"])
def test_line_equals_the_closed_form_trapezoid_when_joints_are_slack(robot: str) -> None:
    arm = _slack_joints(robot)
    s = random_subtasks(arm, 8, seed=3)
    line = travel_times(s, arm, "line")
    trap = travel_times(s, arm, "trapezoid", check_legs=False)
    lines = line.moves() == MOVE_LINE
    assert lines.sum() >= 20  # most legs are straight lines
    np.testing.assert_allclose(line.matrix[lines], trap.matrix[lines], rtol=1e-3)


def _toppra_time(arm, p0, p1, branch) -> float:
    """toppra on the joint path of the line (sampled by IK), with s and the tool angle as
    extra path coordinates so that Kv, Ka, Kw, Kw_dot become its joint limits."""
    ta = pytest.importorskip("toppra")
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    ta.setup_logging("WARNING")
    d = float(np.hypot(*(p1 - p0)))
    s = np.linspace(0.0, d, 801)
    q = arm.ik(p0 + s[:, None] * (p1 - p0) / d)[:, branch]
    q = np.unwrap(q, axis=0)
    phi = np.unwrap([arm.fk(qk)[2] for qk in q])
    path = ta.SplineInterpolator(s, np.column_stack([q, s, phi]))
    jl, cl = arm.joint_limits, arm.cartesian_limits
    vlim = np.array([*jl.velocity, cl.kv, cl.kw])
    alim = np.array([*jl.acceleration, cl.ka, cl.kw_dot])
    inst = algo.TOPPRA(
        [constraint.JointVelocityConstraint(np.column_stack([-vlim, vlim])),
         constraint.JointAccelerationConstraint(
             np.column_stack([-alim, alim]),
             discretization_scheme=constraint.DiscretizationType.Interpolation)],
        path, gridpoints=np.linspace(0.0, d, 1001), parametrizer="ParametrizeConstAccel")
    return float(inst.compute_trajectory(0, 0).duration)


@pytest.mark.parametrize("robot", ["planar_2r", "asr_twodof"])
def test_line_matches_toppra_on_random_legs(robot: str) -> None:
    pytest.importorskip("toppra")
    arm = _no_jerk(robot)  # toppra has no jerk limits
    s = random_subtasks(arm, 6, seed=11)
    res = travel_times(s, arm, "line")
    moves = res.moves()
    checked = 0
    for i in range(6):
        for j in range(i + 1, 6):
            if moves[i, j] != MOVE_LINE:
                continue
            expected = _toppra_time(arm, s.points[i], s.points[j], res.configurations[i])
            assert res.matrix[i, j] == pytest.approx(expected, rel=5e-3)
            checked += 1
    assert checked >= 3


def test_line_is_never_faster_than_the_joint_optimum() -> None:
    # asr_twodof has no jerk limit: the joint model is the unconstrained joint-space optimum.
    arm = _arm("asr_twodof")
    s = random_subtasks(arm, size(10, 5), seed=5)
    line = travel_times(s, arm, "line")
    joint = travel_times(s, arm, "joint")
    assert np.all(line.branch_times >= joint.branch_times * (1 - 1e-9))


def test_line_converges_with_the_grid() -> None:
    arm = _no_jerk("planar_2r")
    s = random_subtasks(arm, 5, seed=2)
    coarse = travel_times(s, arm, "line", line_grid=128).branch_times
    fine = travel_times(s, arm, "line", line_grid=size(2048, 512)).branch_times
    ok = np.isfinite(fine)
    np.testing.assert_allclose(coarse[ok], fine[ok], rtol=5e-3)
    assert np.all(coarse[ok] >= fine[ok] * (1 - 1e-9))  # a coarser grid is more conservative


@settings(max_examples=examples(10, 3), deadline=None)
@given(st.sampled_from(["planar_2r", "asr_twodof"]), st.integers(0, 10_000))
def test_line_tensor_invariants(robot: str, seed: int) -> None:
    arm = _arm(robot)
    s = random_subtasks(arm, 5, seed=seed)
    res = travel_times(s, arm, "line")
    t = res.branch_times
    np.testing.assert_allclose(t, t.transpose(2, 3, 0, 1), rtol=1e-12)
    d = np.hypot(*(s.points[:, None] - s.points[None]).transpose(2, 0, 1))
    for c in range(2):  # straight lines respect Kv (joint moves answer to joint limits only)
        line = res.branch_moves[:, c, :, c] == MOVE_LINE
        assert np.all(t[:, c, :, c][line] >= d[line] / arm.cartesian_limits.kv)
    # a line never changes elbow branch
    assert not np.any(res.branch_moves[:, 0, :, 1] == MOVE_LINE)


def test_line_through_the_inner_disc_is_reported_and_replaced_or_excluded() -> None:
    arm = _arm("asr_twodof")
    bx, by = arm.base_xy
    r = 0.5 * (arm.r_min + arm.r_max)
    pts = np.array([[bx - r, by], [bx + r, by], [bx, by + r]])
    s = Targets(pts)
    res = travel_times(s, arm, "line")
    assert res.line_failure(0, 1, 0, 0) == "leaves the reachable annulus"
    assert res.moves()[0, 1] == MOVE_JOINT
    joint = travel_times(s, arm, "joint")
    assert res.matrix[0, 1] == joint.matrix[0, 1]
    excl = travel_times(s, arm, "line", line_fallback="exclude")
    assert math.isinf(excl.matrix[0, 1]) and excl.moves()[0, 1] == MOVE_NONE
    # every closed tour of 3 subtasks uses the impossible line
    for configurations in ("fixed", "optimize"):
        problem = PlanarProblem(s, arm, time_model="line", line_fallback="exclude",
                                configurations=configurations)
        with pytest.raises(NoPathError, match="excluded straight lines"):
            solve(problem, seed=0)
    # the fallback drives it as a joint move and says so
    result = solve(PlanarProblem(s, arm, time_model="line"), seed=0)
    report = result.report
    assert report is not None and "joint" in report.leg_moves
    assert report.diagnostics["all_pairs_lines"]["n_infeasible_lines"] >= 1
    assert any("leaves the reachable annulus" in note
               for leg in report.infeasible for note in leg.notes)


def test_line_past_a_joint_limit_is_reported() -> None:
    # (reduced: without jerk limits, which decide the durations but not the geometry)
    arm = _arm("planar_2r") if not REDUCED else _no_jerk("planar_2r")
    s = random_subtasks(arm, 12, seed=0)
    res = travel_times(s, arm, "line")
    reasons = {res.line_failure(i, j, c, c) for i in range(12) for j in range(12) if i != j
               for c in range(2) if np.isfinite(res.branch_joints[[i, j], c]).all()}
    assert "passes a joint limit" in reasons


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"line_fallback": "teleport"}, "line_fallback"),
    ({"line_grid": 3}, "line_grid"),
    ({"line_grid": 64.5}, "line_grid"),
])
def test_line_bad_parameters(kwargs: dict, match: str) -> None:
    arm = _arm("planar_2r")
    with pytest.raises(ParameterError, match=match):
        travel_times(random_subtasks(arm, 4, seed=0), arm, "line", **kwargs)


def test_missing_or_non_positive_limits_are_rejected() -> None:
    with pytest.raises(ParameterError, match="acceleration"):
        JointLimits([-1, -1], [1, 1], [1, 1], [0.0, 1.0])
    with pytest.raises(ParameterError, match="velocity"):
        JointLimits([-1, -1], [1, 1], None, [1, 1])
    with pytest.raises(ParameterError, match="kv"):
        CartesianLimits(-0.1, 1.0, 1.0, 1.0)


def test_third_path_derivatives_match_finite_differences() -> None:
    # the oracle: IK along the line, differentiated numerically
    from subtask_opt.arm.timing import _line_kernels as lk

    arm = _arm("planar_2r")
    s = random_subtasks(arm, 6, seed=4)
    checked = 0
    for i in range(5):
        p0, p1 = s.points[i], s.points[i + 1]
        d = float(np.hypot(*(p1 - p0)))
        u = (p1 - p0) / d
        branch = int(np.isnan(arm.ik(p0)[0, 0]))
        if np.isnan(arm.ik(p1)[branch, 0]):
            continue
        sm = 0.5 * d
        h = 1e-3 * d
        q = arm.ik(np.array([p0 + (sm + k * h) * u for k in (-2, -1, 0, 1, 2)]))[:, branch]
        if np.isnan(q).any():
            continue
        q = np.unwrap(q, axis=0)
        der = np.empty(lk.N_DER)
        assert lk.path_derivatives(arm.kinematics, q[2, 0], q[2, 1], u[0], u[1], der)
        third = (q[4] - 2 * q[3] + 2 * q[1] - q[0]) / (2 * h ** 3)
        second = (q[3] - 2 * q[2] + q[1]) / h ** 2
        np.testing.assert_allclose(der[2:4], second, rtol=1e-4, atol=1e-6)
        np.testing.assert_allclose(der[6:8], third, rtol=1e-3, atol=1e-4 * np.abs(third).max())
        checked += 1
    assert checked >= 2


def test_jerk_limited_line_bounds() -> None:
    # with jerk limits a line is never faster than without them (same path, more limits),
    # nor than the joint model's per-joint jerk-limited optimum (a lower bound of any move)
    arm = _arm("planar_2r")
    assert arm.joint_limits.jerk is not None
    s = random_subtasks(arm, 6, seed=7)
    jerk = travel_times(s, arm, "line", line_fallback="exclude").branch_times
    acc = travel_times(s, _no_jerk("planar_2r"), "line", line_fallback="exclude").branch_times
    joint = travel_times(s, arm, "joint").branch_times
    ok = np.isfinite(jerk) & (jerk > 0)
    assert ok.sum() >= 10
    np.testing.assert_array_equal(np.isfinite(jerk), np.isfinite(acc))
    assert np.all(jerk[ok] >= acc[ok] * (1 - 1e-3))
    assert np.all(jerk[ok] >= joint[ok] * (1 - 1e-9))
    assert np.all(jerk[ok] > acc[ok] * 1.01)  # the jerk limits of planar_2r do bind


def test_line_limits_reject_a_bad_grid() -> None:
    from subtask_opt.arm.timing.models import line_limits

    with pytest.raises(ParameterError, match="grid"):
        line_limits(_arm("planar_2r"), 8)


def test_jerk_limited_line_picks_a_near_best_averaging_width() -> None:
    # oracle: the same smoothed family measured exactly on a fine grid of widths
    from subtask_opt.arm.timing import _line_kernels as lk
    from subtask_opt.arm.timing.models import line_limits

    arm = _arm("planar_2r")
    lim = line_limits(arm)
    s = random_subtasks(arm, 6, seed=3)
    q = arm.ik(s.points)
    ratios = []
    for i in range(6):
        for j in range(i + 1, 6):
            for c in range(2):
                if np.isnan(q[i, c, 0]) or np.isnan(q[j, c, 0]):
                    continue
                a, b = s.points[i].copy(), s.points[j].copy()
                st, sg, qs, der = lk.line_geometry(arm.kinematics, a, b, c, q[i, c].copy(),
                                                   q[j, c].copy(), lim.grid)
                if st != lk.LINE_OK:
                    continue
                ok, x, w, t1 = lk.topp_profile(der, sg, lim.vel, lim.acc, lim.kv, lim.ka,
                                               lim.kw, lim.kw_dot)
                assert ok
                chosen = lk.line_profile(arm.kinematics, a, b, c, q[i, c].copy(),
                                         q[j, c].copy(), lim)[7]
                tk, sk = lk.profile_knots(sg, x, w)
                u = (b - a) / np.linalg.norm(b - a)
                best = min(lk._slowdown(arm.kinematics, a, u[0], u[1], c, sg, np.sqrt(x), w,
                                        tk, sk, tau, lim, np.inf) * (t1 + tau)
                           for tau in t1 * np.geomspace(1e-3, 2.0, 120))
                ratios.append(chosen / best)
    assert len(ratios) >= 8
    assert max(ratios) < 1.05


def test_point_derivatives_without_trigonometry_equal_those_of_the_ik_angles() -> None:
    # oracle: path_derivatives at the joint angles of the IK (sines and cosines of them)
    from subtask_opt.arm.timing import _line_kernels as lk

    arm = _arm("planar_2r")
    s = random_subtasks(arm, 12, seed=6)
    q = arm.ik(s.points)
    u = np.array([0.6, -0.8])
    checked = 0
    for i, p in enumerate(s.points):
        for branch in range(2):
            if np.isnan(q[i, branch, 0]):
                continue
            want = np.empty(lk.N_DER)
            got = np.empty(lk.N_DER)
            assert lk.path_derivatives(arm.kinematics, q[i, branch, 0], q[i, branch, 1], u[0],
                                       u[1], want)
            assert lk.point_derivatives(arm.kinematics, p[0], p[1], branch, u[0], u[1], got)
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
            checked += 1
    assert checked >= 12
    outside = arm.base_xy + np.array([2.0 * arm.r_max, 0.0])
    assert not lk.point_derivatives(arm.kinematics, outside[0], outside[1], 0, 1.0, 0.0,
                                    np.empty(lk.N_DER))


def test_the_breakpoint_check_is_never_below_a_dense_sampling() -> None:
    # oracle: the smoothed profile sampled at 12 instants per piece, path derivatives by IK;
    # the check (every breakpoint, the jerk on both sides) may be above it, and below it by
    # less than the margin the time stretch gets (the limits between breakpoints)
    from subtask_opt.arm.timing import _line_kernels as lk
    from subtask_opt.arm.timing.models import line_limits

    arm = _arm("planar_2r")
    lim = line_limits(arm)
    inv = lk._inverse_limits(lim)
    s = random_subtasks(arm, 5, seed=3)
    q = arm.ik(s.points)
    checked = 0
    for i in range(5):
        for j in range(i + 1, 5):
            c = 0 if not np.isnan(q[[i, j], 0, 0]).any() else 1
            if np.isnan(q[[i, j], c, 0]).any():
                continue
            a, b = s.points[i].copy(), s.points[j].copy()
            st, sg, qs, der = lk.line_geometry(arm.kinematics, a, b, c, q[i, c].copy(),
                                               q[j, c].copy(), lim.grid)
            if st != lk.LINE_OK:
                continue
            ok, x, w, t1 = lk.topp_profile(der, sg, lim.vel, lim.acc, lim.kv, lim.ka, lim.kw,
                                           lim.kw_dot)
            tk, sk = lk.profile_knots(sg, x, w)
            v = np.sqrt(x)
            u = (b - a) / np.linalg.norm(b - a)
            for tau in t1 * np.array([0.003, 0.05, 0.3, 1.0]):
                check = lk._slowdown(arm.kinematics, a, u[0], u[1], c, sg, v, w, tk, sk, tau, lim,
                                     np.inf)
                dense = _dense_slowdown(lk, arm.kinematics, a, u, c, sg, qs, v, w, tk, sk, tau,
                                        inv, lim.has_jerk)
                assert check * (1 + lim.margin) >= dense, (i, j, tau / t1)
                assert check <= dense * (1 + 1e-3)
                checked += 1
    assert checked >= 12


def _dense_slowdown(lk, kin, p0, u, branch, sg, qs, v, w, tk, sk, tau, inv, has_jerk):
    n = 12 * 2 * tk.shape[0]
    end = tk[-1] + tau
    der = np.empty(lk.N_DER)
    tmp = np.empty(2)
    rv = ra = rj = 0.0
    ia = ib = g = 0
    for k in range(n):
        t = (k + 0.5) * end / n
        f, f1, f2, f3, ia, ib = lk._smoothed(t, tau, ia, ib, sg, v, w, tk, sk)
        while g < sg.shape[0] - 2 and f >= sg[g + 1]:
            g += 1
        lk._exact_derivatives(kin, p0, u[0], u[1], branch, sg, qs, f, g, der, tmp)
        rv, ra, rj = lk._ratios(tuple(der), f1, f2, f3, f3, inv, has_jerk, rv, ra, rj)
    return max(rv, math.sqrt(ra), rj ** (1.0 / 3.0))


def test_a_bounded_judgement_of_a_width_stops_only_above_its_bound() -> None:
    # oracle: the same width judged in full (bound inf). Below its bound a judgement is the
    # full one, flagged complete; above it, a lower bound of the full one that is above the
    # bound, so every comparison the width search makes with it comes out the same
    from subtask_opt.arm.timing import _line_kernels as lk
    from subtask_opt.arm.timing.models import line_limits

    arm = _arm("planar_2r")
    lim = line_limits(arm, 256)
    s = random_subtasks(arm, 6, seed=4)
    q = arm.ik(s.points)
    kin = arm.kinematics
    checked = stopped = 0
    for i in range(6):
        for j in range(i + 1, 6):
            for c in range(2):
                if np.isnan(q[[i, j], c, 0]).any():
                    continue
                a, b = s.points[i].copy(), s.points[j].copy()
                st, sg, qs, der = lk.line_geometry(kin, a, b, c, q[i, c].copy(),
                                                   q[j, c].copy(), lim.grid)
                if st != lk.LINE_OK:
                    continue
                ok, x, w, t1 = lk.topp_profile(der, sg, lim.vel, lim.acc, lim.kv, lim.ka,
                                               lim.kw, lim.kw_dot)
                tk, sk = lk.profile_knots(sg, x, w)
                v = np.sqrt(x)
                u = (b - a) / np.linalg.norm(b - a)
                jumps = lk._jump_times(tk, w)
                index = lk._time_index(tk, lk.TIME_BUCKETS)
                for tau in t1 * np.array([0.01, 0.15, 0.8]):
                    full, done = lk._estimate(kin, a, u[0], u[1], c, sg, v, w, tk, sk, tau,
                                              lim, jumps, index, np.inf)
                    assert done
                    exact = lk._slowdown(kin, a, u[0], u[1], c, sg, v, w, tk, sk, tau, lim,
                                         np.inf)
                    for share in (0.3, 0.9, 1.0, 1.2):
                        bound = share * full
                        part, done = lk._estimate(kin, a, u[0], u[1], c, sg, v, w, tk, sk,
                                                  tau, lim, jumps, index, bound)
                        if done:
                            assert part == full
                        else:
                            stopped += 1
                            assert bound < part <= full * (1 + 1e-15)
                        low = lk._slowdown(kin, a, u[0], u[1], c, sg, v, w, tk, sk, tau, lim,
                                           share * exact)
                        assert low == (exact if share >= 1.0 else np.inf)
                    checked += 1
    assert checked >= 12 and stopped >= checked

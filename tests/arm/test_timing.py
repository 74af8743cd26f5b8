"""Tests of the time models: 1-DOF profile times, the three time models, the leg check."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from ruckig import InputParameter, Result, Ruckig, Trajectory

from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import builtin_case, random_subtasks
from subtask_opt.arm.timing.models import (
    MOVE_LINE,
    TIME_MODELS,
    LegCheck,
    scurve_time,
    trapezoid_time,
    travel_times,
)
from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.kinematics.planar import (
    ROBOT_NAMES,
    Arm,
    CartesianLimits,
    JointLimits,
    load_planar_arm,
)
from tests.conftest import examples, size


@functools.cache
def _arm(name: str) -> Arm:
    return load_planar_arm(name)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _ruckig_time(d: float, v: float, a: float, j: float | None) -> float:
    """Duration of ruckig's time-optimal 1-DOF rest-to-rest move (the oracle)."""
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [d]
    inp.max_velocity = [v]
    inp.max_acceleration = [a]
    inp.max_jerk = [math.inf if j is None else j]
    traj = Trajectory(1)
    assert otg.calculate(inp, traj) == Result.Working
    return traj.duration


# ---------------------------------------------------------------- 1-DOF profiles

def _envelope_time(d: float, v: float, a: float) -> float:
    """Brute force: the least T whose fastest rest-to-rest speed envelope covers d.

    The envelope min(a t, v, a (T - t)) is integrated numerically and T found by
    bisection: no closed form involved.
    """
    def covered(T: float) -> float:
        t = np.linspace(0.0, T, 20001)
        return float(np.trapezoid(np.minimum(np.minimum(a * t, v), a * (T - t)), t))

    lo, hi = 0.0, 1.0
    while covered(hi) < d:
        hi *= 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if covered(mid) < d else (lo, mid)
    return 0.5 * (lo + hi)


@settings(max_examples=30, deadline=None)
@given(st.floats(1e-3, 5.0), st.floats(0.05, 3.0), st.floats(0.1, 10.0))
def test_trapezoid_matches_brute_integration(d: float, v: float, a: float) -> None:
    assert trapezoid_time(d, v, a) == pytest.approx(_envelope_time(d, v, a), rel=1e-5)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.05, 3.0), st.floats(0.1, 10.0))
def test_trapezoid_continuous_at_the_switch(v: float, a: float) -> None:
    d0 = v * v / a
    below, at, above = (trapezoid_time(d0 * (1 + e), v, a) for e in (-1e-9, 0.0, 1e-9))
    assert at == pytest.approx(2 * v / a, rel=1e-12)
    assert below == pytest.approx(at, rel=1e-8) and above == pytest.approx(at, rel=1e-8)
    assert below <= at <= above


@settings(max_examples=40, deadline=None)
@given(st.floats(1e-3, 5.0), st.floats(0.05, 3.0), st.floats(0.1, 10.0),
       st.floats(0.5, 200.0))
def test_scurve_matches_ruckig(d: float, v: float, a: float, j: float) -> None:
    assert scurve_time(d, v, a, j) == pytest.approx(_ruckig_time(d, v, a, j), rel=1e-6)


@pytest.mark.parametrize("d, v, a, j", [
    (2.0, 1.0, 2.0, 10.0),    # cruise, amax reached
    (2.0, 1.0, 2.0, 2.0),     # cruise, amax not reached (v j < a^2)
    (0.3, 1.0, 2.0, 10.0),    # no cruise, amax reached
    (0.05, 1.0, 2.0, 10.0),   # no cruise, jerk phases only
    (0.0, 1.0, 2.0, 10.0),
])
def test_scurve_cases_match_ruckig(d: float, v: float, a: float, j: float) -> None:
    assert scurve_time(d, v, a, j) == pytest.approx(_ruckig_time(d, v, a, j), rel=1e-9, abs=1e-12)


def test_scurve_tends_to_the_trapezoid() -> None:
    for d in (0.01, 0.5, 3.0):
        assert scurve_time(d, 1.0, 2.0, 1e9) == pytest.approx(trapezoid_time(d, 1.0, 2.0),
                                                              rel=1e-6)
        assert trapezoid_time(d, 1.0, 2.0) == pytest.approx(_ruckig_time(d, 1.0, 2.0, None))


@pytest.mark.parametrize("args, field", [
    ((-1.0, 1.0, 1.0), "distance"), ((1.0, 0.0, 1.0), "vmax"), ((1.0, 1.0, -2.0), "amax"),
    ((math.nan, 1.0, 1.0), "distance"), ((1.0, math.inf, 1.0), "vmax"),
])
def test_profile_times_reject_bad_values(args: tuple, field: str) -> None:
    with pytest.raises(ParameterError, match=f"trapezoid_time.{field}"):
        trapezoid_time(*args)
    with pytest.raises(ParameterError, match=f"scurve_time.{field}"):
        scurve_time(*args, 5.0)
    with pytest.raises(ParameterError, match="scurve_time.jmax"):
        scurve_time(1.0, 1.0, 1.0, 0.0)


# ---------------------------------------------------------------- time models

@settings(max_examples=examples(15, 6), deadline=None)
@given(st.sampled_from(ROBOT_NAMES), st.sampled_from(TIME_MODELS), st.integers(0, 10_000),
       st.integers(3, size(8, 5)), st.integers(0, 1))
def test_matrix_invariants(robot: str, model: str, seed: int, n: int, elbow: int) -> None:
    arm = _arm(robot)
    s = random_subtasks(arm, n, seed=seed)
    res = travel_times(s, arm, model, elbow=elbow)
    m = res.matrix
    assert m.shape == (n, n) and res.model == model
    np.testing.assert_array_equal(m, m.T)
    assert np.all(np.diag(m) == 0) and np.all(m >= 0)
    off = ~np.eye(n, dtype=bool)
    assert np.all(m[off] > 0)
    d = np.hypot(*(s.points[:, None] - s.points[None]).transpose(2, 0, 1))
    if model == "trapezoid":
        assert np.all(m >= d / arm.cartesian_limits.kv)
    if model == "joint":
        dq = np.abs(res.joint_positions[:, None] - res.joint_positions[None])
        assert np.all(m >= (dq / arm.joint_limits.velocity).max(axis=2) - 1e-12)
        assert res.leg_check is None
    elif model == "line":  # straight lines obey Kv; joint moves (fallback) only joint limits
        line = res.moves() == MOVE_LINE
        assert np.all(m[line] >= d[line] / arm.cartesian_limits.kv)
        assert res.leg_check is None and res.line_status.shape == (n, n, 2)
    else:
        assert isinstance(res.leg_check, LegCheck)


@pytest.mark.parametrize("robot, jerk", [("planar_2r", True), ("planar_2r", False),
                                         ("asr_twodof", False)])
def test_joint_model_matches_ruckig(robot: str, jerk: bool) -> None:
    arm = _arm(robot)
    if not jerk and arm.joint_limits.jerk is not None:
        jl = arm.joint_limits
        arm = load_planar_arm(robot, joint_limits=JointLimits(jl.lower, jl.upper, jl.velocity,
                                                       jl.acceleration, None))
    s = random_subtasks(arm, 5, seed=7)
    for elbow in (0, 1):
        res = travel_times(s, arm, "joint", elbow=elbow)
        q = res.joint_positions
        jl = arm.joint_limits
        for i in range(len(s)):
            for j in range(i + 1, len(s)):
                expected = max(
                    _ruckig_time(abs(q[j, a] - q[i, a]), jl.velocity[a], jl.acceleration[a],
                                 None if jl.jerk is None else jl.jerk[a])
                    for a in range(2))
                assert res.matrix[i, j] == pytest.approx(expected, rel=1e-7)


def test_configurations_follow_elbow_with_fallback() -> None:
    arm = _arm("planar_2r")
    # (-0.545, -0.198) lies behind the base: the shoulder limit leaves only elbow-up.
    s = Targets([[0.4, 0.1], [0.3, -0.2], [-0.545, -0.198]])
    assert np.isnan(arm.ik(s.points[2])[0]).all()
    down = travel_times(s, arm, "joint", elbow=0)
    up = travel_times(s, arm, "joint", elbow=1)
    assert down.configurations.tolist() == [0, 0, 1]
    assert up.configurations.tolist() == [1, 1, 1]
    for res in (down, up):
        for qi, p in zip(res.joint_positions, s.points, strict=True):
            np.testing.assert_allclose(arm.fk(qi)[:2], p, atol=1e-12)


def _tool_angles(arm: Arm, res) -> np.ndarray:
    return np.array([arm.fk(q)[2] for q in res.joint_positions])


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_trapezoid_model_closed_form(robot: str) -> None:
    arm = _arm(robot)
    cl = arm.cartesian_limits
    s = builtin_case("random30", arm, seed=2)
    res = travel_times(s, arm, "trapezoid", check_legs=False)
    phi = _tool_angles(arm, res)  # the tool angles by Pinocchio
    np.testing.assert_allclose(res.tool_angles, phi, atol=1e-9)
    for i, j in [(0, 1), (3, 17), (5, 29), (11, 12)]:
        d = float(np.hypot(*(s.points[j] - s.points[i])))
        rot = abs(_wrap(phi[j] - phi[i]))
        expected = max(trapezoid_time(d, cl.kv, cl.ka), trapezoid_time(rot, cl.kw, cl.kw_dot))
        assert res.matrix[i, j] == pytest.approx(expected, rel=1e-9)


def _paper_expected(d_lin: float, theta: float, cl: CartesianLimits) -> float:
    """Eq. (17)-(19) as SPEC.md restates them."""
    t_lin = max(d_lin / cl.kv, theta / cl.kw)
    t_acc = max(d_lin / t_lin / cl.ka, theta / t_lin / cl.kw_dot)
    return t_acc + t_lin + t_acc


@pytest.mark.parametrize("k", [0.0, 0.1, 0.25, 0.45])
def test_paper_model_reduces_on_translation(k: float) -> None:
    arm = _arm("asr_twodof")
    cl = arm.cartesian_limits
    base = builtin_case("square20", arm)
    # Constant tool angles: pure translation, t = (1 - 2k) d / Kv + 2 Kv / Ka.
    s = Targets(base.points, theta=np.full(len(base), 0.3))
    m = travel_times(s, arm, "paper", k=k).matrix
    d = np.hypot(*(s.points[:, None] - s.points[None]).transpose(2, 0, 1))
    off = ~np.eye(len(s), dtype=bool)
    np.testing.assert_allclose(m[off], ((1 - 2 * k) * d / cl.kv + 2 * cl.kv / cl.ka)[off],
                               rtol=1e-12)
    # Given tool angles with almost no translation: the rotation terms take over.
    s2 = Targets([[0.1, 0.05], [0.1 + 1e-7, 0.05], [0.1, 0.05 + 1e-7]],
                    theta=[0.0, 2.0, -1.0])
    m2 = travel_times(s2, arm, "paper", k=k).matrix
    assert m2[0, 1] == pytest.approx((1 - 2 * k) * 2.0 / cl.kw + 2 * cl.kw / cl.kw_dot, rel=1e-6)


def test_paper_model_uses_the_arm_at_the_via_points() -> None:
    arm = _arm("asr_twodof")
    cl = arm.cartesian_limits
    k = 0.1
    s = builtin_case("random30", arm, seed=4)
    res = travel_times(s, arm, "paper", k=k)
    n_translation = 0
    for i in range(len(s)):
        for j in range(i + 1, len(s)):
            pi, pj = s.points[i], s.points[j]
            angles = []
            for p, end in ((pi + k * (pj - pi), i), (pj + k * (pi - pj), j)):
                q = arm.ik(p)[res.configurations[end]]
                angles.append(arm.fk(q)[2] if np.isfinite(q).all() else res.tool_angles[end])
            theta = abs(_wrap(angles[1] - angles[0]))
            d = float(np.hypot(*(pj - pi)))
            lin = (1 - 2 * k) * d
            expected = _paper_expected(lin, theta, cl)
            assert res.matrix[i, j] == pytest.approx(expected, rel=1e-9)
            if lin / cl.kv >= theta / cl.kw and cl.kv / cl.ka >= theta / (lin / cl.kv) / cl.kw_dot:
                n_translation += 1
                assert res.matrix[i, j] == pytest.approx(lin / cl.kv + 2 * cl.kv / cl.ka)
    assert n_translation > 0


@pytest.mark.parametrize("kwargs, match", [
    ({"model": "cartesian"},
     "unknown time model 'cartesian': expected one of paper, trapezoid, joint"),
    ({"k": 0.5}, "k must be < 0.5"),
    ({"k": -0.1}, r"travel_times.k must be in \[0.0, 0.5\]"),
    ({"k": math.nan}, "travel_times.k"),
    ({"elbow": 2}, "elbow must be 0"),
    ({"elbow": True}, "elbow must be 0"),
    ({"n_samples": 1}, "n_samples"),
])
def test_travel_times_bad_parameters(kwargs: dict, match: str) -> None:
    arm = _arm("asr_twodof")
    with pytest.raises(ParameterError, match=match):
        travel_times(builtin_case("square20", arm), arm, **kwargs)


def test_travel_times_unreachable_subtask() -> None:
    arm = _arm("asr_twodof")
    s = Targets([[0.1, 0.05], [0.15, 0.0], [0.5, 0.5]])
    with pytest.raises(UnreachableError, match=r"subtask 2 at \(0.5, 0.5\) is beyond"):
        travel_times(s, arm)
    with pytest.raises(ParameterError, match="Targets"):
        travel_times(np.zeros((3, 2)), arm)  # type: ignore[arg-type]


# ---------------------------------------------------------------- leg check

def _profile_speed(s: np.ndarray, d: float, kv: float, ka: float, scale: float) -> np.ndarray:
    return scale * np.minimum(kv, np.minimum(np.sqrt(2 * ka * s), np.sqrt(2 * ka * (d - s))))


def test_leg_ratio_matches_pinocchio_jacobian() -> None:
    """Same samples, q_dot by Pinocchio's Jacobian and numpy's solver."""
    arm = _arm("asr_twodof")
    cl, vel = arm.cartesian_limits, arm.joint_limits.velocity
    s = Targets([[0.15, 0.05], [0.1, 0.15], [0.2, -0.05]])
    n = 40
    res = travel_times(s, arm, "trapezoid", n_samples=n)
    lc = res.leg_check
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        assert not lc.outside_annulus[i, j]
        pi, pj = s.points[i], s.points[j]
        d = float(np.hypot(*(pj - pi)))
        u = (pj - pi) / d
        t_tr = trapezoid_time(d, cl.kv, cl.ka)
        rot = abs(_wrap(res.tool_angles[j] - res.tool_angles[i]))
        scale = t_tr / max(t_tr, trapezoid_time(rot, cl.kw, cl.kw_dot))
        sv = d * np.arange(1, n) / n
        worst = 0.0
        for sk, speed in zip(sv, _profile_speed(sv, d, cl.kv, cl.ka, scale), strict=True):
            q = arm.ik(pi + sk * u)[res.configurations[i]]
            qd = np.linalg.solve(arm.jacobian(q), u * speed)
            worst = max(worst, float(np.max(np.abs(qd) / vel)))
        assert lc.speed_ratio[i, j] == pytest.approx(worst, rel=1e-9)
        assert lc.speed_ratio[j, i] == lc.speed_ratio[i, j]


def test_leg_ratio_matches_finite_differences() -> None:
    """Drive the leg in time: q(t) by IK along the trapezoid, q_dot by central differences."""
    arm = _arm("asr_twodof")
    cl, vel = arm.cartesian_limits, arm.joint_limits.velocity
    s = Targets([[0.2, 0.0], [0.05, 0.12], [0.1, -0.12]], theta=[0.0, 0.0, 0.0])
    lc = travel_times(s, arm, "trapezoid", n_samples=4000).leg_check
    pi, pj = s.points[0], s.points[1]
    d = float(np.hypot(*(pj - pi)))
    T = trapezoid_time(d, cl.kv, cl.ka)
    t = np.linspace(0.0, T, 4001)
    ta = cl.kv / cl.ka  # d >= Kv^2/Ka here: accelerate, cruise, decelerate
    assert d >= cl.kv**2 / cl.ka
    pos = np.where(t < ta, 0.5 * cl.ka * t**2,
                   np.where(t < T - ta, cl.kv * (t - ta / 2), d - 0.5 * cl.ka * (T - t) ** 2))
    q = arm.ik(pi + pos[:, None] * (pj - pi) / d)[:, 0]
    q[:, 0] = np.unwrap(q[:, 0])
    qd = np.gradient(q, t, axis=0)
    assert lc.speed_ratio[0, 1] == pytest.approx(float(np.max(np.abs(qd) / vel)), rel=2e-3)
    assert lc.speed_ratio[0, 1] > 1.0  # this Cartesian leg is too fast for the joints


def test_leg_check_flags_impossible_lines() -> None:
    arm = _arm("asr_twodof")
    b = arm.base_xy
    s = Targets(b + np.array([
        [0.1, 0.0],        # 0: in front
        [-0.1, 0.01],      # 1: behind: the line 0-1 crosses the inner disc
        [0.15 * math.cos(-1.92), 0.15 * math.sin(-1.92)],  # 2, 4: on elbow-down the
        [0.1, 0.1],                                        # upper arm turns through +-pi
        [0.15 * math.cos(-2.44), 0.15 * math.sin(-2.44)],  # (joint 1 at +-3.14) on 2-4
    ]))
    lc = travel_times(s, arm).leg_check
    assert lc.outside_annulus[0, 1] and lc.outside_annulus[1, 0]
    assert lc.outside_annulus[2, 4]
    assert not lc.outside_annulus[0, 3] and not lc.outside_annulus[0, 2]
    assert np.isinf(lc.speed_ratio[0, 1]) and np.isfinite(lc.speed_ratio[0, 3])
    # Joint 1 wide open: the line behind the base becomes drivable, the disc does not.
    jl = arm.joint_limits
    wide = load_planar_arm("asr_twodof", joint_limits=JointLimits([-7.0, -3.14], [7.0, 3.14],
                                                           jl.velocity, jl.acceleration))
    lw = travel_times(s, wide).leg_check
    assert lw.outside_annulus[0, 1] and not lw.outside_annulus[2, 4]


def test_leg_check_flags_branch_changes() -> None:
    arm = _arm("planar_2r")
    s = Targets([[0.4, 0.1], [0.3, -0.2], [-0.545, -0.198]])
    res = travel_times(s, arm, "trapezoid", elbow=0)
    assert res.configurations.tolist() == [0, 0, 1]
    lc = res.leg_check
    assert lc.outside_annulus[0, 2] and lc.outside_annulus[1, 2]
    assert not lc.outside_annulus[0, 1]


def test_leg_check_summary_and_json() -> None:
    arm = _arm("asr_twodof")
    s = builtin_case("random30", arm, seed=0)
    lc = travel_times(s, arm).leg_check
    assert lc.n_legs == 435
    up = np.triu(np.ones((30, 30), dtype=bool), 1)
    assert lc.n_infeasible == int(lc.outside_annulus[up].sum()) > 0
    assert 0 < lc.n_overspeed <= lc.n_legs - lc.n_infeasible
    assert lc.worst_ratio == float(lc.speed_ratio[np.isfinite(lc.speed_ratio)].max())
    data = json.loads(json.dumps(lc.to_dict()))
    assert data["n_infeasible"] == lc.n_infeasible and len(data["infeasible"]) == lc.n_infeasible
    assert len(data["overspeed"]) == lc.n_overspeed
    assert all(r > 1 for _, _, r in data["overspeed"])
    assert "straight legs impossible" in lc.summary()
    # Slow enough Cartesian limits: no leg overspeeds.
    slow = load_planar_arm("asr_twodof", cartesian_limits=CartesianLimits(0.001, 0.2, 0.01, 2.0))
    assert travel_times(s, slow).leg_check.n_overspeed == 0


def test_results_are_read_only() -> None:
    arm = _arm("planar_2r")
    res = travel_times(builtin_case("square20", arm), arm)
    with pytest.raises(ValueError):
        res.matrix[0, 1] = 0.0
    assert res.configurations.dtype == np.int64


def test_explicit_configurations() -> None:
    arm = _arm("planar_2r")
    s = Targets([[0.4, 0.1], [0.3, -0.2], [-0.545, -0.198]])
    res = travel_times(s, arm, "joint", configurations=[1, 0, 1])
    assert res.configurations.tolist() == [1, 0, 1]
    np.testing.assert_allclose(res.joint_positions[0], arm.ik(s.points[0])[1])
    with pytest.raises(UnreachableError, match="subtask 2 .* not reachable elbow-down"):
        travel_times(s, arm, "joint", configurations=[1, 0, 0])
    with pytest.raises(ParameterError, match="configurations must be 3 values"):
        travel_times(s, arm, "joint", configurations=[1, 0])
    with pytest.raises(ParameterError, match="configurations must be 3 values"):
        travel_times(s, arm, "joint", configurations=[1, 0, 2])


def test_leg_check_of_named_legs_equals_all_pairs() -> None:
    """Checking only some legs (a tour, reversed legs, a stay) reads the all-pairs arrays."""
    arm = _arm("asr_twodof")
    lc = travel_times(builtin_case("random30", arm, seed=3), arm, "trapezoid").leg_check
    rng = np.random.default_rng(0)
    tour = rng.permutation(30)
    starts = np.concatenate([tour, rng.integers(0, 30, 40), [5]])
    ends = np.concatenate([np.roll(tour, -1), rng.integers(0, 30, 40), [5]])
    outside, ratio = lc.legs(starts, ends)
    assert outside.shape == ratio.shape == (71,)
    assert np.array_equal(outside, lc.outside_annulus[starts, ends])
    assert np.array_equal(ratio, lc.speed_ratio[starts, ends])
    assert outside.any() and (ratio[~outside] > 1).any()  # both kinds of finding are covered


@pytest.mark.parametrize("starts, ends", [([0, 1], [1]), ([0, 30], [1, 2]), ([-1], [2]),
                                          ([0.0], [1.0]), ([[0]], [[1]])])
def test_leg_check_rejects_bad_legs(starts: list, ends: list) -> None:
    arm = _arm("asr_twodof")
    lc = travel_times(builtin_case("random30", arm, seed=3), arm, "trapezoid").leg_check
    with pytest.raises(ParameterError, match=r"LegCheck.legs .*\[0, 29\]"):
        lc.legs(starts, ends)

"""Tests of the spherical-wrist closed form of subtask_opt.kinematics.ik.

Oracles: Pinocchio's forward kinematics (every solution reaches its pose), the
configuration that generated a pose (it must be among the solutions), the joint
placements written in the URDF (the wrist centre), and a dense multi-start DLS
(the closed form finds every solution DLS finds).
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest

from subtask_opt.arm.poses import make_targets
from subtask_opt.base.errors import ParameterError
from subtask_opt.kinematics import ik as ik_module
from subtask_opt.kinematics.ik import (
    IKParams,
    IKSolver,
    SphericalWristKinematics,
    spherical_wrist_kinematics,
)
from subtask_opt.kinematics.serial import load_serial_arm
from tests.conftest import SHARED_DATA
from tests.kinematics.test_ik import _alternative_count, _fk_error, _mod_distance

TWO_PI = 2 * math.pi

# A spherical-wrist arm with every offset the closed form claims to handle: a tilted
# base, a shoulder offset, a shoulder axis not perpendicular to axis 1 (rolled 0.2 rad),
# lateral offsets along the shoulder axis, an elbow offset, joint 3 turning the other
# way from joint 2, a forearm axis along x, a tool offset and joint 6 with a range over
# 2 pi.
_OFFSET_URDF = """<?xml version="1.0"?>
<robot name="offset6r">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <link name="l4"/><link name="l5"/><link name="l6"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.02 -0.01 0.4" rpy="0.1 -0.2 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3.0" upper="3.0" velocity="2" effort="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.025 0.05 0.0" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" velocity="2" effort="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 -0.03 0.455" rpy="0 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="-2.8" upper="2.8" velocity="2" effort="1"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.32 0 0.035" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-3.1" upper="3.1" velocity="2" effort="1"/></joint>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2.0" upper="2.0" velocity="2" effort="1"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/>
    <origin xyz="0.08 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-6.0" upper="6.0" velocity="2" effort="1"/></joint>
  <joint name="tool" type="fixed"><parent link="l6"/><child link="tip"/>
    <origin xyz="0.1 0.02 0.05" rpy="0.3 0.2 0.1"/></joint>
</robot>
"""


@functools.cache
def _arm(name):
    return load_serial_arm(name)


@pytest.fixture(scope="module")
def offset_arm(tmp_path_factory):
    path = tmp_path_factory.mktemp("urdf") / "offset6r.urdf"
    path.write_text(_OFFSET_URDF)
    return load_serial_arm(path, tool_frame="tip")


@pytest.fixture(params=["vs060_drill", "offset6r"])
def arm(request, offset_arm):
    return offset_arm if request.param == "offset6r" else _arm(request.param)






def test_vs060_has_a_spherical_wrist_at_the_urdf_point():
    kin = spherical_wrist_kinematics(_arm("vs060_drill"))
    assert kin is not None
    # robots/vs060_drill.urdf: joint 4 at x = -0.01; joints 1-6 stacked along z
    np.testing.assert_allclose(kin.wrist, [-0.01, 0.0, 0.1815 + 0.1635 + 0.305 + 0.1645
                                           + 0.1355], atol=1e-12)
    solver = IKSolver(_arm("vs060_drill"))
    assert solver.method == "closed_form" and solver.ur is None
    assert IKSolver(_arm("vs060_drill"), IKParams(method="dls")).spherical is None


def test_arms_without_a_spherical_wrist_are_not_detected():
    assert spherical_wrist_kinematics(_arm("ur5")) is None  # wrist axes do not meet
    assert spherical_wrist_kinematics(_arm("panda")) is None  # 7 joints
    with pytest.raises(ParameterError, match="no closed form"):
        IKSolver(_arm("panda"), IKParams(method="closed_form"))


def test_exponential_fk_matches_pinocchio(arm):
    kin = spherical_wrist_kinematics(arm)
    assert kin is not None
    qs = np.random.default_rng(7).uniform(-TWO_PI, TWO_PI, size=(25, 6))
    np.testing.assert_allclose(kin.fk(qs), np.array([arm.fk(q) for q in qs]), atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_random_reachable_poses_are_solved_exactly(arm, seed):
    """40 poses from random configurations within the limits, per seed."""
    solver = IKSolver(arm)
    assert solver.method == "closed_form"
    rng = np.random.default_rng(1000 + seed)
    for q_true in rng.uniform(arm.limits.lower, arm.limits.upper, size=(40, 6)):
        pose = arm.fk(q_true)
        sols = solver.solve(pose)
        assert np.abs(sols - q_true).max(axis=1).min() < 1e-6  # the generator, exactly
        for q in sols:
            assert arm.within_limits(q)
            dp, dr = _fk_error(arm, q, pose)
            assert dp < 1e-6 and dr < 1e-6
        canon = solver.solve_canonical(pose)
        assert 1 <= len(canon) <= 8
        for a, b in itertools.combinations(canon, 2):
            assert _mod_distance(a, b) > 1e-4
        assert len(sols) == sum(_alternative_count(arm, q) for q in canon)


@pytest.mark.parametrize("seed", range(3))
def test_closed_form_finds_every_solution_dense_dls_finds(arm, seed):
    rng = np.random.default_rng(2000 + seed)
    q_true = rng.uniform(arm.limits.lower * 0.9, arm.limits.upper * 0.9)
    pose = arm.fk(q_true)
    closed = IKSolver(arm).solve_canonical(pose)
    dls = IKSolver(arm, IKParams(method="dls", starts=600)).solve_canonical(pose, seed=seed)
    assert len(dls) >= 1
    for q in dls:
        assert min(_mod_distance(q, c) for c in closed) < 1e-6
    assert len(closed) >= len(dls)


@pytest.mark.parametrize("q4", [0.0, 0.7, -2.0])
def test_wrist_singularity_reaches_the_pose(arm, q4):
    """q5 = 0 aligns axes 4 and 6 on both arms: only q4 + q6 is determined."""
    q_true = np.array([0.3, 0.4, 0.9, q4, 0.0, 0.5])
    pose = arm.fk(q_true)
    canon = IKSolver(arm).solve_canonical(pose)
    assert len(canon) >= 1
    for q in canon:
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6
    same_arm = [q for q in canon if _mod_distance(q[:3], q_true[:3]) < 1e-6
                and abs(q[4]) < 1e-6]
    assert len(same_arm) == 1
    assert _mod_distance([same_arm[0][3] + same_arm[0][5]], [q4 + 0.5]) < 1e-6


@pytest.mark.parametrize("wrap", [True, False])
def test_batched_targets_equal_per_pose_solutions(wrap):
    arm = _arm("vs060_drill")
    rng = np.random.default_rng(5)
    rows = []
    for q in rng.uniform(arm.limits.lower * 0.7, arm.limits.upper * 0.7, size=(6, 6)):
        tool = arm.fk(q)
        rows.append(np.concatenate([tool[:3, 3] + 0.01 * tool[:3, 2], tool[:3, 2]]))
    far = np.array([3.0, 0.0, 0.0, 0.0, 0.0, 1.0])  # out of reach
    targets = make_targets(np.array(rows + [far]), axis_step=45, standoff=0.01)
    solver = IKSolver(arm, IKParams(wrap_alternatives=wrap))
    result = solver.solve_targets(targets.poses)
    assert result.unreachable() == [len(rows)]
    for i, block in enumerate(targets.poses):
        per_pose = [solver.solve(p) for p in block]
        expected = np.concatenate(per_pose)
        index = np.repeat(np.arange(len(block)), [len(s) for s in per_pose])
        np.testing.assert_allclose(result.configurations[i], expected, atol=0, rtol=0)
        np.testing.assert_array_equal(result.pose_index[i], index)


def test_failed_fk_check_falls_back_to_dls(monkeypatch):
    arm = _arm("vs060_drill")
    original = SphericalWristKinematics.fk

    def shifted(self, q):
        out = original(self, q)
        out[:, 0, 3] += 1e-6
        return out

    monkeypatch.setattr(SphericalWristKinematics, "fk", shifted)
    assert spherical_wrist_kinematics(arm) is None
    assert IKSolver(arm).method == "dls"


def test_failed_solve_check_falls_back_to_dls(monkeypatch):
    arm = _arm("vs060_drill")
    original = SphericalWristKinematics.solve_batch

    def lossy(self, poses):
        sol, valid = original(self, poses)
        sol[:, :, 2] += 0.1  # a wrong elbow angle on every branch
        return sol, valid

    monkeypatch.setattr(SphericalWristKinematics, "solve_batch", lossy)
    assert spherical_wrist_kinematics(arm) is None


def test_candidates_missing_the_pose_are_polished_or_dropped(monkeypatch):
    """A candidate 1e-4 rad off is brought back by Newton steps; one far off is dropped."""
    arm = _arm("vs060_drill")
    solver = IKSolver(arm)
    q_true = np.array([0.2, 0.3, 1.0, 0.4, 0.9, -0.6])
    pose = arm.fk(q_true)
    exact = solver.solve_canonical(pose)
    original = SphericalWristKinematics.solve_batch

    def perturbed(self, poses):
        sol, valid = original(self, poses)
        sol[:, 0, 0] += 1e-4
        sol[:, 1] += [1.5, -1.0, 1.0, 2.0, -1.0, 1.0]  # 5 Newton steps do not mend this
        return sol, valid

    monkeypatch.setattr(solver.spherical.__class__, "solve_batch", perturbed)
    got = solver.solve_canonical(pose)
    assert len(got) == len(exact) - 1
    for q in got:
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-9 and dr < 1e-9


def test_kinematics_fields_are_validated():
    with pytest.raises(ParameterError, match="axes"):
        SphericalWristKinematics(np.zeros((5, 3)), np.zeros((6, 3)), np.zeros(3), np.eye(4))
    with pytest.raises(ParameterError, match="home"):
        SphericalWristKinematics(np.zeros((6, 3)), np.zeros((6, 3)), np.zeros(3),
                                 np.full((4, 4), np.nan))


def test_cos_sin_roots_solve_their_equation():
    rng = np.random.default_rng(3)
    a, b, c = rng.normal(size=(3, 200))
    roots, ok = ik_module._cos_sin_roots(a, b, c)
    assert ok.tolist() == (np.abs(c) <= np.hypot(a, b)).tolist()
    for k in range(2):
        t = roots[ok, k]
        np.testing.assert_allclose(a[ok] * np.cos(t) + b[ok] * np.sin(t), c[ok], atol=1e-12)


@pytest.mark.bench
def test_robotsp_holes_closed_form_finds_every_dls_solution():
    """On RoboTSP's 245 holes (45 degree step, 0.01 m standoff) the closed form's set
    contains the 64-start DLS set of every candidate pose."""
    path = SHARED_DATA / "robotsp" / "targets.csv"
    if not path.is_file():
        pytest.skip(f"shared data not found at {path}")
    arm = _arm("vs060_drill")
    rows = np.loadtxt(path, delimiter=",", skiprows=1)
    targets = make_targets(rows, axis_step=45, standoff=0.01)
    params = IKParams(wrap_alternatives=False)
    closed = IKSolver(arm, params).solve_targets(targets.poses)
    dls_params = IKParams(method="dls", wrap_alternatives=False)
    dls = IKSolver(arm, dls_params).solve_targets(targets.poses)
    assert closed.method == "closed_form" and dls.method == "dls"
    for i in range(len(rows)):
        for q, j in zip(dls.configurations[i], dls.pose_index[i], strict=True):
            mine = closed.configurations[i][closed.pose_index[i] == j]
            assert min(_mod_distance(q, c) for c in mine) < 1e-6
        for q, j in zip(closed.configurations[i], closed.pose_index[i], strict=True):
            dp, dr = _fk_error(arm, q, targets.poses[i][j])
            assert dp < 1e-6 and dr < 1e-6


def test_shoulder_singularity_returns_solutions_that_reach_the_pose():
    """Wrist centre on axis 1 (q1 free): the closed form still returns exact solutions."""
    from scipy.optimize import brentq

    arm = _arm("vs060_drill")
    kin = spherical_wrist_kinematics(arm)

    def wrist_x(q2):
        q = np.array([0.0, q2, 1.0, 0.0, 0.0, 0.0])
        return (kin.fk(q)[0] @ np.linalg.inv(kin.home) @ np.append(kin.wrist, 1.0))[0]

    q2 = brentq(wrist_x, -1.0, 1.0, xtol=1e-15)
    q_true = np.array([0.3, q2, 1.0, 0.4, 0.8, -0.2])
    pose = arm.fk(q_true)
    canon = IKSolver(arm).solve_canonical(pose)
    assert len(canon) >= 2
    for q in canon:
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6


@pytest.mark.fuzz
def test_fuzz_spherical_closed_form_contains_the_generating_configuration(offset_arm):
    import os

    rng = np.random.default_rng(int(os.environ.get("FUZZ_SEED", "0")))
    for arm in (_arm("vs060_drill"), offset_arm):
        solver = IKSolver(arm)
        for _ in range(int(os.environ.get("FUZZ_EXAMPLES", "200"))):
            q_true = rng.uniform(arm.limits.lower, arm.limits.upper)
            pose = arm.fk(q_true)
            full = solver.solve(pose)
            assert np.abs(full - q_true).max(axis=1).min() < 1e-6
            for q in full:
                dp, dr = _fk_error(arm, q, pose)
                assert dp < 1e-6 and dr < 1e-6

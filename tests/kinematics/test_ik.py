"""Tests of subtask_opt.kinematics.ik: every IK solution, closed form (UR) and DLS."""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest

from subtask_opt.arm.poses import load_targets, make_targets
from subtask_opt.base.errors import ParameterError
from subtask_opt.kinematics.ik import IKParams, IKSolver, ur_kinematics
from subtask_opt.kinematics.serial import load_serial_arm
from tests.conftest import SHARED_DATA

TWO_PI = 2 * math.pi


@functools.cache
def _arm(name):
    return load_serial_arm(name)


def _fk_error(arm, q, pose):
    """Position and rotation error of Pinocchio's FK at q from pose (own formula)."""
    reached = arm.fk(q)
    dp = np.linalg.norm(reached[:3, 3] - pose[:3, 3])
    rel = pose[:3, :3].T @ reached[:3, :3]
    skew = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
    dr = math.atan2(np.linalg.norm(skew) / 2, (np.trace(rel) - 1) / 2)
    return dp, dr


def _mod_distance(a, b):
    d = np.abs(np.asarray(a) - np.asarray(b)) % TWO_PI
    return float(np.minimum(d, TWO_PI - d).max())


def _same_set_mod_2pi(a, b, tol=1e-6):
    """Whether two solution arrays hold the same configurations modulo 2 pi."""
    if len(a) != len(b):
        return False
    return all(min(_mod_distance(x, y) for y in b) < tol for x in a) and all(
        min(_mod_distance(y, x) for x in a) < tol for y in b)


def _alternative_count(arm, q):
    """Brute force: values q_j + 2 pi k (|k| <= 3) inside the limits, multiplied over joints."""
    lim = arm.limits
    total = 1
    for j in range(arm.nq):
        total *= sum(1 for k in range(-3, 4)
                     if lim.lower[j] - 1e-9 <= q[j] + TWO_PI * k <= lim.upper[j] + 1e-9)
    return total


@pytest.mark.parametrize("name", ["ur3", "ur5", "ur10"])
def test_ur_dh_table_matches_pinocchio(name):
    arm = _arm(name)
    kin = ur_kinematics(arm)
    assert kin is not None
    rng = np.random.default_rng(123)  # not the seed of the internal check
    for q in rng.uniform(-TWO_PI, TWO_PI, size=(30, 6)):
        np.testing.assert_allclose(kin.fk(q), arm.fk(q), atol=1e-10)


def test_arms_without_ur_structure_have_no_closed_form():
    assert ur_kinematics(_arm("vs060_drill")) is None
    assert ur_kinematics(_arm("panda")) is None
    with pytest.raises(ParameterError, match="no closed form"):
        IKSolver(_arm("panda"), IKParams(method="closed_form"))


def _generic_ur5_pose(seed):
    """A random tool0 pose well inside the UR5's workspace, and a configuration reaching it.

    The flange lies 0.3-0.55 m from the shoulder, at least 0.25 m off the base axis:
    every (shoulder, wrist) branch then puts the wrist-1 centre within
    0.55 + d5 + d6 = 0.73 m < |a2| + |a3| = 0.817 m of the shoulder, so all eight
    elbow solutions exist (a generic pose, no singularity by construction).
    """
    rng = np.random.default_rng(seed)
    arm = _arm("ur5")
    shoulder = arm.fk_se3(np.zeros(6), arm.model.getFrameId("shoulder_link")).translation
    while True:
        direction = rng.normal(size=3)
        point = shoulder + rng.uniform(0.3, 0.55) * direction / np.linalg.norm(direction)
        if np.hypot(point[0], point[1]) > 0.25:
            break
    quat = rng.normal(size=4)
    x, y, z, w = quat / np.linalg.norm(quat)
    pose = np.eye(4)
    pose[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    pose[:3, 3] = point
    return pose


@pytest.mark.parametrize("seed", range(8))
def test_ur5_closed_form_gives_eight_solutions_that_reach_the_pose(seed):
    arm = _arm("ur5")
    solver = IKSolver(arm)
    assert solver.method == "closed_form"
    pose = _generic_ur5_pose(seed)
    canon = solver.solve_canonical(pose)
    assert canon.shape == (8, 6)
    for q in canon:
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6
        assert arm.within_limits(q)
    # pairwise distinct modulo 2 pi
    for a, b in itertools.combinations(canon, 2):
        assert _mod_distance(a, b) > 1e-4


def test_ur5_closed_form_contains_the_configuration_that_made_the_pose():
    arm = _arm("ur5")
    rng = np.random.default_rng(11)
    for q_true in rng.uniform(-math.pi, math.pi, size=(20, 6)):
        canon = IKSolver(arm).solve_canonical(arm.fk(q_true))
        assert min(_mod_distance(q, q_true) for q in canon) < 1e-6


@pytest.mark.parametrize("seed", range(2))
def test_ur5_alternatives_are_every_2pi_shift_within_limits(seed):
    arm = _arm("ur5")
    solver = IKSolver(arm)
    pose = _generic_ur5_pose(seed)
    canon = solver.solve_canonical(pose)
    full = solver.solve(pose)
    assert len(full) == sum(_alternative_count(arm, q) for q in canon)
    assert len(full) > len(canon)
    for q in full:
        assert arm.within_limits(q)
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6
    # no two alternatives are the same configuration
    for a, b in itertools.combinations(full, 2):
        assert np.abs(a - b).max() > 1e-6
    narrow = IKSolver(arm, IKParams(wrap_alternatives=False)).solve(pose)
    assert _same_set_mod_2pi(narrow, canon)


@pytest.mark.parametrize("seed", range(3))
def test_ur5_dls_finds_the_closed_form_set(seed):
    arm = _arm("ur5")
    pose = _generic_ur5_pose(seed)
    closed = IKSolver(arm).solve_canonical(pose)
    dls = IKSolver(arm, IKParams(method="dls", starts=120)).solve_canonical(pose, seed=seed)
    assert _same_set_mod_2pi(closed, dls)


def test_unreachable_pose_has_no_solution():
    pose = np.eye(4)
    pose[:3, 3] = [3.0, 0.0, 0.0]
    assert IKSolver(_arm("ur5")).solve(pose).shape == (0, 6)
    vs = IKSolver(_arm("vs060_drill"), IKParams(method="dls", starts=8, max_iter=30))
    assert vs.solve(pose).shape == (0, 6)


@pytest.mark.parametrize("seed", range(3))
def test_vs060_dls_solutions_reach_the_pose_within_limits(seed):
    arm = _arm("vs060_drill")
    rng = np.random.default_rng(100 + seed)
    q_true = rng.uniform(arm.limits.lower * 0.8, arm.limits.upper * 0.8)
    pose = arm.fk(q_true)
    solver = IKSolver(arm, IKParams(method="dls"))
    assert solver.method == "dls"
    sols = solver.solve(pose, seed=seed)
    assert len(sols) >= 1
    for q in sols:
        assert arm.within_limits(q)
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6
    assert min(np.abs(q - q_true).max() for q in sols) < 1e-6
    canon = solver.solve_canonical(pose, seed=seed)
    assert len(sols) == sum(_alternative_count(arm, q) for q in canon)
    for a, b in itertools.combinations(canon, 2):
        assert _mod_distance(a, b) > 1e-4


def test_solver_is_thread_safe():
    import threading

    arm = _arm("vs060_drill")
    solver = IKSolver(arm, IKParams(method="dls", starts=32))
    poses = [arm.fk(np.array([0.1 * k, 0.4, 1.2, 0.5, 0.8, -0.3])) for k in range(6)]
    expected = [solver.solve(p, seed=3) for p in poses]
    results = [None] * 8

    def work(k):
        results[k] = [solver.solve(p, seed=3) for p in poses[k % 6:] + poses[:k % 6]]

    threads = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, got in enumerate(results):
        for a, b in zip(got, expected[k % 6:] + expected[:k % 6], strict=True):
            np.testing.assert_array_equal(a, b)


def test_same_seed_same_solutions():
    arm = _arm("vs060_drill")
    pose = arm.fk(np.array([0.3, 0.4, 1.2, 0.5, 0.8, -0.3]))
    solver = IKSolver(arm, IKParams(method="dls", starts=16))
    np.testing.assert_array_equal(solver.solve(pose, seed=5), solver.solve(pose, seed=5))


def test_vs060_tool_axis_target_solution_set():
    arm = _arm("vs060_drill")
    # a reachable drilling ray: the tool point and z axis at a known configuration
    tool = arm.fk(np.radians([10, 20, 100, 0, 60, 0]))
    row = np.concatenate([tool[:3, 3] + 0.01 * tool[:3, 2], tool[:3, 2]])
    targets = make_targets(row[None], axis_step=45, standoff=0.01)
    np.testing.assert_allclose(targets.poses[0][0][:3, 3], tool[:3, 3], atol=1e-12)
    solver = IKSolver(arm, IKParams(method="dls", starts=32))
    result = solver.solve_targets(targets.poses, seed=0)
    configs, index = result.configurations[0], result.pose_index[0]
    assert result.method == "dls"
    assert len(configs) > 0
    for q, j in zip(configs, index, strict=True):
        pose = targets.poses[0][j]
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6
        # the tool axis is the same for every sample
        np.testing.assert_allclose(arm.fk(q)[:3, 2], row[3:] / np.linalg.norm(row[3:]),
                                   atol=1e-6)
    # the set is the union of the per-sample solutions
    per_sample = [solver.solve(p, seed=[0, 0, j]) for j, p in enumerate(targets.poses[0])]
    assert len(configs) == sum(len(s) for s in per_sample)
    assert result.counts.tolist() == [len(configs)]


def test_ur5_tool_axis_target_has_every_sample_solved():
    arm = _arm("ur5")
    pose = _generic_ur5_pose(9)
    row = np.concatenate([pose[:3, 3], pose[:3, 2]])
    targets = make_targets(row[None], axis_step=90)
    result = IKSolver(arm).solve_targets(targets.poses)
    index = result.pose_index[0]
    assert sorted(set(index.tolist())) == [0, 1, 2, 3]
    for q, j in zip(result.configurations[0], index, strict=True):
        dp, dr = _fk_error(arm, q, targets.poses[0][j])
        assert dp < 1e-6 and dr < 1e-6


def test_panda_dls_solutions_reach_the_pose():
    arm = _arm("panda")
    q_true = np.array([0.2, 0.3, -0.1, -1.8, 0.2, 2.0, 0.5])
    pose = arm.fk(q_true)
    sols = IKSolver(arm, IKParams(starts=12)).solve(pose, seed=1)
    assert len(sols) >= 1
    for q in sols:
        assert arm.within_limits(q)
        dp, dr = _fk_error(arm, q, pose)
        assert dp < 1e-6 and dr < 1e-6


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"method": "newton"}, "method"),
    ({"starts": 0}, "starts"),
    ({"damping": -1.0}, "damping"),
    ({"dedup_tol": 0.0}, "dedup_tol"),
    ({"wrap_alternatives": 1}, "wrap_alternatives"),
])
def test_ik_params_validation(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        IKParams(**kwargs)


def test_solve_refuses_bad_poses():
    solver = IKSolver(_arm("ur5"))
    with pytest.raises(ParameterError, match="4x4"):
        solver.solve(np.eye(3))
    with pytest.raises(ParameterError, match="finite"):
        solver.solve(np.full((4, 4), np.nan))
    with pytest.raises(ParameterError, match="one per target; got ndarray"):
        solver.solve_targets(np.eye(4)[None, None])  # one array, not a sequence of blocks
    with pytest.raises(ParameterError, match="one per target; got Targets"):
        solver.solve_targets(make_targets(np.array([[0.4, 0.2, 0.3, 0, 0, -1.0]])))
    with pytest.raises(ParameterError, match="finite"):
        solver.solve_targets([np.full((1, 4, 4), np.nan)])


@pytest.mark.bench
def test_robotsp_targets_all_solutions_reach_their_poses():
    """Every IK solution of RoboTSP's 245 holes (45 degree step, 0.01 m standoff) is exact."""
    path = SHARED_DATA / "robotsp" / "targets.csv"
    if not path.is_file():
        pytest.skip(f"shared data not found at {path}")
    arm = _arm("vs060_drill")
    targets = load_targets(path, axis_step=45, standoff=0.01)
    result = IKSolver(arm).solve_targets(targets.poses, seed=0)
    for i, (configs, index) in enumerate(zip(result.configurations, result.pose_index,
                                             strict=True)):
        for q, j in zip(configs, index, strict=True):
            assert arm.within_limits(q)
            dp, dr = _fk_error(arm, q, targets.poses[i][j])
            assert dp < 1e-6 and dr < 1e-6
    counts = result.counts
    print(f"\nsolutions per target: mean {counts.mean():.1f}, min {counts.min()}, "
          f"max {counts.max()}, unreachable {len(result.unreachable())}")


@pytest.mark.parametrize("q", [[0.3, -1.0, 1.2, 0.4, 0.0, 0.5],   # wrist singularity
                               [0.3, -1.0, 0.0, 0.4, 1.0, 0.5],   # elbow stretched
                               [0.3, -1.0, 1.2, 0.4, math.pi, 0.5]])
def test_ur5_closed_form_at_singular_configurations_still_reaches_the_pose(q):
    arm = _arm("ur5")
    pose = arm.fk(np.array(q))
    canon = IKSolver(arm).solve_canonical(pose)
    assert len(canon) >= 1
    for sol in canon:
        dp, dr = _fk_error(arm, sol, pose)
        assert dp < 1e-6 and dr < 1e-6


@pytest.mark.fuzz
def test_fuzz_ur5_closed_form_contains_the_generating_configuration():
    import os

    arm = _arm("ur5")
    solver = IKSolver(arm)
    rng = np.random.default_rng(int(os.environ.get("FUZZ_SEED", "0")))
    for _ in range(int(os.environ.get("FUZZ_EXAMPLES", "60"))):
        q_true = rng.uniform(arm.limits.lower, arm.limits.upper)
        pose = arm.fk(q_true)
        full = solver.solve(pose)
        assert np.abs(full - q_true).max(axis=1).min() < 1e-6
        for q in full[:: max(1, len(full) // 16)]:
            dp, dr = _fk_error(arm, q, pose)
            assert dp < 1e-6 and dr < 1e-6


@pytest.mark.parametrize("seed", [-1, 1.5, "3", [1, -2]])
def test_bad_seeds_are_refused(seed):
    solver = IKSolver(_arm("vs060_drill"), IKParams(method="dls", starts=2))
    pose = _arm("vs060_drill").fk(np.zeros(6))
    with pytest.raises(ParameterError, match="seed"):
        solver.solve(pose, seed=seed)


@pytest.mark.parametrize("wrap", [False, True])
def test_ur_targets_batched_equal_the_per_pose_solutions(wrap):
    """solve_targets solves every pose of a UR arm in one numpy batch: the same set of
    solutions per target as solve() pose by pose (the per-pose closed form is the oracle),
    each reaching its pose by Pinocchio's FK."""
    arm = load_serial_arm("ur5")
    rng = np.random.default_rng(3)
    qs = rng.uniform(-math.pi, math.pi, (12, 6))
    rows = []
    for q in qs:
        pose = arm.fk(q)
        rows.append([*pose[:3, 3], *pose[:3, 2]])
    targets = make_targets(np.array(rows), axis_step=90.0)
    solver = IKSolver(arm, IKParams(wrap_alternatives=wrap))
    batched = solver.solve_targets(targets.poses)
    for i, block in enumerate(targets.poses):
        got = batched.configurations[i]
        ref = np.vstack([solver.solve(pose) for pose in block])
        assert got.shape == ref.shape
        key = lambda a: a[np.lexsort(a.round(7).T[::-1])]  # noqa: E731
        np.testing.assert_allclose(key(got), key(ref), atol=1e-7)
        for q, j in zip(got, batched.pose_index[i], strict=True):
            dp, dr = solver.pose_error(q, block[j])
            assert dp < 1e-9 and dr < 1e-9

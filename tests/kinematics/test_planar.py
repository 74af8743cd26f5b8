"""Tests of subtask_opt.kinematics.planar: model loading, FK/IK/Jacobian against Pinocchio,
reachability."""

from __future__ import annotations

import functools
import math
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.kinematics import _kernels as _k
from subtask_opt.kinematics.planar import (
    ROBOT_NAMES,
    Arm,
    CartesianLimits,
    JointLimits,
    load_planar_arm,
)

ROBOTS_DIR = Path(__file__).resolve().parents[2] / "robots"
LIMITS = JointLimits([-3.0, -2.5], [3.0, 2.5], [2.0, 2.0], [4.0, 4.0])
CART = CartesianLimits(1.0, 2.0, 3.0, 4.0)


@functools.cache
def _arm(name: str) -> Arm:
    return load_planar_arm(name)


@pytest.fixture(scope="module")
def arms() -> dict[str, Arm]:
    return {name: _arm(name) for name in ROBOT_NAMES}


def _custom_urdf(tmp_path: Path, *, axis2: str = "0 0 -1", yaw: float = 0.7,
                 xyz: str = "0.3 -0.2 0.1", axis1: str = "0 0 1") -> Path:
    """planar_2r with a moved/rotated base and a reversed elbow axis."""
    text = (ROBOTS_DIR / "planar_2r.urdf").read_text()
    text = text.replace('<origin xyz="0 0 0" rpy="0 0 0"/>\n    <parent link="world"/>',
                        f'<origin xyz="{xyz}" rpy="0 0 {yaw}"/>\n    <parent link="world"/>')
    text = text.replace('<child link="upper_arm"/>\n    <axis xyz="0 0 1"/>',
                        f'<child link="upper_arm"/>\n    <axis xyz="{axis1}"/>')
    text = text.replace('<child link="forearm"/>\n    <axis xyz="0 0 1"/>',
                        f'<child link="forearm"/>\n    <axis xyz="{axis2}"/>')
    path = tmp_path / "custom.urdf"
    path.write_text(text)
    return path


# ---------------------------------------------------------------- loading

def test_builtin_geometry_from_the_model(arms: dict[str, Arm]) -> None:
    asr = arms["asr_twodof"]
    np.testing.assert_allclose(asr.link_lengths, (0.089, 0.122), atol=1e-9)
    np.testing.assert_allclose(asr.base_xy, (0.044, 0.0), atol=1e-4)
    # The ground joint is turned by -1.57 rad, not -pi/2: the arm points 0.0008 rad off +x.
    assert asr.angle_offsets[0] == pytest.approx(math.pi / 2 - 1.57, abs=1e-12)
    assert asr.joint_limits.velocity.tolist() == [1.0, 1.0]
    assert asr.cartesian_limits.kv == 0.1 and asr.cartesian_limits.ka == 0.2
    assert asr.joint_limits.jerk is None
    ours = arms["planar_2r"]
    np.testing.assert_allclose(ours.link_lengths, (0.325, 0.275))
    assert ours.r_min == pytest.approx(0.05) and ours.r_max == pytest.approx(0.6)
    assert ours.joint_limits.jerk is not None
    assert "planar_2r" in repr(ours)


def test_kernel_parameters_are_a_named_tuple_of_the_arm(arms: dict[str, Arm]) -> None:
    for arm in arms.values():
        kin = arm.kinematics
        assert isinstance(kin, _k.ArmKinematics)
        assert all(type(v) is float for v in kin), kin  # one numba type per field
        assert (kin.l1, kin.l2) == arm.link_lengths
        assert (kin.base_x, kin.base_y) == tuple(arm.base_xy)
        assert (kin.a1, kin.a2) == arm.angle_offsets and (kin.s1, kin.s2) == arm.axis_signs
        assert [kin.lower1, kin.lower2] == arm.joint_limits.lower.tolist()
        assert [kin.upper1, kin.upper2] == arm.joint_limits.upper.tolist()
        # At q = 0 the tool angle is the forearm direction plus the offset.
        expected_phi = _k.wrap_angle(kin.a1 + kin.a2 + kin.phi_offset)
        assert _k.wrap_angle(arm.fk([0.0, 0.0])[2] - expected_phi) == pytest.approx(0, abs=1e-9)


def test_custom_urdf_with_json_beside(tmp_path: Path) -> None:
    urdf = _custom_urdf(tmp_path)
    shutil.copy(ROBOTS_DIR / "planar_2r.json", tmp_path / "custom.json")
    arm = load_planar_arm(urdf)
    assert arm.name == "custom"
    assert arm.axis_signs == (1.0, -1.0)
    np.testing.assert_allclose(arm.base_xy, (0.3, -0.2), atol=1e-12)
    assert arm.angle_offsets[0] == pytest.approx(0.7)
    _check_round_trip(arm, np.array([0.4, -0.9]))


def test_urdf_without_json_needs_limits(tmp_path: Path) -> None:
    urdf = _custom_urdf(tmp_path)
    with pytest.raises(ParameterError, match="acceleration"):
        load_planar_arm(urdf)
    with pytest.raises(ParameterError, match="Cartesian limits"):
        load_planar_arm(urdf, joint_limits=LIMITS)
    arm = load_planar_arm(urdf, joint_limits=LIMITS, cartesian_limits=CART)
    assert arm.cartesian_limits == CART


@pytest.mark.parametrize("name", ["planar_3r", "", "ASR_TWODOF"])
def test_unknown_robot_lists_the_names(name: str) -> None:
    with pytest.raises(ParameterError, match="planar_2r, asr_twodof"):
        load_planar_arm(name)


def test_bad_robot_files(tmp_path: Path) -> None:
    with pytest.raises(InputDataError, match="not found"):
        load_planar_arm(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link")
    with pytest.raises(InputDataError, match="cannot build"):
        load_planar_arm(bad, joint_limits=LIMITS, cartesian_limits=CART)
    urdf = _custom_urdf(tmp_path)
    (tmp_path / "custom.json").write_text('{"joint_limits": {"acceleration": [1, 1]},\n  oops}')
    with pytest.raises(InputDataError, match="line 2"):
        load_planar_arm(urdf)
    (tmp_path / "custom.json").write_text(
        '{"joint_limits": {"acceleration": [1, 1]}, "cartesian_limits": {"kv": 1, "ka": 0, '
        '"kw": 1, "kw_dot": 1}}')
    with pytest.raises(ParameterError, match="CartesianLimits.ka"):
        load_planar_arm(urdf)
    with pytest.raises(InputDataError, match="no frame 'nope'"):
        load_planar_arm(urdf, tip_frame="nope", joint_limits=LIMITS, cartesian_limits=CART)


def test_non_planar_urdf_rejected(tmp_path: Path) -> None:
    urdf = _custom_urdf(tmp_path, axis2="1 0 0")
    with pytest.raises(InputDataError, match="world z axis"):
        load_planar_arm(urdf, joint_limits=LIMITS, cartesian_limits=CART)


@pytest.mark.parametrize("kwargs, field", [
    ({"kv": 0.0}, "kv"), ({"ka": -1.0}, "ka"), ({"kw": float("nan")}, "kw"),
    ({"kw_dot": float("inf")}, "kw_dot"), ({"kv": "fast"}, "kv"),
])
def test_cartesian_limits_validated(kwargs: dict, field: str) -> None:
    values = {"kv": 1.0, "ka": 1.0, "kw": 1.0, "kw_dot": 1.0, **kwargs}
    with pytest.raises(ParameterError, match=f"CartesianLimits.{field}"):
        CartesianLimits(**values)


@pytest.mark.parametrize("kwargs, match", [
    ({"lower": [1.0, 0.0], "upper": [0.5, 1.0]}, "lower must be < upper"),
    ({"velocity": [1.0, 0.0]}, r"velocity must be in \[1e-06, 1e\+06\]"),
    ({"acceleration": [1.0, -2.0]}, r"acceleration must be in \[1e-06, 1e\+06\]"),
    ({"jerk": [1.0, 0.0]}, r"jerk must be in \[1e-06, 1e\+06\]"),
    ({"velocity": [1.0, 2.0, 3.0]}, "velocity must have 2 values"),
    ({"lower": [float("nan"), 0.0]}, "lower must be finite"),
    ({"acceleration": None}, "acceleration is required"),
])
def test_joint_limits_validated(kwargs: dict, match: str) -> None:
    values = {"lower": [-1.0, -1.0], "upper": [1.0, 1.0], "velocity": [1.0, 1.0],
              "acceleration": [1.0, 1.0], "jerk": None, **kwargs}
    with pytest.raises(ParameterError, match=match):
        JointLimits(**values)


# ---------------------------------------------------------------- kinematics

def _check_round_trip(arm: Arm, q: np.ndarray) -> None:
    """IK of FK(q) gives q on one branch, and every finite branch maps back to the point."""
    x, y, _ = arm.fk(q)
    sol = arm.ik([x, y])
    assert sol.shape == (2, 2)
    found = False
    for row in sol:
        if np.isfinite(row).all():
            np.testing.assert_allclose(arm.fk(row)[:2], (x, y), atol=1e-9)
            assert np.all(row >= arm.joint_limits.lower - 1e-9)
            assert np.all(row <= arm.joint_limits.upper + 1e-9)
            found |= bool(np.allclose(row, q, atol=1e-6))
    assert found, (q, sol)


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(ROBOT_NAMES), st.floats(0.0, 1.0), st.floats(0.02, 0.98))
def test_ik_round_trips_through_pinocchio(name: str, u1: float, u2: float) -> None:
    arm = _arm(name)
    lim = arm.joint_limits
    q = lim.lower + np.array([u1, u2]) * (lim.upper - lim.lower)
    _check_round_trip(arm, q)


def test_branch_convention(arms: dict[str, Arm]) -> None:
    """Row 0 (elbow-down) has the elbow right of the base->tip line, row 1 left of it."""
    for arm in arms.values():
        tip = arm.base_xy + np.array([0.7 * arm.r_max, 0.1 * arm.r_max])
        sol = arm.ik(tip)
        for branch, sign in ((0, -1.0), (1, 1.0)):
            pin.forwardKinematics(arm.model, arm.data, sol[branch])
            elbow = arm.data.oMi[2].translation[:2] - arm.base_xy
            links = arm.link_points(sol[branch])
            np.testing.assert_allclose(links, [arm.base_xy, elbow + arm.base_xy, tip], atol=1e-12)
            np.testing.assert_allclose(np.hypot(*np.diff(links, axis=0).T), arm.link_lengths)
            a = tip - arm.base_xy
            cross = a[0] * elbow[1] - a[1] * elbow[0]
            assert np.sign(cross) == sign


def test_ik_batch_shape_and_nan_rows(arms: dict[str, Arm]) -> None:
    arm = arms["planar_2r"]
    pts = np.array([[0.4, 0.1], [0.0, 0.0], [1.0, 0.0], [-0.545, -0.198]])
    sol = arm.ik(pts)
    assert sol.shape == (4, 2, 2)
    assert np.isfinite(sol[0]).all()
    assert np.isnan(sol[1]).all() and np.isnan(sol[2]).all()
    # Behind the base the shoulder's +-150 deg limit leaves one branch at most.
    assert np.isnan(sol[3]).all(axis=1).sum() == 1


def test_analytic_fk_and_jacobian_match_pinocchio(arms: dict[str, Arm]) -> None:
    rng = np.random.default_rng(0)
    for arm in arms.values():
        q = rng.uniform(arm.joint_limits.lower, arm.joint_limits.upper, size=(20, 2))
        fk = _k.fk_batch(arm.kinematics, q)
        jac = _k.jacobian_batch(arm.kinematics, q)
        for qi, fi, ji in zip(q, fk, jac, strict=True):
            ref = arm.fk(qi)
            np.testing.assert_allclose(fi[:2], ref[:2], atol=1e-12)
            assert abs(_k.wrap_angle(fi[2] - ref[2])) < 1e-9
            np.testing.assert_allclose(ji, arm.jacobian(qi), atol=1e-12)
            # Finite differences of Pinocchio's FK as a third method.
            h = 1e-6
            fd = np.column_stack([(arm.fk(qi + h * e)[:2] - arm.fk(qi - h * e)[:2]) / (2 * h)
                                  for e in np.eye(2)])
            np.testing.assert_allclose(ji, fd, atol=1e-8)


def test_analytic_kinematics_with_reversed_axis(tmp_path: Path) -> None:
    arm = load_planar_arm(_custom_urdf(tmp_path, axis1="0 0 -1", axis2="0 0 -1", yaw=-2.0),
                   joint_limits=LIMITS, cartesian_limits=CART)
    q = np.array([[0.3, -1.2], [-2.0, 2.2]])
    for qi, fi, ji in zip(q, _k.fk_batch(arm.kinematics, q), _k.jacobian_batch(arm.kinematics, q),
                          strict=True):
        np.testing.assert_allclose(fi[:2], arm.fk(qi)[:2], atol=1e-12)
        np.testing.assert_allclose(ji, arm.jacobian(qi), atol=1e-12)
        _check_round_trip(arm, qi)


def test_fk_rejects_bad_q(arms: dict[str, Arm]) -> None:
    with pytest.raises(ParameterError, match="q must be 2 finite"):
        arms["planar_2r"].fk([0.0, float("nan")])
    with pytest.raises(ParameterError, match="q must be 2 finite"):
        arms["planar_2r"].jacobian([0.0, 1.0, 2.0])


# ---------------------------------------------------------------- reachability

def test_reachable_and_check(arms: dict[str, Arm]) -> None:
    arm = arms["planar_2r"]
    assert arm.reachable([0.4, 0.0])
    assert not arm.reachable([0.7, 0.0])
    assert not arm.reachable([0.1, 0.0])  # inside the elbow-limit disc
    arm.check_reachable(np.array([[0.4, 0.0], [0.3, 0.2]]))


@pytest.mark.parametrize("point, match", [
    ([0.7, 0.1], r"subtask 1 at \(0.7, 0.1\) is beyond the reach.*r_max = 0.6"),
    ([0.01, 0.02], r"subtask 1 .* inside the unreachable inner disc.*r_min = 0.05"),
    ([0.12, 0.0], r"subtask 1 .* breaks the joint limits.*q2 = .* outside \[-2.531, 2.531\]"),
])
def test_check_reachable_names_the_subtask(arms: dict[str, Arm], point: list, match: str) -> None:
    with pytest.raises(UnreachableError, match=match):
        arms["planar_2r"].check_reachable(np.array([[0.4, 0.0], point, [0.3, 0.1]]))


def test_check_reachable_bad_arrays(arms: dict[str, Arm]) -> None:
    arm = arms["asr_twodof"]
    with pytest.raises(InputDataError, match="subtask 0 is not finite"):
        arm.check_reachable(np.array([[np.nan, 0.1], [0.1, 0.1]]))
    with pytest.raises(InputDataError, match="shape"):
        arm.check_reachable(np.zeros((3, 3)))

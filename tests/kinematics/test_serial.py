"""Tests of subtask_opt.kinematics.serial: loading serial arms, limits, tool frames, FK."""

from __future__ import annotations

import math
import threading
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.kinematics.serial import (
    SERIAL_ROBOT_NAMES,
    SerialLimits,
    load_serial_arm,
    pose_error,
    robots_dir,
)

ROBOTS = Path(__file__).resolve().parents[2] / "robots"


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' formula (independent of Pinocchio)."""
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    ex, ey, ez = np.eye(3)
    return _rot(ez, y) @ _rot(ey, p) @ _rot(ex, r)


def _urdf_chain_fk(urdf: Path, q: np.ndarray, tip: str) -> np.ndarray:
    """FK by composing the URDF's joint origins and axes directly from the XML."""
    root = ET.parse(urdf).getroot()
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}
    chain = []
    link = tip
    while link in by_child:
        joint = by_child[link]
        chain.append(joint)
        link = joint.find("parent").get("link")
    chain.reverse()
    t = np.eye(4)
    k = 0
    for joint in chain:
        origin = joint.find("origin")
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        rpy = [float(v) for v in origin.get("rpy", "0 0 0").split()]
        step = np.eye(4)
        step[:3, :3] = _rpy(*rpy)
        step[:3, 3] = xyz
        t = t @ step
        if joint.get("type") == "revolute":
            axis = np.array([float(v) for v in joint.find("axis").get("xyz").split()])
            rot = np.eye(4)
            rot[:3, :3] = _rot(axis, q[k])
            t = t @ rot
            k += 1
    return t


@pytest.mark.parametrize("name", SERIAL_ROBOT_NAMES)
def test_every_named_robot_loads_with_urdf_limits(name):
    arm = load_serial_arm(name)
    expected_nq = {"ur3": 6, "ur5": 6, "ur10": 6, "panda": 7, "vs060_drill": 6}[name]
    assert arm.nq == expected_nq
    root = ET.parse(arm.urdf_path).getroot()
    limits = {j.get("name"): j.find("limit") for j in root.findall("joint")
              if j.get("type") == "revolute"}
    for k, joint in enumerate(arm.joint_names):
        assert arm.limits.lower[k] == pytest.approx(float(limits[joint].get("lower")))
        assert arm.limits.upper[k] == pytest.approx(float(limits[joint].get("upper")))
        assert arm.limits.velocity[k] == pytest.approx(float(limits[joint].get("velocity")))


def test_default_tool_frame_is_the_last_frame():
    arm = load_serial_arm("ur5")
    assert arm.tool_frame == arm.model.frames[len(arm.model.frames) - 1].name == "tool0"
    assert load_serial_arm("vs060_drill").tool_frame == "drill_tip"


def test_vs060_fk_matches_the_urdf_composed_by_hand():
    arm = load_serial_arm("vs060_drill")
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.uniform(arm.limits.lower, arm.limits.upper)
        np.testing.assert_allclose(arm.fk(q), _urdf_chain_fk(arm.urdf_path, q, "drill_tip"),
                                   atol=1e-12)


def test_ur5_fk_matches_the_urdf_composed_by_hand():
    arm = load_serial_arm("ur5")
    rng = np.random.default_rng(8)
    for _ in range(10):
        q = rng.uniform(-3, 3, size=6)
        np.testing.assert_allclose(arm.fk(q), _urdf_chain_fk(arm.urdf_path, q, "tool0"),
                                   atol=1e-9)


def test_vs060_limit_sets():
    default = load_serial_arm("vs060_drill")
    robotsp = load_serial_arm("vs060_drill", limits="robotsp")
    np.testing.assert_array_equal(robotsp.limits.velocity, [1, 0.7, 0.7, 1, 0.7, 1.57])
    np.testing.assert_array_equal(robotsp.limits.acceleration, [5, 4.25, 4.25, 5.25, 6, 8])
    assert robotsp.limits.name == "robotsp"
    assert np.all(robotsp.limits.velocity < default.limits.velocity)
    np.testing.assert_array_equal(robotsp.limits.lower, default.limits.lower)
    with pytest.raises(ParameterError, match="unknown limit set 'fast'.*robotsp"):
        load_serial_arm("vs060_drill", limits="fast")


def test_limits_from_arguments_replace_the_files():
    arm = load_serial_arm("ur5", limits={"acceleration": [1, 2, 3, 4, 5, 6]})
    np.testing.assert_array_equal(arm.limits.acceleration, [1, 2, 3, 4, 5, 6])
    assert arm.limits.name == "arguments"
    with pytest.raises(ParameterError, match="acceleration must have 6 values"):
        load_serial_arm("ur5", limits={"acceleration": [1, 2]})


def test_missing_acceleration_is_named_when_required(tmp_path):
    # a URDF with no limits file beside it: URDF cannot hold acceleration limits
    urdf = tmp_path / "bare.urdf"
    urdf.write_text((robots_dir() / "vs060_drill.urdf").read_text())
    arm = load_serial_arm(urdf)
    assert arm.limits.acceleration is None
    with pytest.raises(InputDataError, match='"acceleration"'):
        arm.limits.require("acceleration")
    vs = load_serial_arm("vs060_drill")
    np.testing.assert_array_equal(vs.limits.require("acceleration"), vs.limits.acceleration)


def test_tool_offset_as_matrix_and_as_xyz_rpy():
    arm = load_serial_arm("ur5")
    xyz, rpy = [0.01, -0.02, 0.15], [0.1, -0.2, 0.3]
    offset = np.eye(4)
    offset[:3, :3] = _rpy(*rpy)
    offset[:3, 3] = xyz
    a1 = load_serial_arm("ur5", tool_offset=offset)
    a2 = load_serial_arm("ur5", tool_offset=(xyz, rpy))
    assert a1.tool_frame == "tool"
    q = np.array([0.3, -1.0, 1.2, -0.5, 0.7, 0.2])
    np.testing.assert_allclose(a1.fk(q), arm.fk(q) @ offset, atol=1e-12)
    np.testing.assert_allclose(a2.fk(q), arm.fk(q) @ offset, atol=1e-12)


@pytest.mark.parametrize("offset", [np.eye(3), 2 * np.eye(4), ([0, 0], [0, 0, 0]),
                                    np.full((4, 4), np.nan)])
def test_bad_tool_offset(offset):
    with pytest.raises(ParameterError, match="tool_offset"):
        load_serial_arm("ur5", tool_offset=offset)


def test_missing_tool_frame_names_the_frame_and_the_available_ones():
    with pytest.raises(InputDataError, match="no frame 'flange'.*available frames:.*tool0"):
        load_serial_arm("ur5", tool_frame="flange")


def _write_urdf(path: Path, joint1_limit: str, joint1_type: str = "revolute") -> Path:
    path.write_text(f"""<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
<joint name="j1" type="{joint1_type}"><parent link="a"/><child link="b"/>
<axis xyz="0 0 1"/>{joint1_limit}</joint>
<joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/>
<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="2" effort="1"/></joint>
</robot>""")
    return path


def test_urdf_without_limits_names_the_joint(tmp_path):
    urdf = _write_urdf(tmp_path / "nolimit.urdf", "")
    with pytest.raises(InputDataError, match="joint 'j1' \\(revolute\\) needs <limit> with "
                                             "lower, upper, velocity"):
        load_serial_arm(urdf)


def test_urdf_without_velocity_names_velocity(tmp_path):
    urdf = _write_urdf(tmp_path / "novel.urdf", '<limit lower="-1" upper="1" effort="1"/>')
    with pytest.raises(InputDataError, match="'j1'.*velocity"):
        load_serial_arm(urdf)


def test_continuous_joint_is_refused(tmp_path):
    urdf = _write_urdf(tmp_path / "cont.urdf", "", joint1_type="continuous")
    with pytest.raises(InputDataError, match="'j1' is continuous"):
        load_serial_arm(urdf)


def test_urdf_path_with_json_beside_it(tmp_path):
    urdf = _write_urdf(tmp_path / "two.urdf", '<limit lower="-2" upper="2" velocity="3" '
                                              'effort="1"/>')
    (tmp_path / "two.json").write_text('{"joint_limits": {"acceleration": [4, 5]}}')
    arm = load_serial_arm(urdf)
    assert arm.name == "two" and arm.nq == 2
    np.testing.assert_array_equal(arm.limits.acceleration, [4, 5])
    np.testing.assert_array_equal(arm.limits.velocity, [3, 2])
    # tip of a 2R arm with a 1 m link at q = (q1, 0) sits at (cos q1, sin q1, 0)
    np.testing.assert_allclose(arm.fk([0.5, 0.0])[:3, 3], [math.cos(0.5), math.sin(0.5), 0],
                               atol=1e-12)


def test_unknown_name_and_missing_file():
    with pytest.raises(ParameterError, match="unknown robot 'kuka'"):
        load_serial_arm("kuka")
    with pytest.raises(InputDataError, match="URDF file not found"):
        load_serial_arm("/nonexistent/robot.urdf")


def test_bad_q_is_refused():
    arm = load_serial_arm("ur5")
    with pytest.raises(ParameterError, match="6 finite joint values"):
        arm.fk([0.0] * 5)
    with pytest.raises(ParameterError, match="6 finite joint values"):
        arm.fk([0.0] * 5 + [math.nan])


def test_fk_is_thread_safe():
    arm = load_serial_arm("vs060_drill")
    rng = np.random.default_rng(3)
    qs = rng.uniform(arm.limits.lower, arm.limits.upper, size=(300, 6))
    expected = np.array([arm.fk(q) for q in qs])
    results: list[np.ndarray | None] = [None] * 8
    barrier = threading.Barrier(8)

    def work(k: int) -> None:
        barrier.wait()
        order = np.roll(np.arange(len(qs)), 37 * k)  # threads visit q in different orders
        out = np.empty_like(expected)
        for i in order:
            out[i] = arm.fk(qs[i])
        results[k] = out

    threads = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for out in results:
        np.testing.assert_array_equal(out, expected)


@pytest.mark.parametrize(("field", "value", "match"), [
    ("lower", [0.0, 2.0], "lower must be < upper"),
    ("velocity", [1.0, 0.0], r"velocity must be in \[1e-06, 1e\+06\]"),
    ("velocity", [1.0], "velocity must have 2 values"),
    ("acceleration", [1.0, math.inf], "acceleration must be finite"),
])
def test_serial_limits_validation(field, value, match):
    kwargs = {"lower": [-1.0, -1.0], "upper": [1.0, 1.0], "velocity": [1.0, 1.0]}
    kwargs[field] = value
    with pytest.raises(ParameterError, match=match):
        SerialLimits(**kwargs)


def test_pose_error_of_known_offsets():
    a = np.eye(4)
    b = np.eye(4)
    b[:3, :3] = _rot(np.array([1.0, 1.0, 0.0]), 0.3)
    b[:3, 3] = [0.0, 3.0, 4.0]
    dp, dr = pose_error(a, b)
    assert dp == pytest.approx(5.0)
    assert dr == pytest.approx(0.3)
    assert pose_error(b, b)[1] < 1e-12


def test_shipped_licence_files_are_present():
    for name in ("vs060_drill.urdf", "vs060_drill.json", "LICENSE-robotsp.txt",
                 "LICENSE-denso.txt"):
        assert (ROBOTS / name).is_file(), name


def test_tool_offset_on_a_urdf_that_already_has_a_tool_frame():
    urdf = ROBOTS / "planar_2r.urdf"
    plain = load_serial_arm(urdf, tool_frame="tool")
    shifted = load_serial_arm(urdf, tool_frame="tool", tool_offset=([0.1, 0, 0], [0, 0, 0]))
    assert shifted.tool_frame == "tool_offset"
    q = np.array([0.4, -0.7])
    expected = plain.fk(q)
    expected[:3, 3] += expected[:3, 0] * 0.1
    np.testing.assert_allclose(shifted.fk(q), expected, atol=1e-12)

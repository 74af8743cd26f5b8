"""Tests of subtask_opt.cell.scene: box scenes, self-collision, swept legs."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.cell.scene import Box, CollisionChecker, Scene
from subtask_opt.kinematics.serial import load_serial_arm
from tests.conftest import SHARED_DATA


@functools.cache
def _arm(name):
    return load_serial_arm(name)


def _box_scene(center, half, name="b"):
    return Scene(boxes=(Box(name, np.asarray(center, float), np.asarray(half, float),
                            np.eye(3)),))


def _capsules(checker, q):
    """World segments (a, b) and radii of the checker's capsules at q, by FK of joint frames."""
    arm = checker.arm
    out = {}
    for obj in checker.geometry_model.geometryObjects:
        if obj.name.startswith("box:"):
            continue
        if obj.parentJoint == 0:
            frame = np.eye(4)
        else:
            frame = np.array(arm.fk_se3(q, arm.model.getFrameId(arm.model.names[obj.parentJoint]))
                             .homogeneous)
        place = np.array(obj.placement.homogeneous)
        half = obj.geometry.halfLength
        ends = [frame @ place @ np.array([0, 0, s * half, 1.0]) for s in (-1, 1)]
        out[obj.name] = (ends[0][:3], ends[1][:3], obj.geometry.radius)
    return out


def _segment_points(a, b, n=400):
    t = np.linspace(0, 1, n)[:, None]
    return a + t * (b - a)


def _segment_distance(s1, s2):
    """Distance between two segments: points of s1 (dense) to s2 (exact); error < 0.5 mm."""
    p = _segment_points(*s1, n=1000)
    a, b = s2
    ab = b - a
    t = np.clip(((p - a) @ ab) / max(float(ab @ ab), 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + t[:, None] * ab), axis=1).min())


def _box_distance(points, box):
    local = (points - box.center) @ box.rotation
    excess = np.maximum(np.abs(local) - box.half_extents, 0.0)
    return float(np.sqrt((excess ** 2).sum(-1)).min())


# ------------------------------------------------------------------ scene files

def test_robotsp_obstacles_load():
    path = SHARED_DATA / "robotsp" / "obstacles.json"
    if not path.is_file():
        pytest.skip(f"shared data not found at {path}")
    scene = Scene.load(path)
    assert [b.name for b in scene.boxes] == ["panel", "robot_pedestal"]
    np.testing.assert_array_equal(scene.boxes[0].half_extents, [0.027, 0.35, 0.35])


def test_scene_with_rotation_and_bom(tmp_path):
    c, s = math.cos(0.3), math.sin(0.3)
    rot = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    doc = {"boxes": [{"name": "tilted", "center": [1, 0, 0], "half_extents": [0.5, 0.1, 0.1],
                      "rotation": rot}]}
    path = tmp_path / "s.json"
    path.write_text("\ufeff" + json.dumps(doc), encoding="utf-8")
    box = Scene.load(path).boxes[0]
    # a point along the box's first axis is inside, one along the world x at that distance not
    assert box.contains(np.array([1, 0, 0]) + 0.45 * np.array([c, s, 0]))
    assert not box.contains([1.0, 0.45, 0.0])


@pytest.mark.parametrize(("doc", "match"), [
    ([], "'boxes', 'meshes' and/or 'tool'"),
    ({"boxes": {}}, "'boxes' must be a list"),
    ({"boxes": [{"name": "a", "center": [0, 0, 0]}]}, r"boxes\[0\] lacks the field "
                                                         "'half_extents'"),
    ({"boxes": [{"center": [0, 0], "half_extents": [1, 1, 1]}]}, r"boxes\[0\]\.center must be "
                                                                   "3 numbers"),
    ({"boxes": [{"center": [0, 0, 0], "half_extents": [1, -1, 1]}]},
     r"boxes\[0\]\.half_extents must be 3 numbers > 0"),
    ({"boxes": [{"center": [0, 0, 0], "half_extents": [1, 1, 1],
                 "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}]},
     r"boxes\[0\]\.rotation must be a rotation"),
    ({"boxes": [{"center": [0, 0, 0], "half_extents": [1, 1, 1], "size": 2}]},
     r"boxes\[0\] has unknown field\(s\) \['size'\]"),
    ({"boxes": [{"name": "a", "center": [0, 0, 0], "half_extents": [1, 1, 1]},
                {"name": "a", "center": [0, 0, 0], "half_extents": [1, 1, 1]}]}, "unique"),
    ({"boxes": [{"name": 3, "center": [0, 0, 0], "half_extents": [1, 1, 1]}]},
     r"boxes\[0\]\.name"),
])
def test_malformed_scene_names_the_field(tmp_path, doc, match):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputDataError, match=match):
        Scene.load(path)


def test_scene_file_not_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{boxes: ")
    with pytest.raises(InputDataError, match="not valid JSON"):
        Scene.load(path)
    with pytest.raises(InputDataError, match="not found"):
        Scene.load(tmp_path / "missing.json")


# ------------------------------------------------------------------ collisions

@pytest.mark.parametrize("name", ["vs060_drill", "ur5"])
def test_box_around_the_tool_collides_and_a_far_box_does_not(name):
    arm = _arm(name)
    q = np.array([0.3, 0.5, 0.9, -0.4, 0.8, 0.2])
    tool = arm.fk(q)[:3, 3]
    near = _box_scene(tool, [0.03, 0.03, 0.03]).for_arm(arm)
    assert near.in_collision(q)
    pairs = near.colliding_pairs(q)
    assert pairs and all(b == "box:b" for _, b in pairs)
    far = _box_scene(tool + [3.0, 3.0, 3.0], [0.03, 0.03, 0.03]).for_arm(arm)
    assert not far.in_collision(q)
    # moving the arm away from the box clears the collision
    q_away = q.copy()
    q_away[0] += math.pi / 2
    assert not near.in_collision(q_away)


def test_vs060_uses_capsules_ur5_uses_meshes():
    assert Scene().for_arm(_arm("vs060_drill")).uses_capsules
    assert not Scene().for_arm(_arm("ur5")).uses_capsules


def test_self_collision_pairs_skip_same_and_adjacent_links():
    arm = _arm("vs060_drill")
    checker = Scene().for_arm(arm)
    names = {obj.name: obj.parentJoint for obj in checker.geometry_model.geometryObjects}
    parents = arm.model.parents
    assert checker.collision_pairs
    for a, b in checker.collision_pairs:
        ja, jb = names[a], names[b]
        assert ja != jb and parents[ja] != jb and parents[jb] != ja


def test_vs060_self_collision_agrees_with_brute_force_capsule_distances():
    arm = _arm("vs060_drill")
    checker = Scene().for_arm(arm)
    rng = np.random.default_rng(4)
    checked = hits = 0
    for q in rng.uniform(arm.limits.lower, arm.limits.upper, size=(150, 6)):
        caps = _capsules(checker, q)
        gaps = [_segment_distance(caps[a][:2], caps[b][:2]) - caps[a][2] - caps[b][2]
                for a, b in checker.collision_pairs]
        if min(abs(g) for g in gaps) < 2e-3:  # too close to call for the sampled oracle
            continue
        expected = min(gaps) < 0
        assert checker.in_collision(q) == expected, q
        checked += 1
        hits += expected
    assert checked > 100 and 0 < hits < checked


def test_vs060_boxes_agree_with_brute_force_point_distances():
    arm = _arm("vs060_drill")
    box = Box("b", np.array([0.35, 0.1, 0.5]), np.array([0.12, 0.08, 0.15]), np.eye(3))
    checker = CollisionChecker(arm, Scene(boxes=(box,)), self_collision=False)
    rng = np.random.default_rng(5)
    checked = hits = 0
    for q in rng.uniform(arm.limits.lower, arm.limits.upper, size=(150, 6)):
        caps = _capsules(checker, q)
        gaps = [_box_distance(_segment_points(a, b), box) - r
                for name, (a, b, r) in caps.items() if not name.startswith("universe")]
        if min(abs(g) for g in gaps) < 2e-3:
            continue
        expected = min(gaps) < 0
        assert checker.in_collision(q) == expected, q
        checked += 1
        hits += expected
    assert checked > 100 and 0 < hits < checked


def test_ur5_folded_elbow_collides_with_itself():
    arm = _arm("ur5")
    checker = Scene().for_arm(arm)
    assert not checker.in_collision(np.zeros(6))
    folded = np.array([0.0, 0.0, 3.1, 0.0, 0.0, 0.0])  # forearm folded onto the upper arm
    assert checker.in_collision(folded)
    assert any("upper_arm" in a or "upper_arm" in b for a, b in checker.colliding_pairs(folded))


def test_margin_makes_near_misses_collide():
    from subtask_opt.arm.poses import axis_frame

    arm = _arm("vs060_drill")
    q = np.array([0.3, 0.5, 0.9, -0.4, 0.8, 0.2])
    tool = arm.fk(q)[:3, 3]
    wrist = arm.fk_se3(q, arm.model.getFrameId("joint_6")).translation
    # the tool capsule runs from joint 6 towards the tool point and its surface ends there;
    # put a box face square to that direction 5 cm beyond the tool point
    u = (tool - wrist) / np.linalg.norm(tool - wrist)
    box = Box("b", tool + 0.15 * u, np.array([0.1, 0.1, 0.1]), axis_frame(u))
    scene = Scene(boxes=(box,))
    assert not scene.for_arm(arm, self_collision=False, margin=0.045).in_collision(q)
    assert scene.for_arm(arm, self_collision=False, margin=0.055).in_collision(q)


# ------------------------------------------------------------------ legs

def _geometry_points(checker):
    """Test points on every moving robot geometry, in its joint frame: (joint, (k, 3))."""
    out = []
    for obj in checker.geometry_model.geometryObjects:
        if obj.name.startswith("box:") or obj.parentJoint == 0:
            continue
        geometry = obj.geometry
        if hasattr(geometry, "halfLength"):
            h, r = geometry.halfLength, geometry.radius
            local = np.array([[sx * r, sy * r, sz * (h + r * (sx == sy == 0))]
                              for sx in (-1, 0, 1) for sy in (-1, 0, 1) for sz in (-1, 1)])
        else:
            local = np.array(geometry.vertices())[::15] if hasattr(geometry, "vertices") else (
                np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
                * geometry.halfSide)
        place = np.array(obj.placement.homogeneous)
        pts = (place[:3, :3] @ local.T).T + place[:3, 3]
        out.append((obj.parentJoint, pts))
    return out


def _world_points(arm, q, points):
    import pinocchio as pin

    data = arm.model.createData()
    pin.forwardKinematics(arm.model, data, q)
    return np.concatenate([(np.array(data.oMi[j].rotation) @ p.T).T
                           + np.array(data.oMi[j].translation) for j, p in points])


@pytest.mark.parametrize("name", ["vs060_drill", "ur5"])
def test_no_point_moves_more_than_the_clearance_between_leg_samples(name):
    arm = _arm(name)
    checker = Scene().for_arm(arm)
    points = _geometry_points(checker)
    rng = np.random.default_rng(6)
    clearance = 0.02
    for _ in range(3):
        q0 = rng.uniform(arm.limits.lower, arm.limits.upper) * 0.5
        q1 = rng.uniform(arm.limits.lower, arm.limits.upper) * 0.5
        samples = checker.leg_samples(q0, q1, clearance)
        np.testing.assert_array_equal(samples[0], q0)
        np.testing.assert_allclose(samples[-1], q1, atol=1e-15)
        worst = 0.0
        for a, b in zip(samples[:-1], samples[1:], strict=True):
            # path length of every point between two samples, by 8 sub-steps
            sub = [_world_points(arm, a + t * (b - a), points) for t in np.linspace(0, 1, 9)]
            travel = sum(np.linalg.norm(s1 - s0, axis=1) for s0, s1 in zip(sub[:-1], sub[1:],
                                                                          strict=True))
            worst = max(worst, float(travel.max()))
        assert worst <= clearance
        assert worst > clearance / 10  # the bound is not absurdly loose


def test_leg_through_a_box_collides_though_its_ends_are_free():
    arm = _arm("vs060_drill")
    q0 = np.array([-0.8, 0.3, 1.2, 0.0, 0.9, 0.0])
    q1 = np.array([0.8, 0.3, 1.2, 0.0, 0.9, 0.0])
    middle = arm.fk((q0 + q1) / 2)[:3, 3]
    checker = _box_scene(middle, [0.02, 0.02, 0.02]).for_arm(arm, self_collision=False)
    assert not checker.in_collision(q0) and not checker.in_collision(q1)
    assert checker.leg_in_collision(q0, q1, clearance=0.01)
    far = _box_scene(middle + [0, 0, 3], [0.02, 0.02, 0.02]).for_arm(arm)
    assert not far.leg_in_collision(q0, q1, clearance=0.01)


def test_leg_sample_count_follows_the_bound():
    arm = _arm("vs060_drill")
    checker = Scene().for_arm(arm)
    q0 = np.zeros(6)
    q1 = np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.0])
    n = len(checker.leg_samples(q0, q1, 0.01)) - 1
    assert n == math.ceil(0.5 * checker.sweep_radii[0] / 0.01)
    assert len(checker.leg_samples(q0, q0, 0.01)) == 2
    with pytest.raises(ParameterError, match="clearance"):
        checker.leg_samples(q0, q1, 0.0)


def test_checker_parameters_are_validated():
    with pytest.raises(ParameterError, match="link_radius"):
        CollisionChecker(_arm("vs060_drill"), link_radius=-1.0)
    with pytest.raises(ParameterError, match="margin"):
        CollisionChecker(_arm("vs060_drill"), margin=math.nan)


def test_robotsp_home_is_free_in_the_robotsp_scene():
    path = SHARED_DATA / "robotsp" / "obstacles.json"
    if not path.is_file():
        pytest.skip(f"shared data not found at {path}")
    arm = _arm("vs060_drill")
    checker = Scene.load(path).for_arm(arm)
    assert not checker.in_collision(np.radians([0, -20, 130, 0, 70, 0]))
    # every configuration putting the drill tip 3 cm deep into the panel hits the panel
    from subtask_opt.arm.poses import axis_poses
    from subtask_opt.kinematics.ik import IKParams, IKSolver

    poses = axis_poses([0.60, 0.0, 0.45], [1.0, 0.0, 0.0], axis_step=90)
    solver = IKSolver(arm, IKParams(starts=16))
    solutions = [q for pose in poses for q in solver.solve_canonical(pose, seed=0)]
    assert solutions
    for q in solutions:
        assert any(b == "box:panel" for _, b in checker.colliding_pairs(q))


def _urdf_with_mesh(folder, filename: str):
    urdf = folder / "robot.urdf"
    urdf.write_text(f"""<robot name="r"><link name="base"><collision><geometry>
        <mesh filename="{filename}"/></geometry></collision></link></robot>""")
    return urdf


@pytest.mark.parametrize("filename", [
    "file:///etc/passwd", "/etc/passwd", "../outside.stl", "meshes/../../outside.stl",
    "package://../outside.stl", "http://example.com/x.stl", "escape/link.stl"])
def test_mesh_paths_outside_the_robot_folders_are_refused(tmp_path, filename):
    from subtask_opt.cell.scene import confined_meshes

    robot = tmp_path / "robot"
    robot.mkdir()
    (tmp_path / "outside.stl").write_text("solid x\nendsolid x\n")
    (robot / "escape").mkdir()
    (robot / "escape" / "link.stl").symlink_to(tmp_path / "outside.stl")
    urdf = _urdf_with_mesh(robot, filename)
    with pytest.raises(InputDataError, match="mesh") as err:
        confined_meshes(urdf, [str(robot)])
    assert filename in str(err.value)


def test_mesh_paths_inside_the_robot_folders_are_kept(tmp_path):
    from subtask_opt.cell.scene import confined_meshes

    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "a.stl").write_text("solid a\nendsolid a\n")
    for name in ("meshes/a.stl", "package://meshes/a.stl"):
        assert confined_meshes(_urdf_with_mesh(tmp_path, name), [str(tmp_path)]) == [
            (tmp_path / "meshes" / "a.stl").resolve()]

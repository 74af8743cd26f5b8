"""Tests of subtask_opt.arm.poses: pose targets from CSV and JSON."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from subtask_opt.arm.poses import (
    axis_frame,
    axis_samples,
    load_targets,
    make_targets,
    quaternion_pose,
)
from subtask_opt.base.errors import InputDataError, ParameterError
from tests.conftest import SHARED_DATA

AXIS_CSV = "x,y,z,dx,dy,dz\n0.5,0.1,0.4,1,0,0\n0.3,-0.2,0.6,0,3,4\n"


def _write(tmp_path, name, text, encoding="utf-8"):
    path = tmp_path / name
    path.write_text(text, encoding=encoding)
    return path


def test_axis_targets_sample_the_free_rotation(tmp_path):
    targets = load_targets(_write(tmp_path, "t.csv", AXIS_CSV), axis_step=45, standoff=0.01)
    assert len(targets) == 2 and targets.n_candidates == 16
    assert targets.free_axis.tolist() == [True, True]
    for k, (point, axis) in enumerate([((0.5, 0.1, 0.4), (1, 0, 0)),
                                        ((0.3, -0.2, 0.6), (0, 0.6, 0.8))]):
        poses = targets.poses[k]
        assert poses.shape == (8, 4, 4)
        for pose in poses:
            rot = pose[:3, :3]
            np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
            assert np.linalg.det(rot) == pytest.approx(1.0)
            np.testing.assert_allclose(rot[:, 2], axis, atol=1e-12)
            # the tool point backs off 0.01 m against the axis
            np.testing.assert_allclose(pose[:3, 3], np.array(point) - 0.01 * np.array(axis),
                                       atol=1e-12)
        # consecutive samples turn the x axis by 45 degrees about the tool axis
        for a, b in zip(poses[:-1], poses[1:], strict=True):
            cos = float(a[:3, 0] @ b[:3, 0])
            sin = float(np.cross(a[:3, 0], b[:3, 0]) @ a[:3, 2])
            assert math.degrees(math.atan2(sin, cos)) == pytest.approx(45.0)


@pytest.mark.parametrize(("step", "count"), [(45, 8), (360, 1), (180, 2), (100, 4), (15, 24)])
def test_axis_sample_counts(step, count):
    angles = axis_samples(step)
    assert len(angles) == count
    assert np.all(np.degrees(angles) < 360.0)
    np.testing.assert_allclose(np.diff(np.degrees(angles)), step)


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 0, -1), (1, 1, 1), (0.2, -0.9, 0.1)])
def test_axis_frame_is_a_rotation_with_z_along_the_axis(axis):
    rot = axis_frame(axis)
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    np.testing.assert_allclose(rot[:, 2], np.array(axis) / np.linalg.norm(axis), atol=1e-12)


def test_full_pose_targets_match_pinocchio_quaternions(tmp_path):
    import pinocchio as pin

    rng = np.random.default_rng(2)
    rows = []
    for _ in range(5):
        q = rng.normal(size=4)
        rows.append([*rng.uniform(-1, 1, 3), *q])
    text = "x,y,z,qx,qy,qz,qw\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows)
    targets = load_targets(_write(tmp_path, "p.csv", text), standoff=0.02)
    assert targets.free_axis.tolist() == [False] * 5
    for row, poses in zip(rows, targets.poses, strict=True):
        assert poses.shape == (1, 4, 4)
        x, y, z, w = np.array(row[3:]) / np.linalg.norm(row[3:])
        expected = pin.Quaternion(w, x, y, z).toRotationMatrix()
        np.testing.assert_allclose(poses[0, :3, :3], expected, atol=1e-12)
        np.testing.assert_allclose(poses[0, :3, 3], np.array(row[:3]) - 0.02 * expected[:, 2],
                                   atol=1e-12)


def test_json_equals_csv(tmp_path):
    csv_targets = load_targets(_write(tmp_path, "t.csv", AXIS_CSV), axis_step=60)
    doc = {"targets": [{"position": [0.5, 0.1, 0.4], "axis": [1, 0, 0]},
                       {"position": [0.3, -0.2, 0.6], "axis": [0, 3, 4]}]}
    json_targets = load_targets(_write(tmp_path, "t.json", json.dumps(doc)), axis_step=60)
    for a, b in zip(csv_targets.poses, json_targets.poses, strict=True):
        np.testing.assert_array_equal(a, b)
    pose_doc = {"targets": [{"position": [0, 0, 1], "quaternion": [0, 0, 0, 1]}]}
    pose = load_targets(_write(tmp_path, "q.json", json.dumps(pose_doc)))
    expected = np.eye(4)
    expected[2, 3] = 1.0
    np.testing.assert_array_equal(pose.poses[0][0], expected)


def test_utf8_bom_is_accepted(tmp_path):
    path = _write(tmp_path, "bom.csv", "\ufeff" + AXIS_CSV)
    assert len(load_targets(path)) == 2


@pytest.mark.parametrize(("text", "match"), [
    ("x,y,z,a,b,c\n1,2,3,1,0,0\n", "header must be"),
    ("x,y,z,dx,dy,dz\n1,2,3,1,0,0\n1,2,3,1,0\n", "row 2 of bad.csv has 5 columns"),
    ("x,y,z,dx,dy,dz\n1,2,3,1,0,0\n1,2,3,1,0,0\n1,nan,3,1,0,0\n", "row 3 of bad.csv holds NaN"),
    ("x,y,z,dx,dy,dz\n1,2,3,1,0,zero\n", "row 1 of bad.csv is not all numbers"),
    ("x,y,z,dx,dy,dz\n1,2,3,0,0,0\n", "row 1 of bad.csv: axis must be a non-zero"),
    ("x,y,z,dx,dy,dz\n", "no targets"),
    ("", "is empty"),
])
def test_bad_csv_names_the_row(tmp_path, text, match):
    with pytest.raises(InputDataError, match=match):
        load_targets(_write(tmp_path, "bad.csv", text))


@pytest.mark.parametrize(("doc", "match"), [
    ({"targets": []}, "at least one target"),
    ([1, 2], "must hold"),
    ({"targets": [{"position": [0, 0, 0]}]}, "target 0 of bad.json must be an object with"),
    ({"targets": [{"position": [0, 0, 0], "axis": [1, 0, 0]},
                  {"position": [0, 0, 0], "quaternion": [0, 0, 0, 1]}]}, "target 1.*one kind"),
    ({"targets": [{"position": [0, 0], "axis": [1, 0, 0]}]}, "'position' must be 3 numbers"),
    ({"targets": [{"position": [0, 0, 0], "quaternion": [0, 0, 0, 0]}]},
     "target 0 of bad.json: quaternion must be non-zero"),
])
def test_bad_json_names_the_target(tmp_path, doc, match):
    with pytest.raises(InputDataError, match=match):
        load_targets(_write(tmp_path, "bad.json", json.dumps(doc)))


def test_nan_in_json_is_refused(tmp_path):
    path = _write(tmp_path, "nan.json", '{"targets": [{"position": [0, NaN, 0], '
                                        '"axis": [1, 0, 0]}]}')
    with pytest.raises(InputDataError, match="nan.json: NaN is not a finite number"):
        load_targets(path)


def test_oversize_file_is_refused(tmp_path):
    path = _write(tmp_path, "big.csv", AXIS_CSV)
    with pytest.raises(InputDataError, match="bytes; the limit is 10"):
        load_targets(path, max_bytes=10)


@pytest.mark.parametrize(("kwargs", "match"), [({"axis_step": 0}, "axis_step"),
                                                ({"axis_step": 400}, "axis_step"),
                                                ({"standoff": math.nan}, "standoff")])
def test_bad_parameters(tmp_path, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        load_targets(_write(tmp_path, "t.csv", AXIS_CSV), **kwargs)


def test_targets_are_frozen_and_read_only():
    targets = make_targets(np.array([[0.5, 0.0, 0.4, 1.0, 0.0, 0.0]]))
    with pytest.raises(dataclasses.FrozenInstanceError):
        targets.standoff = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        targets.poses[0][0, 0, 0] = 2.0


def test_quaternion_pose_of_a_quarter_turn_about_z():
    s = math.sqrt(0.5)
    pose = quaternion_pose([1, 2, 3], [0, 0, s, s])
    np.testing.assert_allclose(pose[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)


def test_robotsp_targets():
    path = SHARED_DATA / "robotsp" / "targets.csv"
    if not path.is_file():
        pytest.skip(f"shared data not found at {path}")
    targets = load_targets(path, axis_step=45, standoff=0.01)
    assert len(targets) == 245
    assert targets.n_candidates == 245 * 8

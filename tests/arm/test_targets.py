"""Tests of subtask_opt.arm.targets: one target type, planar or 3-D, validated."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.arm.poses import make_targets
from subtask_opt.arm.targets import Targets, describe
from subtask_opt.base.errors import InputDataError, ParameterError

PTS = np.array([[0.1, 0.2], [0.3, -0.1], [0.25, 0.05], [0.15, 0.12]])
AXIS_ROWS = np.array([[0.4, 0.2, 0.3, 0.0, 0.0, -1.0], [0.5, 0.1, 0.3, 0.0, 0.0, -1.0]])


# ---------------------------------------------------------------- planar

def test_subtask_set_basics() -> None:
    s = Targets(PTS.tolist(), theta=[0.0, 1.0, 2.0, 3.0], name="demo")
    assert len(s) == 4 and s.points.dtype == np.float64
    assert not s.points.flags.writeable
    assert "demo" in repr(s)
    assert s.to_dict()["theta"] == [0.0, 1.0, 2.0, 3.0]


@pytest.mark.parametrize("points, match", [
    (PTS[:2], "at least 3 subtasks, got 2"),
    (np.zeros((0, 2)), "at least 3 subtasks, got 0"),
    (np.vstack([PTS, [[np.nan, 0.0]]]), r"subtask 4 is \[nan, 0.0\]: coordinates must be finite"),
    (np.vstack([PTS, [[0.0, np.inf]]]), r"subtask 4 is \[0.0, inf\]: coordinates must be finite"),
    (np.vstack([PTS, PTS[1:2]]), r"subtasks 1 and 4 are duplicates: \[0.3, -0.1\] and"),
    (np.zeros((4, 3)), r"shape \(N, 2\)"),
    ([["a", "b"]] * 3, "numbers"),
])
def test_bad_points(points: object, match: str) -> None:
    with pytest.raises(InputDataError, match=match):
        Targets(points)


def test_bad_theta() -> None:
    with pytest.raises(InputDataError, match="4 values"):
        Targets(PTS, theta=[0.0, 1.0])
    with pytest.raises(InputDataError, match="theta of subtask 2 is not finite"):
        Targets(PTS, theta=[0.0, 1.0, np.nan, 0.0])
    with pytest.raises(ParameterError, match="name"):
        Targets(PTS, name=3)  # type: ignore[arg-type]


# ---------------------------------------------------------------- 3-D

def test_3d_targets_hold_their_poses() -> None:
    t = make_targets(AXIS_ROWS, axis_step=90.0, standoff=0.01)
    assert not t.planar and len(t) == 2 and t.n_candidates == 8
    assert all(block.shape == (4, 4, 4) and not block.flags.writeable for block in t.poses)
    np.testing.assert_allclose(t.points, AXIS_ROWS[:, :3])
    assert "3-D targets, 8 candidate poses" in repr(t)
    planar = Targets(PTS)
    assert planar.planar and planar.n_candidates == 4 and "planar" in repr(planar)
    assert describe(t) == "3-D Targets" and describe(planar) == "planar Targets"
    assert describe([1, 2]) == "list"


def test_fields_of_the_other_kind_are_refused() -> None:
    t = make_targets(AXIS_ROWS)
    with pytest.raises(ParameterError, match="theta applies to planar targets"):
        Targets(t.points, theta=np.zeros(2), poses=t.poses, axes=t.axes,
                free_axis=t.free_axis)
    with pytest.raises(ParameterError, match="axes applies to 3-D targets"):
        Targets(PTS, axes=np.zeros((4, 3)))
    with pytest.raises(ParameterError, match="standoff apply to 3-D targets"):
        Targets(PTS, standoff=0.01)
    with pytest.raises(InputDataError, match="need their poses"):
        Targets(np.zeros((4, 3)))
    with pytest.raises(ParameterError, match="need axes"):
        Targets(t.points, poses=t.poses, free_axis=t.free_axis)
    with pytest.raises(ParameterError, match=r"poses\[1\] must have shape \(k, 4, 4\)"):
        Targets(t.points, poses=(t.poses[0], np.eye(4)), axes=t.axes, free_axis=t.free_axis)
    with pytest.raises(ParameterError, match="axis_step"):
        Targets(t.points, poses=t.poses, axes=t.axes, free_axis=t.free_axis, axis_step=1.0)
    with pytest.raises(ParameterError, match="to_dict writes planar targets"):
        t.to_dict()


def test_a_problem_refuses_the_other_kind_of_targets() -> None:
    """A planar arm's targets are planar and a serial arm's 3-D: the other kind is refused
    with both kinds named, by ArmProblem and by the problems behind it."""
    import subtask_opt as so
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.serial_problem import SerialProblem

    planar_robot, ur5 = so.load_robot("planar_2r"), so.load_robot("ur5")
    three_d = make_targets(AXIS_ROWS)
    with pytest.raises(ParameterError, match="targets are planar points.*got 3-D Targets"):
        so.ArmProblem(three_d, planar_robot)
    with pytest.raises(ParameterError, match="targets are 3-D.*got planar Targets"):
        so.ArmProblem(Targets(PTS), ur5)
    with pytest.raises(ParameterError, match="must be planar Targets.*got 3-D Targets"):
        PlanarProblem(three_d, planar_robot.model)
    with pytest.raises(ParameterError, match="must be 3-D Targets, got planar Targets"):
        SerialProblem(Targets(PTS), ur5.model, np.zeros(6))

"""Tests of subtask_opt.arm.tasks: planar target files (CSV/JSON), built-in cases."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import (
    CASE_NAMES,
    builtin_case,
    load_subtasks,
    random_subtasks,
    save_subtasks,
)
from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.kinematics.planar import ROBOT_NAMES, Arm, load_planar_arm
from tests.conftest import size

PTS = np.array([[0.1, 0.2], [0.3, -0.1], [0.25, 0.05], [0.15, 0.12]])


@functools.cache
def _arm(name: str) -> Arm:
    return load_planar_arm(name)


# ---------------------------------------------------------------- files

@pytest.mark.parametrize("suffix", [".csv", ".json"])
@pytest.mark.parametrize("with_theta", [False, True])
def test_save_load_round_trip(tmp_path: Path, suffix: str, with_theta: bool) -> None:
    rng = np.random.default_rng(1)
    theta = rng.uniform(-3, 3, len(PTS)) if with_theta else None
    s = Targets(PTS + rng.normal(0, 1e-3, PTS.shape), theta=theta, name="rt")
    path = tmp_path / f"rt{suffix}"
    save_subtasks(s, path)
    back = load_subtasks(path)
    np.testing.assert_array_equal(back.points, s.points)  # full precision
    if with_theta:
        np.testing.assert_array_equal(back.theta, s.theta)
    else:
        assert back.theta is None
    assert back.name == "rt"


def test_csv_tolerates_spaces_and_blank_lines(tmp_path: Path) -> None:
    path = tmp_path / "pts.csv"
    path.write_text(" X , y\n0.1, 0.2\n\n0.3,0.4\n0.5 ,0.6\n")
    s = load_subtasks(path)
    np.testing.assert_array_equal(s.points, [[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]])
    assert s.name == "pts"


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("a,b\n1,2\n", "line 1: header must be x,y or x,y,theta"),
    ("x,y\n1,2\n3,oops\n4,5\n", "line 3: y is not a number: 'oops'"),
    ("x,y\n1,2\n3,4,5\n6,7\n", "line 3: expected 2 values"),
    ("x,y,theta\n1,2,0\n3,4\n", "line 3: expected 3 values"),
    ("x,y\n1,2\nnan,4\n5,6\n", "line 3: values must be finite"),
    ("x,y\n1,2\n3,4\n", "at least 3 subtasks"),
    ("x,y\n1,2\n3,4\n1,2\n", "subtasks 0 and 2 are duplicates"),
])
def test_malformed_csv(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputDataError, match=match):
        load_subtasks(path)


@pytest.mark.parametrize("text, match", [
    ('{"points": [[1, 2], [3, 4],\n [5, 6]', "line 2: not valid JSON"),
    ('[[1, 2], [3, 4], [5, 6]]', "expected an object"),
    ('{"points": [[1, 2], [3], [5, 6]]}', "list of \\[x, y\\] number pairs"),
    ('{"points": [[1, 2], [3, "4"], [5, 6]]}', "list of \\[x, y\\] number pairs"),
    ('{"points": [[1, 2], [3, 4], [5, 6]], "theta": [1, "a", 2]}', "theta"),
    ('{"points": [[1, 2], [3, 4], [5, 6]], "theta": [1, 2]}', "3 values"),
    ('{"points": [[1, 2], [3, 4]]}', "at least 3"),
    ('{"points": [[1, 2], [3, 4], [5, 6]], "name": 7}', "name"),
])
def test_malformed_json(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(InputDataError, match=match):
        load_subtasks(path)


def test_bad_paths(tmp_path: Path) -> None:
    with pytest.raises(InputDataError, match="not found"):
        load_subtasks(tmp_path / "missing.csv")
    with pytest.raises(InputDataError, match=r"\.csv or \.json"):
        load_subtasks(tmp_path / "points.txt")
    with pytest.raises(InputDataError, match=r"\.csv or \.json"):
        save_subtasks(Targets(PTS), tmp_path / "points.txt")


# ---------------------------------------------------------------- built-in cases

@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_square20_is_a_reachable_lattice(robot: str) -> None:
    arm = _arm(robot)
    s = builtin_case("square20", arm)
    assert len(s) == 20 and s.name == "square20"
    assert np.isfinite(arm.ik(s.points)).all()  # both elbow branches everywhere
    # 5 x 4 lattice: in the frame of the arm's q = 0 direction, 5 distinct
    # abscissae and 4 ordinates, all equally spaced with the same step.
    a = arm.angle_offsets[0]
    rel = (s.points - arm.base_xy) @ np.array([[math.cos(a), -math.sin(a)],
                                               [math.sin(a), math.cos(a)]])
    xs = np.unique(rel[:, 0].round(9))
    ys = np.unique(rel[:, 1].round(9))
    assert len(xs) == 5 and len(ys) == 4
    steps = np.concatenate([np.diff(xs), np.diff(ys)])
    np.testing.assert_allclose(steps, steps[0], rtol=1e-6)
    assert builtin_case("square20", arm, seed=5).points.tolist() == s.points.tolist()


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_random30_is_seeded_and_reachable(robot: str) -> None:
    arm = _arm(robot)
    a = builtin_case("random30", arm, seed=3)
    b = builtin_case("random30", arm, seed=3)
    c = builtin_case("random30", arm, seed=4)
    assert len(a) == 30
    np.testing.assert_array_equal(a.points, b.points)
    assert not np.array_equal(a.points, c.points)
    arm.check_reachable(a.points)
    d = np.hypot(*(a.points[:, None] - a.points[None]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 0.03 * arm.r_max


def test_random_subtasks_errors() -> None:
    arm = _arm("asr_twodof")
    with pytest.raises(ParameterError, match="random_subtasks.n"):
        random_subtasks(arm, 2)
    with pytest.raises(ParameterError, match="min_spacing"):
        random_subtasks(arm, 5, min_spacing=0.0)
    n = size(30, 3)  # the search gives up after the same number of batches, each 64 n points
    with pytest.raises(ParameterError, match=f"cannot place {n} subtasks"):
        random_subtasks(arm, n, min_spacing=size(0.2, 1.0))


def test_unknown_case() -> None:
    with pytest.raises(ParameterError, match=", ".join(CASE_NAMES)):
        builtin_case("square21", _arm("planar_2r"))


def test_json_file_matches_to_dict(tmp_path: Path) -> None:
    s = builtin_case("random30", _arm("planar_2r"), seed=1)
    path = tmp_path / "r.json"
    save_subtasks(s, path)
    assert json.loads(path.read_text()) == s.to_dict()

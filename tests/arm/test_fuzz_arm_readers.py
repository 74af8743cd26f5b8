"""Fuzzing the arm side's file readers (hypothesis): subtask CSV/JSON files, the
limits JSON beside a planar URDF, the serial arm's JSON, scene files and target
files. For any bytes they give a valid object or raise the project's
:class:`SubtaskOptError`, nothing else (no RecursionError, OverflowError,
TypeError, ...).

Inputs: raw bytes, random JSON, JSON nested up to thousands deep, and the
valid shipped files with one field replaced by junk. ``make test`` runs a few
examples each; ``make fuzz`` runs ``FUZZ_EXAMPLES`` each.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import SubtaskOptError

FUZZ = int(os.environ.get("FUZZ_EXAMPLES", "60"))
QUICK = 15
ROBOTS = files("subtask_opt.robots")

_LEAF = (st.none() | st.booleans() | st.integers(-10**30, 10**30)
         | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=6))
_JSON = st.recursive(_LEAF, lambda inner: st.lists(inner, max_size=4)
                     | st.dictionaries(st.text(max_size=8), inner, max_size=4), max_leaves=20)
_JUNK = (_JSON | st.sampled_from([[], {}, "", -1, 0, 1e308, -1e308, 10**40, [1e-320] * 3,
                                   [0.0, 0.0], [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]]))


def _deep(depth: int) -> str:
    return "[" * depth + "]" * depth


def _mutations(valid: dict) -> st.SearchStrategy[str]:
    """``valid`` as JSON with one (possibly nested) field replaced, dropped or deepened."""

    @st.composite
    def mutate(draw) -> str:
        doc = json.loads(json.dumps(valid))
        node: Any = doc
        path = []
        while isinstance(node, dict | list) and node and draw(st.booleans()):
            key = draw(st.sampled_from(sorted(node) if isinstance(node, dict)
                                       else list(range(len(node)))))
            path.append((node, key))
            node = node[key]
        if not path:
            return json.dumps(draw(_JUNK))
        parent, key = path[-1]
        how = draw(st.sampled_from(["junk", "drop", "deep"]))
        if how == "drop" and isinstance(parent, dict):
            del parent[key]
            return json.dumps(doc)
        if how == "deep":
            parent[key] = "@DEEP@"
            return json.dumps(doc).replace('"@DEEP@"', _deep(draw(st.integers(30, 3000))))
        parent[key] = draw(_JUNK)
        return json.dumps(doc)

    return mutate()


def _texts(valid: dict) -> st.SearchStrategy[bytes]:
    return st.one_of(
        st.binary(max_size=300),
        _JSON.map(lambda d: json.dumps(d).encode()),
        st.integers(30, 5000).map(lambda n: _deep(n).encode()),
        _mutations(valid).map(str.encode),
        _mutations(valid).map(lambda t: ("\ufeff" + t).encode()),
    )


def _reads_or_refuses(read, data: bytes, name: str, setup=None) -> Any:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        path.write_bytes(data)
        if setup is not None:
            setup(Path(tmp))
        try:
            return read(path)
        except SubtaskOptError as exc:
            assert str(exc)
            return None


# ---------------------------------------------------------------- subtask files

_SUBTASKS_JSON = {"name": "p", "points": [[0.3, 0.1], [0.35, 0.22], [0.25, 0.3]]}
_CSV = st.one_of(
    st.text(max_size=200).map(str.encode),
    st.lists(st.lists(st.sampled_from(["0.3", "0.1", "nan", "1e309", "-0", "x", "", "9" * 80,
                                       "0.25", "0.35", "1j", " 0.2"]), max_size=4),
             max_size=6).map(lambda rows: ("x,y\n" + "\n".join(",".join(r) for r in rows))
                             .encode()),
)


def _check_subtasks(data: bytes, suffix: str) -> None:
    from subtask_opt.arm.tasks import load_subtasks

    s = _reads_or_refuses(load_subtasks, data, f"s{suffix}")
    if s is not None:
        assert len(s) >= 3 and np.isfinite(s.points).all()


@settings(max_examples=QUICK, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SUBTASKS_JSON) | _CSV, suffix=st.sampled_from([".csv", ".json"]))
def test_subtask_files(data, suffix):
    _check_subtasks(data, suffix)


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SUBTASKS_JSON) | _CSV, suffix=st.sampled_from([".csv", ".json"]))
def test_fuzz_subtask_files(data, suffix):
    _check_subtasks(data, suffix)


# ---------------------------------------------------------------- planar robot limits

_PLANAR = json.loads((ROBOTS / "planar_2r.json").read_text())


def _check_planar_limits(data: bytes) -> None:
    from subtask_opt.kinematics.planar import load_planar_arm

    def setup(tmp: Path) -> None:
        (tmp / "arm.urdf").write_text((ROBOTS / "planar_2r.urdf").read_text())

    arm = _reads_or_refuses(lambda p: load_planar_arm(p.with_suffix(".urdf")), data, "arm.json",
                            setup)
    if arm is not None:
        assert all(math.isfinite(v) for v in np.ravel(arm.fk([0.1, 0.2])))


@settings(max_examples=QUICK, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_PLANAR))
def test_planar_limit_files(data):
    _check_planar_limits(data)


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_PLANAR))
def test_fuzz_planar_limit_files(data):
    _check_planar_limits(data)


# ---------------------------------------------------------------- serial arm JSON

_SERIAL = json.loads((ROBOTS / "vs060_drill.json").read_text())


def _check_serial_params(data: bytes) -> None:
    from subtask_opt.kinematics.serial import load_serial_arm

    def setup(tmp: Path) -> None:
        shutil.copy(str(ROBOTS / "vs060_drill.urdf"), tmp / "arm.urdf")

    _reads_or_refuses(lambda p: load_serial_arm(p.with_suffix(".urdf")), data, "arm.json", setup)


@settings(max_examples=QUICK, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SERIAL))
def test_serial_arm_files(data):
    _check_serial_params(data)


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SERIAL))
def test_fuzz_serial_arm_files(data):
    _check_serial_params(data)


# ---------------------------------------------------------------- scenes and targets

_SCENE = {"boxes": [{"name": "table", "center": [0.5, 0.0, 0.2],
                     "half_extents": [0.3, 0.4, 0.02],
                     "rotation": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]}]}
_TARGETS = {"targets": [{"position": [0.5, 0.1, 0.4], "axis": [1, 0, 0]},
                        {"position": [0.3, -0.2, 0.6], "axis": [0, 3, 4]}]}


def _check_scene(data: bytes) -> None:
    from subtask_opt.cell.scene import Scene

    _reads_or_refuses(Scene.load, data, "scene.json")


def _check_targets(data: bytes, suffix: str) -> None:
    from subtask_opt.arm.poses import load_targets

    _reads_or_refuses(load_targets, data, f"targets{suffix}")


@settings(max_examples=QUICK, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SCENE))
def test_scene_files(data):
    _check_scene(data)


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_SCENE))
def test_fuzz_scene_files(data):
    _check_scene(data)


@settings(max_examples=QUICK, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_TARGETS) | _CSV, suffix=st.sampled_from([".json", ".csv"]))
def test_target_files(data, suffix):
    _check_targets(data, suffix)


@pytest.mark.fuzz
@settings(max_examples=FUZZ, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=_texts(_TARGETS) | _CSV, suffix=st.sampled_from([".json", ".csv"]))
def test_fuzz_target_files(data, suffix):
    _check_targets(data, suffix)


def test_the_valid_files_read():
    # the mutations start from files that do read: a refusal is the mutation's doing
    from subtask_opt.arm.poses import load_targets
    from subtask_opt.cell.scene import Scene

    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "s.json").write_text(json.dumps(_SCENE))
        (Path(tmp) / "t.json").write_text(json.dumps(_TARGETS))
        assert len(Scene.load(Path(tmp) / "s.json").boxes) == 1
        assert load_targets(Path(tmp) / "t.json") is not None

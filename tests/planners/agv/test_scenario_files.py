"""AGV scenario files: good files load, every bad file raises one
SubtaskOptError (issue "Bad input never crashes"), fuzzed with hypothesis."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    SubtaskOptError,
    UnreachableError,
)
from subtask_opt.base.results import Outcome
from subtask_opt.planners.agv.scenarios import (
    MAX_JSON_DEPTH,
    MAX_SCENARIO_BYTES,
    get_scenario,
    load_scenario,
)
from subtask_opt.planners.agv.simulation import simulate

GOOD = {"name": "corridor", "map": ["..........", "....@@....", ".........."],
        "start": [0, 1], "goal": [9, 1],
        "obstacles": [{"path": [[5, 2], [5, 0]], "start_time": 3.0}],
        "params": {"sonar_max_m": 1.2}}


def _write(tmp_path: Path, data: object, name: str = "s.json") -> Path:
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def test_a_good_file_loads_and_runs(tmp_path):
    sc = load_scenario(_write(tmp_path, GOOD))
    assert sc.params.sonar_range == pytest.approx((1.0, 6.0)) and len(sc.obstacles) == 1
    assert sc.name == "corridor"
    run = simulate(sc)
    assert run.outcome == Outcome.SUCCESS


@pytest.mark.parametrize(("change", "error", "match"), [
    ({"start": [4, 1]}, UnreachableError, "start"),
    ({"start": "ab"}, UnreachableError, "start"),
    ({"goal": [1.5, 1]}, UnreachableError, "goal"),
    ({"params": {"dt": "0.1"}}, ParameterError, "dt"),
    ({"params": {"dt": 1e-9}}, ParameterError, "steps"),
    ({"params": {"max_time_s": 1e300}}, ParameterError, "steps"),
    ({"params": {"horizon_s": 1e9}}, ParameterError, "look-ahead"),
    ({"params": {"drift": "yes"}}, ParameterError, "drift"),
    ({"params": [1]}, InputDataError, "mapping"),
    ({"params": {"speed": 2}}, ParameterError, "unknown AgvParams"),
    ({"obstacles": {"path": [[1, 1]]}}, InputDataError, "'obstacles' must be a list"),
    ({"obstacles": 3}, InputDataError, "'obstacles' must be a list"),
    ({"obstacles": [{"path": [["a", "b"]]}]}, InputDataError, "path"),
    ({"obstacles": [{"path": [[1, 2, 3]]}]}, InputDataError, "path"),
    ({"obstacles": [{"path": [[1, 1]], "speed": "fast"}]}, ParameterError, "speed"),
    ({"obstacles": [{"path": [[1, 1]], "colour": "red"}]}, InputDataError, "colour"),
    ({"obstacles": [{"path": [[1, 1]], "name": 5}]}, InputDataError, "name"),
    ({"obstacles": [{"path": [[1, 1], [50, 1]]}]}, InputDataError, "leaves"),
    ({"map": "....."}, InputDataError, "'map'"),
    ({"map": []}, InputDataError, "'map'"),
    ({"name": 7}, InputDataError, "'name'"),
    ({"size": 7}, InputDataError, "unknown key"),
])
def test_bad_fields_raise_one_error(tmp_path, change, error, match):
    with pytest.raises(error, match=match):
        load_scenario(_write(tmp_path, {**GOOD, **change}))


def test_nan_and_infinity_literals_are_refused(tmp_path):
    text = json.dumps(GOOD).replace('"start_time": 3.0', '"start_time": NaN')
    with pytest.raises(InputDataError, match="NaN"):
        load_scenario(_write(tmp_path, text))
    text = json.dumps(GOOD).replace('"start_time": 3.0', '"start_time": -Infinity')
    with pytest.raises(InputDataError, match="Infinity"):
        load_scenario(_write(tmp_path, text))


def test_deep_nesting_is_refused_before_parsing(tmp_path):
    deep = "[" * 100_000 + "]" * 100_000
    text = json.dumps(GOOD)[:-1] + ', "description": ' + deep + "}"
    with pytest.raises(InputDataError, match=f"deeper than the limit of {MAX_JSON_DEPTH}"):
        load_scenario(_write(tmp_path, text))


def test_oversize_and_unreadable_files_are_refused(tmp_path):
    big = tmp_path / "big.json"
    big.write_text(" " * (MAX_SCENARIO_BYTES + 1) + "{}")
    with pytest.raises(InputDataError, match="limit"):
        load_scenario(big)
    with pytest.raises(InputDataError, match="not found"):
        load_scenario(tmp_path / "missing.json")
    (tmp_path / "bin.json").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputDataError, match="not UTF-8"):
        load_scenario(tmp_path / "bin.json")
    with pytest.raises(InputDataError, match="not valid JSON"):
        load_scenario(_write(tmp_path, "{not json"))
    with pytest.raises(InputDataError, match="JSON object"):
        load_scenario(_write(tmp_path, "[1, 2]"))


def test_image_scenarios_and_their_errors(tmp_path):
    from PIL import Image

    img = np.full((40, 40), 255, dtype=np.uint8)
    img[:10, :10] = 0
    img[20:22, 20:25] = 0  # 10 dark pixels in cell (2, 2): mixed under factor 30
    Image.fromarray(img).save(tmp_path / "m.png")
    base = {"image": "m.png", "start": [3, 3], "goal": [3, 0]}
    sc = load_scenario(_write(tmp_path, base))
    assert sc.states[2, 2] == 1 and sc.states[0, 0] >= 2
    with pytest.raises(UnreachableError, match="mixed"):
        load_scenario(_write(tmp_path, {**base, "start": [2, 2]}))
    with pytest.raises(ParameterError, match="density_factor"):
        load_scenario(_write(tmp_path, {**base, "density_factor": 500}))
    with pytest.raises(ParameterError, match="cell_px"):
        load_scenario(_write(tmp_path, {**base, "cell_px": "10"}))
    with pytest.raises(InputDataError, match="cannot read image"):
        load_scenario(_write(tmp_path, {**base, "image": "nope.png"}))
    with pytest.raises(InputDataError, match="both"):
        load_scenario(_write(tmp_path, {**base, "map": ["...."]}))
    with pytest.raises(ParameterError, match="unknown scenario"):
        get_scenario("9-9")


# -- fuzzing ------------------------------------------------------------------------------
_KEYS = ["name", "description", "image", "cell_px", "density_factor", "map", "start", "goal",
         "obstacles", "params", "path", "speed", "start_time", "dt", "max_time_s",
         "horizon_s", "drift", "x"]
_scalars = (st.none() | st.booleans() | st.integers(-10**30, 10**30)
            | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=8))
_json = st.recursive(
    _scalars,
    lambda inner: st.lists(inner, max_size=4)
    | st.dictionaries(st.sampled_from(_KEYS) | st.text(max_size=4), inner, max_size=4),
    max_leaves=20)
_maps = st.lists(st.text(alphabet=".@#SGx", min_size=0, max_size=6), min_size=0, max_size=5)
_scenario = st.fixed_dictionaries(
    {"start": _json | st.lists(st.integers(-2, 8), min_size=2, max_size=2),
     "goal": _json | st.lists(st.integers(-2, 8), min_size=2, max_size=2)},
    optional={"map": _maps | _json, "obstacles": st.lists(
        st.fixed_dictionaries({"path": _json | st.lists(
            st.lists(st.floats(-3, 9), min_size=2, max_size=2), min_size=1, max_size=3)},
            optional={"speed": _json, "start_time": _json}), max_size=2) | _json,
        "params": st.dictionaries(st.sampled_from(["dt", "max_time_s", "horizon_s",
                                                   "v_nominal", "drift", "sonar_max_m"]),
                                  _json, max_size=3) | _json,
        "name": _json, "image": _json})


def _check_one(data: object) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "f.json"
        path.write_text(data if isinstance(data, str) else json.dumps(data))
        try:
            sc = load_scenario(path)
        except SubtaskOptError:
            return
        run = simulate(sc.with_params(max_time_s=min(sc.params.max_time_s, 5.0)))
        assert run.outcome in tuple(Outcome)


_SMALL = settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
_LONG = settings(max_examples=int(os.environ.get("FUZZ_EXAMPLES", "60")), deadline=None,
                 suppress_health_check=list(HealthCheck))


@_SMALL
@given(_scenario)
def test_fuzzed_scenarios_load_or_raise_one_error(data):
    _check_one(data)


@_SMALL
@given(st.text(max_size=200))
def test_fuzzed_text_loads_or_raises_one_error(text):
    _check_one(text)


@pytest.mark.fuzz
@_LONG
@given(_scenario | _json)
def test_fuzz_scenario_reader_long(data):
    _check_one(data)


@pytest.mark.fuzz
@_LONG
@given(st.text(alphabet='{}[]",:0123456789.-eE aNIfinty\\', max_size=400))
def test_fuzz_scenario_reader_json_syntax_long(text):
    _check_one(text)

"""Bad input never crashes a grid reader: arbitrary bytes or text give a valid
world (or scenario set) or an InputDataError, never another exception.

The unit suite runs 20 examples; ``-m fuzz`` (``make fuzz``) runs
``FUZZ_EXAMPLES`` examples (default 60), each through every map reader.
"""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from subtask_opt.base.errors import InputDataError
from subtask_opt.planners.grid.movingai import read_scenarios
from subtask_opt.planners.grid.world import PNG_SIGNATURE, GridWorld, read_grid

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))

MAP_ALPHABET = ".@#GSTWO\n\r\t x0-"
_HEADER = st.sampled_from(["", "type octile\n", "version 1\n", "height 2\nwidth 3\nmap\n",
                           "type octile\nheight 1\nwidth 1\nmap\n",
                           "type octile\nheight -3\nwidth 2\nmap\n"])


def _png_bytes(draw_array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(draw_array).save(buf, format="PNG")
    return buf.getvalue()


@st.composite
def map_bytes(draw):
    kind = draw(st.sampled_from(["raw", "text", "png", "broken_png"]))
    if kind == "raw":
        return draw(st.binary(max_size=300))
    if kind == "text":
        text = draw(_HEADER) + draw(st.text(MAP_ALPHABET, max_size=200))
        return text.encode()
    arr = np.array(draw(st.lists(st.integers(0, 255), min_size=1, max_size=64)), dtype=np.uint8)
    data = _png_bytes(arr.reshape(1, -1))
    if kind == "png":
        return data
    cut = draw(st.integers(len(PNG_SIGNATURE), len(data)))
    noise = draw(st.binary(max_size=40))
    return data[:cut] + noise


@st.composite
def scen_bytes(draw):
    if draw(st.booleans()):
        return draw(st.binary(max_size=300))
    cols = st.one_of(st.integers(-5, 10**20).map(str), st.text("0123456789.-einfa", max_size=6))
    rows = draw(st.lists(st.lists(cols, min_size=7, max_size=10), max_size=4))
    text = "version 1\n" + "\n".join("\t".join([r[0], "m.map", *r[1:]]) for r in rows)
    return text.encode()


def _check_world(world: GridWorld) -> None:
    assert world.occupancy.dtype == bool and world.occupancy.ndim == 2
    assert world.width >= 1 and world.height >= 1


def _through_file(data: bytes, fn):
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "input"
        f.write_bytes(data)
        try:
            return fn(f)
        except InputDataError as exc:
            assert str(exc)  # a message naming the problem
            return None


def _readers():
    return {
        "read_grid": lambda f: _check_world(read_grid(f)),
        "from_movingai": lambda f: _check_world(GridWorld.from_movingai(f)),
        "from_png": lambda f: _check_world(GridWorld.from_png(f)),
        "from_ascii": lambda f: _check_world(
            GridWorld.from_ascii(f.read_bytes().decode("utf-8", "replace"))),
    }


def _fuzz_maps(examples: int) -> None:
    @settings(max_examples=examples, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(map_bytes())
    def run(data):
        for fn in _readers().values():
            _through_file(data, fn)

    run()


def _fuzz_scenarios(examples: int) -> None:
    @settings(max_examples=examples, deadline=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(scen_bytes())
    def run(data):
        scen = _through_file(data, read_scenarios)
        if scen is not None:
            assert len(scen) >= 1 and np.all(scen.optimal >= 0)
            assert np.all(scen.start >= 0) and np.all(scen.start[:, 0] < scen.width)

    run()


def test_map_readers_never_crash():
    _fuzz_maps(20)


def test_scenario_reader_never_crashes():
    _fuzz_scenarios(20)


@pytest.mark.fuzz
def test_map_readers_never_crash_long():
    _fuzz_maps(FUZZ_EXAMPLES)


@pytest.mark.fuzz
def test_scenario_reader_never_crashes_long():
    _fuzz_scenarios(FUZZ_EXAMPLES)


def test_valid_inputs_pass_through():
    # the strategies do produce valid worlds too (the fuzz is not all errors)
    assert _through_file(b"..@\n.S.\n", lambda f: read_grid(f)) is not None
    assert _through_file(_png_bytes(np.zeros((2, 2), np.uint8)), read_grid) is not None
    assert _through_file(b"version 1\n0\tm\t4\t4\t0\t0\t1\t1\t1.41421\n",
                         read_scenarios) is not None

"""Distance transforms (chamfer 3/4, octile) and the any-angle MDT against
independent oracles: raster-sweep Jarvis, scipy Dijkstra, brute-force
line-of-sight Dijkstra."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.grid.test_grid_oracles import (
    anyangle_oracle,
    chamfer_oracle,
    los_free,
    octile_oracle,
    path_free,
)


@st.composite
def grid_and_cells(draw, max_side=7):
    h = draw(st.integers(2, max_side))
    w = draw(st.integers(2, max_side))
    occ = np.array(draw(st.lists(st.booleans(), min_size=h * w, max_size=h * w)),
                   dtype=bool).reshape(h, w)
    free = np.argwhere(~occ)
    if free.shape[0] < 2:
        occ[0, 0] = occ[h - 1, w - 1] = False
        free = np.argwhere(~occ)
    i = draw(st.integers(0, free.shape[0] - 1))
    j = draw(st.integers(0, free.shape[0] - 1))
    return occ, (int(free[i][1]), int(free[i][0])), (int(free[j][1]), int(free[j][0]))


def _close(a, b):
    return np.allclose(np.where(np.isfinite(a), a, -1), np.where(np.isfinite(b), b, -1),
                       atol=1e-9)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(grid_and_cells())
def test_fields_equal_oracles(case):
    occ, start, goal = case
    world = GridWorld(occ)
    assert _close(dt.distance_field(world, goal, "octile"), octile_oracle(occ, goal))
    assert _close(dt.distance_field(world, goal, "chamfer34"), chamfer_oracle(occ, goal))
    mdt = dt.distance_field(world, goal, "anyangle")
    assert _close(mdt, anyangle_oracle(occ, goal))
    # the MDT is never longer than the 8-connected transforms
    octile = dt.distance_field(world, goal, "octile")
    assert np.all(mdt[np.isfinite(octile)] <= octile[np.isfinite(octile)] + 1e-9)


@settings(max_examples=40, deadline=None)
@given(grid_and_cells())
def test_paths_realise_field_values(case):
    occ, start, goal = case
    world = GridWorld(occ)
    for metric in ("octile", "anyangle", "chamfer34"):
        res = dt.plan(world, start, goal, params=dt.DTParams(metric))
        value = dt.distance_field(world, goal, metric)[start[1], start[0]]
        assert res.success == np.isfinite(value)
        if not res.success:
            assert "not reachable" in res.message and res.path.shape == (0, 2)
            continue
        assert tuple(res.path[0]) == start and tuple(res.path[-1]) == goal
        assert path_free(occ, res.path)
        if len(res.path) == 1:
            assert start == goal and value == 0.0
        elif metric == "chamfer34":
            steps = np.abs(np.diff(res.path, axis=0))
            assert steps.max() <= 1  # 8-connected moves
            assert np.isclose(np.sum(np.where(steps.sum(1) == 2, 4, 3)) / 3, value)
        else:
            assert np.isclose(res.length, value)


@settings(max_examples=60, deadline=None)
@given(grid_and_cells(max_side=6), st.data())
def test_segment_hits_matches_liang_barsky(case, data):
    occ, _, _ = case
    h, w = occ.shape
    x0, x1 = data.draw(st.integers(0, w - 1)), data.draw(st.integers(0, w - 1))
    y0, y1 = data.draw(st.integers(0, h - 1)), data.draw(st.integers(0, h - 1))
    blocked = occ.view(np.uint8)
    free = K.segment_hits(blocked, x0, y0, x1, y1, True) == 0
    assert free == los_free(occ, (x0, y0), (x1, y1))


def test_thesis_maps_mdt_exact_and_not_longer_than_dt():
    for name in THESIS_MAPS:
        case = thesis_case(name)
        occ = case.world.occupancy
        mdt = dt.distance_field(case.world, case.goal, "anyangle")
        assert _close(mdt, anyangle_oracle(occ, case.goal)), name
        r_mdt = dt.plan(case.world, case.start, case.goal, params=dt.DTParams("anyangle"))
        for metric in ("chamfer34", "octile"):
            r_dt = dt.plan(case.world, case.start, case.goal, params=dt.DTParams(metric))
            assert r_mdt.length <= r_dt.length + 1e-9, (name, metric)


def test_field_reused_for_many_starts_and_stop_at():
    case = thesis_case("rooms")
    field = dt.distance_field(case.world, case.goal, "octile")
    free = np.argwhere(~case.world.occupancy)[:: 7]
    cells = [(int(x), int(y)) for y, x in free]
    for c in cells:
        path = dt.path_from_field(case.world, field, c, "octile")
        assert np.isclose(np.sum(np.hypot(*np.diff(path, axis=0).T)), field[c[1], c[0]])
    partial = dt.distance_field(case.world, case.goal, "octile", stop_at=cells)
    for x, y in cells:
        assert np.isclose(partial[y, x], field[y, x])


def test_no_path_is_a_result_not_an_error():
    world = GridWorld.from_ascii("""
        .....
        .###.
        .#.#.
        .###.
    """)
    for metric in dt.METRICS:
        res = dt.plan(world, (0, 0), (2, 2), params=dt.DTParams(metric))
        assert not res.success and "not reachable" in res.message
        assert res.length == float("inf")


def test_start_equals_goal():
    world = GridWorld.from_ascii("...")
    res = dt.plan(world, (1, 0), (1, 0), params=dt.DTParams("anyangle"))
    assert res.success and res.length == 0.0


def test_bad_inputs():
    world = GridWorld.from_ascii("..#")
    with pytest.raises(ParameterError, match="metric"):
        dt.DTParams("manhattan")
    with pytest.raises(UnreachableError, match="goal"):
        dt.distance_field(world, (2, 0))
    with pytest.raises(UnreachableError, match="start"):
        dt.plan(world, (9, 0), (0, 0))
    with pytest.raises(ParameterError, match="shape"):
        dt.path_from_field(world, np.zeros((2, 2)), (0, 0))
    with pytest.raises(ParameterError, match="max_free_cells=1"):
        dt.plan(world, (0, 0), (1, 0), params=dt.DTParams("anyangle", max_free_cells=1))
    with pytest.raises(ParameterError, match="max_free_cells"):
        dt.DTParams(max_free_cells=0)
    with pytest.raises(ParameterError, match="stop_at"):
        dt.distance_field(world, (0, 0), "anyangle", stop_at=[(1, 0)])

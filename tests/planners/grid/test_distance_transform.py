"""Distance transforms (chamfer 3/4 with and without corner cutting, octile)
and the any-angle MDT (exact and level fill, each under both corner rules) against
independent oracles:
raster-sweep Jarvis, scipy Dijkstra, brute-force line-of-sight Dijkstra, the
thesis' level fill in plain Python."""

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
    levels_oracle,
    los,
    los_free,
    los_free_thesis,
    octile_oracle,
    path_free,
    path_violations,
)

PLANS = {  # name -> (plan function, params, metric, corner cutting, fill)
    "dt": (dt.plan_dt, None, "chamfer34", True, "exact"),
    "dt-nocut": (dt.plan_dt, dt.DTParams("chamfer34", corner_cutting=False), "chamfer34", False,
                 "exact"),
    "dt-octile": (dt.plan_octile, None, "octile", False, "exact"),
    "mdt": (dt.plan_mdt, None, "anyangle", True, "exact"),
    "mdt-nocut": (dt.plan_mdt, dt.MDTParams(corner_cutting=False), "anyangle", False, "exact"),
    "mdt-levels": (dt.plan_mdt, dt.MDTParams("levels"), "anyangle", True, "levels"),
    "mdt-levels-nocut": (dt.plan_mdt, dt.MDTParams("levels", corner_cutting=False), "anyangle",
                         False, "levels"),
}


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
    assert _close(dt.distance_field(world, goal, "chamfer34", corner_cutting=False),
                  chamfer_oracle(occ, goal))
    assert _close(dt.distance_field(world, goal, "chamfer34"),
                  chamfer_oracle(occ, goal, corner_cutting=True))
    fields = {}
    for cut in (True, False):
        mdt = dt.distance_field(world, goal, "anyangle", corner_cutting=cut)
        assert _close(mdt, anyangle_oracle(occ, goal, corner_cutting=cut)), cut
        levels = dt.distance_field(world, goal, "anyangle", fill="levels", corner_cutting=cut)
        assert _close(levels, levels_oracle(occ, goal, corner_cutting=cut)), cut
        # the exact MDT is never longer than the level fill or the 8-connected transform
        # (octile: true step lengths) of the same corner rule
        octile = dt.distance_field(world, goal, "octile", corner_cutting=cut)
        reach = np.isfinite(octile)
        assert np.array_equal(np.isfinite(levels), np.isfinite(mdt))
        assert np.array_equal(np.isfinite(mdt), reach)
        assert np.all(mdt[reach] <= octile[reach] + 1e-9)
        assert np.all(mdt[reach] <= levels[reach] + 1e-9)
        fields[cut] = mdt
    # the thesis' rule allows more moves: never longer than the closed-square rule
    both = np.isfinite(fields[False])
    assert np.all(fields[True][both] <= fields[False][both] + 1e-9)


@settings(max_examples=40, deadline=None)
@given(grid_and_cells())
def test_paths_realise_field_values(case):
    occ, start, goal = case
    world = GridWorld(occ)
    for name, (fn, params, metric, cut, fill) in PLANS.items():
        res = fn(world, start, goal, params=params)
        field = dt.distance_field(world, goal, metric, corner_cutting=cut, fill=fill)
        value = field[start[1], start[0]]
        assert res.success == np.isfinite(value), name
        if not res.success:
            assert res.outcome == "no_path" and res.path.shape == (0, 2)
            assert "not reachable" in res.message
            continue
        assert tuple(res.path[0]) == start and tuple(res.path[-1]) == goal
        assert path_violations(occ, res.path) == [], name
        if not cut:
            assert path_free(occ, res.path), name  # the closed-square rule
        if metric == "chamfer34":
            steps = np.abs(np.diff(res.path, axis=0))
            assert steps.max(initial=0) <= 1  # 8-connected moves
            assert np.isclose(np.sum(np.where(steps.sum(1) == 2, 4, 3)) / 3 if len(steps)
                              else 0.0, value)
        elif fill == "exact":
            assert np.isclose(res.length, value)
        else:  # the thesis' step 5: each jump goes to the least value in sight
            free = np.argwhere(~occ)
            for a, b in zip(res.path[:-1], res.path[1:], strict=True):
                seen = [field[y, x] for y, x in free
                        if (x, y) != tuple(a) and los(occ, a, (x, y), cut)]
                assert field[int(b[1]), int(b[0])] == min(seen) < field[int(a[1]), int(a[0])]


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
    assert K.segment_clear(blocked, x0, y0, x1, y1, False) == free
    thesis = los_free_thesis(occ, (x0, y0), (x1, y1))
    assert K.segment_clear(blocked, x0, y0, x1, y1, True) == thesis
    assert thesis == (path_violations(occ, [(x0, y0), (x1, y1)]) == [])  # two oracles agree
    assert thesis or not free  # the closed-square rule is the stricter


def test_segment_clear_against_the_oracle_on_every_pair_of_free_cells():
    """Every pair of free cells of random grids (where corner gaps and corner touches are
    common), both rules, against the oracles."""
    rng = np.random.default_rng(7)
    touches = 0
    for _ in range(12):
        occ = rng.random((6, 7)) < 0.3
        blocked = occ.view(np.uint8)
        free = [(int(x), int(y)) for y, x in np.argwhere(~occ)]
        for i, a in enumerate(free):
            for b in free[i + 1:]:
                thesis = K.segment_clear(blocked, *a, *b, True)
                assert thesis == los_free_thesis(occ, a, b), (occ.astype(int), a, b)
                closed = K.segment_clear(blocked, *a, *b, False)
                assert closed == los_free(occ, a, b), (occ.astype(int), a, b)
                touches += thesis and not closed
    assert touches > 50  # many segments pass a blocked corner (the rules differ there)


def test_segment_clear_corner_cases():
    one = np.array([[0, 1], [0, 0]], dtype=np.uint8)  # ".@" over "..": (1, 0) blocked
    gap = np.array([[0, 1], [1, 0]], dtype=np.uint8)  # ".@" over "@."
    assert K.segment_clear(one, 0, 0, 1, 1, True)  # touches (1, 0) at its corner only
    assert not K.segment_clear(one, 0, 0, 1, 1, False)
    assert not K.segment_clear(gap, 0, 0, 1, 1, True)  # between two blocked cells
    wide = np.zeros((3, 5), dtype=np.uint8)
    wide[1, 2] = 1  # the centre cell
    assert not K.segment_clear(wide, 0, 0, 4, 2, True)  # through its open square
    assert K.segment_clear(wide, 0, 2, 2, 0, True)  # x + y = 2 touches its corner (1.5, 0.5)
    assert not K.segment_clear(wide, 0, 2, 2, 0, False)
    assert K.segment_clear(wide, 2, 0, 0, 2, True)  # either direction
    wide[0, 1] = 1  # (1, 0) now touches the centre cell diagonally at (1.5, 0.5)
    assert not K.segment_clear(wide, 0, 2, 2, 0, True)
    assert not K.segment_clear(wide, 2, 0, 0, 2, True)


@pytest.mark.parametrize("cut", [True, False])
def test_thesis_maps_mdt_exact_and_not_longer_than_dt(cut):
    """Under one corner rule the MDT path is never longer than the DT's (3:4 and octile),
    on every thesis map and from every free start; both find a path or neither does."""
    compared = 0
    for name in THESIS_MAPS:
        case = thesis_case(name)
        occ = case.world.occupancy
        mdt = dt.distance_field(case.world, case.goal, "anyangle", corner_cutting=cut)
        assert _close(mdt, anyangle_oracle(occ, case.goal, corner_cutting=cut)), name
        free = np.argwhere(~occ)
        starts = [case.start] + [(int(x), int(y)) for y, x in free[::5]]
        for start in starts:
            r_mdt = dt.plan_mdt(case.world, start, case.goal,
                                params=dt.MDTParams(corner_cutting=cut))
            for params in (dt.DTParams("chamfer34", corner_cutting=cut),
                           dt.DTParams("octile", corner_cutting=cut)):
                r_dt = dt.plan(case.world, start, case.goal, params=params)
                assert r_mdt.info["corner_cutting"] == r_dt.info["corner_cutting"] == cut
                assert r_mdt.success == r_dt.success, (name, start, params)
                if r_dt.success:
                    assert r_mdt.length <= r_dt.length + 1e-9, (name, start, params)
                    compared += 1
    assert compared > 100


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
    for name, (fn, params, *_rest) in PLANS.items():
        res = fn(world, (0, 0), (2, 2), params=params)
        assert not res.success and "not reachable" in res.message, name
        assert res.outcome == "no_path" and res.length == float("inf")


def test_corner_gap_is_never_passed():
    gap = GridWorld.from_ascii("@.\n.@")  # start bottom-left, goal top-right
    for name, (fn, params, *_rest) in PLANS.items():
        res = fn(gap, (0, 1), (1, 0), params=params)
        assert not res.success and res.outcome == "no_path", name


def test_corner_cutting_default_and_option():
    one = GridWorld.from_ascii(".@\n..")
    assert dt.plan_dt(one, (0, 0), (1, 1)).path.shape == (2, 2)  # one diagonal past the corner
    nocut = dt.plan_dt(one, (0, 0), (1, 1), params=dt.DTParams(corner_cutting=False))
    assert nocut.path.tolist() == [[0, 0], [0, 1], [1, 1]]
    assert dt.plan_octile(one, (0, 0), (1, 1)).path.shape == (3, 2)
    assert dt.DTParams("octile", corner_cutting=True).cuts_corners
    # the MDT takes the DT's (thesis') rule by default
    mdt = dt.plan_mdt(one, (0, 0), (1, 1))
    assert mdt.path.shape == (2, 2) and mdt.info["corner_cutting"] is True
    mdt_nocut = dt.plan_mdt(one, (0, 0), (1, 1), params=dt.MDTParams(corner_cutting=False))
    assert mdt_nocut.path.tolist() == [[0, 0], [0, 1], [1, 1]]
    assert mdt_nocut.info["corner_cutting"] is False


@pytest.mark.parametrize("cut", [True, False])
def test_level_fill_on_the_cluttered_map(cut):
    case = thesis_case("cluttered")
    exact = dt.distance_field(case.world, case.goal, "anyangle", corner_cutting=cut)
    levels = dt.distance_field(case.world, case.goal, "anyangle", fill="levels",
                               corner_cutting=cut)
    assert _close(levels, levels_oracle(case.world.occupancy, case.goal, corner_cutting=cut))
    assert np.all(exact[np.isfinite(exact)] <= levels[np.isfinite(exact)] + 1e-9)


@pytest.mark.parametrize("name", list(PLANS))
def test_start_equals_goal(name):
    fn, params, *_ = PLANS[name]
    world = GridWorld.from_ascii("...")
    res = fn(world, (1, 0), (1, 0), params=params)
    assert res.success and res.length == 0.0 and res.path.tolist() == [[1.0, 0.0]]


def test_bad_inputs():
    world = GridWorld.from_ascii("..#")
    with pytest.raises(ParameterError, match="metric"):
        dt.DTParams("manhattan")
    with pytest.raises(ParameterError, match="metric"):
        dt.DTParams("anyangle")
    with pytest.raises(ParameterError, match="corner_cutting"):
        dt.DTParams(corner_cutting=1)
    with pytest.raises(ParameterError, match="fill"):
        dt.MDTParams("bfs")
    with pytest.raises(ParameterError, match="corner_cutting"):
        dt.MDTParams(corner_cutting=None)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="corner_cutting"):
        dt.distance_field(world, (0, 0), "anyangle", corner_cutting=1)
    with pytest.raises(ParameterError, match="metric"):
        dt.distance_field(world, (0, 0), "manhattan")
    with pytest.raises(UnreachableError, match="goal"):
        dt.distance_field(world, (2, 0))
    with pytest.raises(UnreachableError, match="start"):
        dt.plan(world, (9, 0), (0, 0))
    with pytest.raises(ParameterError, match="shape"):
        dt.path_from_field(world, np.zeros((2, 2)), (0, 0))
    with pytest.raises(ParameterError, match="max_free_cells=1"):
        dt.plan_mdt(world, (0, 0), (1, 0), params=dt.MDTParams(max_free_cells=1))
    with pytest.raises(ParameterError, match="max_free_cells"):
        dt.MDTParams(max_free_cells=0)
    with pytest.raises(ParameterError, match="stop_at"):
        dt.distance_field(world, (0, 0), "anyangle", stop_at=[(1, 0)])
    with pytest.raises(ParameterError, match="dt-octile"):
        dt.plan_dt(world, (0, 0), (1, 0), params=dt.DTParams("octile"))
    with pytest.raises(ParameterError, match="use dt"):
        dt.plan_octile(world, (0, 0), (1, 0), params=dt.DTParams("chamfer34"))

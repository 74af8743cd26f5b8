"""Invariants of every registered grid planner on random grids (hypothesis).

No successful path enters a blocked cell or passes between two blocked cells
that touch at a corner, checked by an independent exact walk
(:func:`tests.planners.grid.test_grid_oracles.path_violations`); the same holds
for the trajectory a local planner drove. A success also needs a goal that
the exact any-angle transform can reach.
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.base import planners
from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid.world import GridWorld
from tests.conftest import examples
from tests.planners.grid.test_grid_oracles import path_violations

GRID = planners("grid")


@st.composite
def grid_and_cells(draw, max_side=8):
    h = draw(st.integers(2, max_side))
    w = draw(st.integers(2, max_side))
    density = draw(st.sampled_from([0.15, 0.3, 0.45]))
    bits = draw(st.lists(st.floats(0, 1), min_size=h * w, max_size=h * w))
    occ = (np.array(bits) < density).reshape(h, w)
    free = np.argwhere(~occ)
    if free.shape[0] < 2:
        occ[0, 0] = occ[h - 1, w - 1] = False
        free = np.argwhere(~occ)
    i = draw(st.integers(0, free.shape[0] - 1))
    j = draw(st.integers(0, free.shape[0] - 1))
    return occ, (int(free[i][1]), int(free[i][0])), (int(free[j][1]), int(free[j][0]))


@settings(max_examples=examples(25), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(grid_and_cells(), st.integers(0, 2**32))
def test_no_planner_enters_a_blocked_cell_or_a_corner_gap(case, seed):
    occ, start, goal = case
    world = GridWorld(occ)
    reachable = np.isfinite(dt.distance_field(world, goal, "anyangle")[start[1], start[0]])
    for name, info in GRID.items():
        kwargs = {"seed": seed, "stop": MaxGenerations(10)} if info.stochastic else {}
        res = info.plan(world, start, goal, **kwargs)
        assert res.success <= reachable, name
        if res.success:
            assert np.allclose(res.path[0], start) and np.allclose(res.path[-1], goal), name
            assert path_violations(occ, res.path) == [], (name, res.path.tolist())
        if "trajectory" in res.info:
            driven = np.asarray(res.info["trajectory"])
            clean = driven if res.outcome != "collision" else driven[:-1]
            assert path_violations(occ, clean) == [], name

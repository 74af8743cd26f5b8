"""Every registered grid planner on thousands of seeded random grids, checked by a cell walk.

A grid is 2 to 10 cells a side with a random fill (15, 30 or 45 % blocked)
plus a few planted diagonal corner gaps (two blocked cells touching at a
corner, ``.@`` over ``@.``); start and goal are random free cells.

Oracles independent of the planners: reachability is 4-connectivity of the free
cells (scipy's labelling; passing a corner with one of its two side cells free
is allowed, so 8-moves add no connection that 4-moves lack), and every
successful path (and the trajectory a local planner drove) is walked exactly
over the cells it touches (:func:`tests.planners.grid.test_grid_oracles.path_violations`):
no blocked cell, no corner gap, nothing off the grid. A success needs a
reachable goal; the exact planners (distance transforms) succeed exactly when
it is reachable.

``make test`` runs :data:`WORLDS` grids (``GRID_WORLDS`` overrides), every
planner on every grid except that ``ga``, which takes seconds to give up on an
unreachable goal (its initial paths are redrawn ``init_tries`` times), runs on
every reachable grid but only on every :data:`GA_UNREACHABLE_EVERY`-th grid
overall when the goal is unreachable; the ``fuzz`` variant runs 2,000 fresh grids
(``FUZZ_WORLDS``) with that stride :data:`FUZZ_GA_UNREACHABLE_EVERY`.
"""

from __future__ import annotations

import contextlib
import os

import numpy as np
import pytest
from scipy import ndimage

from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.base import planners
from subtask_opt.planners.grid.world import GridWorld
from tests.fuzz_report import Timer
from tests.planners.grid.test_grid_oracles import path_violations

GRID = planners("grid")
EXACT = ("dt", "dt-octile", "mdt")
WORLDS = int(os.environ.get("GRID_WORLDS", "2000"))
FUZZ_WORLDS = int(os.environ.get("FUZZ_WORLDS", "2000"))
GA_UNREACHABLE_EVERY = 500
FUZZ_GA_UNREACHABLE_EVERY = 20


def random_grid(rng: np.random.Generator):
    """``(occ, start, goal)``: a grid of the module docstring, cells as (x, y)."""
    h, w = (int(v) for v in rng.integers(2, 11, 2))
    occ = rng.random((h, w)) < rng.choice([0.15, 0.3, 0.45])
    for _ in range(int(rng.integers(0, 3))):  # plant a corner gap
        y, x = int(rng.integers(0, h - 1)), int(rng.integers(0, w - 1))
        flip = bool(rng.integers(0, 2))
        occ[y:y + 2, x:x + 2] = [[flip, not flip], [not flip, flip]]
    free = np.argwhere(~occ)
    if free.shape[0] < 2:
        occ[0, 0] = occ[h - 1, w - 1] = False
        free = np.argwhere(~occ)
    i, j = rng.integers(0, free.shape[0], 2)
    return occ, (int(free[i][1]), int(free[i][0])), (int(free[j][1]), int(free[j][0]))


def reachable(occ: np.ndarray, start, goal) -> bool:
    """Start and goal in one 4-connected piece of the free cells."""
    labels, _ = ndimage.label(~occ)
    return bool(labels[start[1], start[0]] == labels[goal[1], goal[0]])


def _check_grids(seeds: np.ndarray, ga_unreachable_every: int = 1,
                 report: str = "") -> dict[str, int]:
    """Every planner on one grid per seed; the successes per planner. With ``report``
    (a test id) each grid counts as one input of a fuzz run."""
    successes = dict.fromkeys(GRID, 0)
    for n, seed in enumerate(seeds):
        with Timer(report) if report else contextlib.nullcontext():
            _check_grid(int(seed), n % ga_unreachable_every == 0, successes)
    return successes


def _check_grid(seed: int, run_ga_if_unreachable: bool, successes: dict[str, int]) -> None:
    """One grid: every planner against the oracles (GA on an unreachable goal only if asked)."""
    occ, start, goal = random_grid(np.random.default_rng(int(seed)))
    world = GridWorld(occ)
    ok = reachable(occ, start, goal)
    for name, info in GRID.items():
        if name == "ga" and not ok and not run_ga_if_unreachable:
            continue
        kwargs: dict = ({"seed": int(seed), "stop": MaxGenerations(10)}
                        if info.stochastic else {})
        res = info.plan(world, start, goal, **kwargs)
        where = (int(seed), name, occ.astype(int).tolist(), start, goal)
        assert res.success <= ok, where
        if name in EXACT:
            assert res.success == ok, where
        if res.success:
            successes[name] += 1
            assert np.allclose(res.path[0], start) and np.allclose(res.path[-1], goal), where
            assert path_violations(occ, res.path) == [], (where, res.path.tolist())
        if "trajectory" in res.info:
            driven = np.asarray(res.info["trajectory"])
            clean = driven if res.outcome != "collision" else driven[:-1]
            assert path_violations(occ, clean) == [], (where, "trajectory")


def test_the_exact_planners_are_registered():
    assert set(EXACT) <= set(GRID)


def test_generator_plants_corner_gaps_and_unreachable_goals():
    gaps = unreachable = 0
    for seed in range(300):
        occ, start, goal = random_grid(np.random.default_rng(seed))
        a, b, c, d = occ[:-1, :-1], occ[:-1, 1:], occ[1:, :-1], occ[1:, 1:]
        gaps += bool(np.any((a & d & ~b & ~c) | (b & c & ~a & ~d)))
        unreachable += not reachable(occ, start, goal)
    assert gaps > 100 and unreachable > 30


def test_every_planner_on_random_grids():
    successes = _check_grids(np.arange(WORLDS), GA_UNREACHABLE_EVERY)
    assert min(successes.values()) > 0, successes


@pytest.mark.fuzz
def test_fuzz_every_planner_on_2000_random_grids(request):
    seeds = np.random.default_rng().integers(0, 2**63 - 1, FUZZ_WORLDS)
    successes = _check_grids(seeds, FUZZ_GA_UNREACHABLE_EVERY, request.node.nodeid)
    assert min(successes.values()) > 0, successes

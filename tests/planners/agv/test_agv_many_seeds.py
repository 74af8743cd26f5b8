"""The AGV among moving obstacles on many seeds no test used before, judged by
an independent collision oracle (:mod:`tests.planners.agv.collision_oracle`):
exact closest approaches to the obstacles' own polylines and the trajectory
against the blocked cells' squares, not the simulator's collision flag."""

from __future__ import annotations

import math

import numpy as np
import pytest

from subtask_opt.base.results import Outcome
from subtask_opt.planners.agv.scenarios import PAPER_SCENARIOS, random_agv_scenario
from subtask_opt.planners.agv.simulation import AgvParams, AgvScenario, MovingObstacle, simulate
from subtask_opt.planners.grid.world import GridWorld
from tests.conftest import size
from tests.planners.agv.collision_oracle import (
    min_obstacle_separation,
    obstacle_at,
    wall_clearance,
)

SEEDS = range(900_000, 900_000 + size(100, 6))
"""Suite seeds of this file (disjoint from every other test's: those are below 20,000)."""


# -- the oracle itself ------------------------------------------------------------------
def test_oracle_obstacle_motion_and_closest_approach_by_hand():
    path = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    np.testing.assert_allclose(obstacle_at(path, 2.0, 1.0, np.array([0.0, 2.0, 4.0, 9.0])),
                               [[0, 0], [2, 0], [4, 2], [4, 3]])
    # the AGV goes (0, 1) -> (4, 1) in 4 s, recorded only at t = 0 and 4: it is at (t, 1).
    # The obstacle waits at (2, 3) until t = 1, then drives up the page at 1 u/s:
    # obstacle - AGV = (2 - t, 2) before t = 1 and (2 - t, 3 - t) after, closest at t = 2.5
    sc = AgvScenario("hand", GridWorld(np.zeros((6, 6), dtype=bool)), (0, 1), (4, 1),
                     (MovingObstacle([(2, 3), (2, -0.5)], 1.0, 1.0),))
    d, j, t = min_obstacle_separation(sc, np.array([0.0, 4.0]), np.array([[0, 1], [4, 1]]))
    assert (j, d, t) == (0, pytest.approx(math.sqrt(0.5)), pytest.approx(2.5))


def test_oracle_walls_by_hand():
    occ = np.zeros((5, 5), dtype=bool)
    occ[2, 2] = True  # square [1.5, 2.5] x [1.5, 2.5]
    assert wall_clearance(occ, np.array([[0, 0], [4, 0]])) == pytest.approx(0.5)
    assert wall_clearance(occ, np.array([[0, 1], [4, 1]])) == pytest.approx(0.5)
    assert wall_clearance(occ, np.array([[0, 0], [1.5, 1.5]])) == 0.0  # touches a corner
    assert wall_clearance(occ, np.array([[0, 4], [4.6, 4]])) == 0.0  # leaves the map
    assert wall_clearance(occ, np.array([[1.0, 1.0]])) == pytest.approx(0.5 * math.sqrt(2))


def test_oracle_sees_the_collisions_of_runs_without_the_check():
    run = simulate(PAPER_SCENARIOS["2-3"]().with_params(collision_check=False))
    sc = PAPER_SCENARIOS["2-3"]()
    d, _, _ = min_obstacle_separation(sc, run.times, run.trajectory)
    assert d < sc.params.collision_distance
    hits = 0
    for seed in SEEDS[:20]:
        sc = random_agv_scenario(seed, params=AgvParams(collision_check=False))
        run = simulate(sc, seed=seed)
        hits += min_obstacle_separation(sc, run.times, run.trajectory)[0] \
            < sc.params.collision_distance
    assert hits > 0


# -- the suite on unseen seeds ------------------------------------------------------------
@pytest.fixture(scope="module")
def suite():
    out = []
    for seed in SEEDS:
        sc = random_agv_scenario(seed)  # the suite's params: drift and check points on
        # free_time given: the obstacle-free twin run (only its arrival time) is not needed
        out.append((seed, sc, simulate(sc, seed=seed, free_time=0.0)))
    return out


def test_unseen_seeds_never_collide_by_the_oracle(suite):
    for seed, sc, run in suite:
        d, j, t = min_obstacle_separation(sc, run.times, run.trajectory)
        assert d >= sc.params.collision_distance, (seed, j, t, d)
        assert wall_clearance(sc.world.occupancy, run.trajectory) > 0.0, seed


def test_unseen_seeds_never_collide_by_the_simulator_and_mostly_arrive(suite):
    outcomes = [run.outcome for _, _, run in suite]
    assert Outcome.COLLISION not in outcomes
    assert outcomes.count(Outcome.SUCCESS) >= 0.95 * len(outcomes)

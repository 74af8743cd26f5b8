"""Every registered polygon planner on thousands of seeded random worlds, checked by shapely.

A world is a 3 x 3 layout of cells over 100 x 100, each cell empty, a convex
hull of random points, or a U shape (non-convex, with a pocket); a convex
obstacle in a border cell may be stretched to touch the wall(s) at a vertex
or along an edge, which closes the gap there (a corner obstacle touching both
walls seals a pocket). Start and goal are random free points.

The oracle is shapely alone (no project geometry): the free space is the box
minus the union of the obstacles, split into its connected pieces; a planner
succeeds exactly when start and goal lie in the same piece, and a successful
path stays in that piece, never enters an obstacle's interior and never passes
through a place where an obstacle touches the wall.

``make test`` runs :data:`WORLDS` (2,000) seeded worlds (``POLYGON_WORLDS``
overrides; about 35 s of CPU); the ``fuzz`` variant runs 2,000 more
(``FUZZ_WORLDS``) with fresh seeds.
"""

from __future__ import annotations

import contextlib
import os

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon, box
from shapely.ops import unary_union

from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.base import planners
from subtask_opt.planners.polygon.world import PolygonWorld, convex_hull
from tests.fuzz_report import Timer

POLYGON = planners("polygon")
SIDE = 100.0
CELL = SIDE / 3
WORLDS = int(os.environ.get("POLYGON_WORLDS", "2000"))
FUZZ_WORLDS = int(os.environ.get("FUZZ_WORLDS", "2000"))
TOL = 1e-6


def _u_shape(cx: int, cy: int, turn: int, depth: float) -> np.ndarray:
    u = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.7, 0.9], [0.7, 0.9 - 0.6 * depth],
                  [0.3, 0.9 - 0.6 * depth], [0.3, 0.9], [0.1, 0.9]])
    for _ in range(turn):  # a quarter turn about the cell centre
        u = np.column_stack([1.0 - u[:, 1], u[:, 0]])
    return (np.array([cx, cy]) + u) * CELL


def random_world(rng: np.random.Generator) -> PolygonWorld:
    """A seeded world of the module docstring (obstacles never touch one another)."""
    obstacles = []
    for cx in range(3):
        for cy in range(3):
            kind = rng.integers(0, 8)
            if kind < 3:
                continue
            if kind == 3:
                obstacles.append(_u_shape(cx, cy, int(rng.integers(0, 4)), rng.uniform(0.2, 0.9)))
                continue
            pts = (np.array([cx, cy]) + rng.uniform(0.1, 0.9, (int(rng.integers(3, 7)), 2))) * CELL
            extra = []
            sides = ((cx == 0, 0, 0.0, np.argmin), (cx == 2, 0, SIDE, np.argmax),
                     (cy == 0, 1, 0.0, np.argmin), (cy == 2, 1, SIDE, np.argmax))
            for near, axis, wall, pick in sides:
                if near and rng.random() < 0.4:
                    p = pts[pick(pts[:, axis])].copy()
                    p[axis] = wall
                    extra.append(p)
                    if rng.random() < 0.3:  # a whole edge along the wall
                        q = p.copy()
                        q[1 - axis] += rng.uniform(2.0, 6.0) * (1 if q[1 - axis] < SIDE / 2 else -1)
                        extra.append(q)
            hull = convex_hull(np.vstack([pts, *extra]) if extra else pts)
            if len(hull) >= 3 and Polygon(hull).area >= 5.0:
                obstacles.append(hull)
    return PolygonWorld((0.0, 0.0, SIDE, SIDE), tuple(obstacles), name="random")


def _free_point(rng: np.random.Generator, world: PolygonWorld) -> np.ndarray:
    for _ in range(1000):
        p = rng.uniform(0.0, SIDE, 2)
        if world.is_free(p) and world.distance_to_obstacles(p) > 1e-3:
            return p
    raise AssertionError("no free point in 1000 draws")


class Oracle:
    """Shapely's view of one world: free pieces, obstacle interiors, wall contacts."""

    def __init__(self, world: PolygonWorld):
        polys = [Polygon(p) for p in world.obstacles]
        frame = box(*world.bounds)
        free = frame.difference(unary_union(polys)) if polys else frame
        self.pieces = list(getattr(free, "geoms", [free]))
        self.interiors = [p.buffer(-TOL) for p in polys]
        walls = frame.exterior
        self.contacts = [p.exterior.intersection(walls) for p in polys]
        self.contacts = [c for c in self.contacts if not c.is_empty]

    def piece(self, p) -> int:
        return int(np.argmin([g.distance(Point(p)) for g in self.pieces]))

    def violations(self, path: np.ndarray, start, goal) -> list[str]:
        line = LineString(path) if len(path) > 1 else LineString([path[0], path[0]])
        out = []
        k = self.piece(start)
        if not self.pieces[k].buffer(TOL).covers(line):
            out.append("leaves the start's free piece")
        out += [f"enters obstacle {i}" for i, s in enumerate(self.interiors)
                if not s.is_empty and line.intersects(s)]
        out += ["passes a wall contact" for c in self.contacts if line.distance(c) <= TOL]
        return out


def _check_worlds(seeds: np.ndarray, report: str = "") -> dict[str, int]:
    """Every planner on one world per seed; the successes per planner. With ``report``
    (a test id) each world counts as one input of a fuzz run."""
    successes = dict.fromkeys(POLYGON, 0)
    for seed in seeds:
        with Timer(report) if report else contextlib.nullcontext():
            _check_world(int(seed), successes)
    return successes


def _check_world(seed: int, successes: dict[str, int]) -> None:
    """One world: every planner against the shapely oracle."""
    rng = np.random.default_rng(int(seed))
    world = random_world(rng)
    start, goal = _free_point(rng, world), _free_point(rng, world)
    oracle = Oracle(world)
    same = oracle.piece(start) == oracle.piece(goal)
    for name, info in POLYGON.items():
        kwargs: dict = {}
        if info.stochastic:
            kwargs["seed"] = int(seed)
        if info.iterative:
            kwargs["stop"] = MaxGenerations(20)
        res = info.plan(world, start, goal, **kwargs)
        assert res.success == same, (int(seed), name, res.message)
        if res.success:
            successes[name] += 1
            assert np.allclose(res.path[0], start) and np.allclose(res.path[-1], goal)
            bad = oracle.violations(res.path, start, goal)
            assert bad == [], (int(seed), name, bad)


def test_oracle_sees_the_closed_corner_and_a_crossing():
    # the world: the triangle touches both walls and seals the corner
    world = PolygonWorld((0, 0, 10, 10), ([[6, 6], [10, 6], [6, 10]],))
    o = Oracle(world)
    assert len(o.pieces) == 2 and o.piece((1, 1)) != o.piece((9.5, 9.5))
    assert o.violations(np.array([[1, 1], [10, 6], [9.5, 9.5]]), (1, 1), (9.5, 9.5))
    assert o.violations(np.array([[1, 1], [7, 7]]), (1, 1), (7, 7))  # into the triangle
    assert o.violations(np.array([[1, 1], [5, 5]]), (1, 1), (5, 5)) == []
    # one vertex on the wall: free on both sides, but not through the contact
    pinch = PolygonWorld((0, 0, 10, 10), ([[4, 0], [6, 3], [2, 3]],))
    o = Oracle(pinch)
    assert o.piece((1, 0.5)) == o.piece((9, 0.5))
    assert o.violations(np.array([[1, 0], [9, 0]]), (1, 0), (9, 0)) == ["passes a wall contact"]


def test_generator_makes_wall_contacts_and_sealed_pockets():
    contacts = sealed = 0
    for seed in range(200):
        o = Oracle(random_world(np.random.default_rng(seed)))
        contacts += bool(o.contacts)
        sealed += len(o.pieces) > 1
    assert contacts > 40 and sealed > 5


def test_every_planner_on_random_worlds():
    successes = _check_worlds(np.arange(WORLDS))
    assert min(successes.values()) > WORLDS // 2, successes


@pytest.mark.fuzz
def test_fuzz_every_planner_on_2000_random_worlds(request):
    seeds = np.random.default_rng().integers(0, 2**63 - 1, FUZZ_WORLDS)
    successes = _check_worlds(seeds, request.node.nodeid)
    assert min(successes.values()) > FUZZ_WORLDS // 2, successes

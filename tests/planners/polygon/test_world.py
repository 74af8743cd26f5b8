"""PolygonWorld: validation, JSON, point and segment predicates against independent oracles.

The oracles here (Cyrus-Beck clipping against convex polygons, brute-force
distances, a random world of convex obstacles) are reused by the planner tests.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, UnreachableError
from subtask_opt.planners.polygon.world import PolygonWorld, convex_hull

# -- independent oracles (numpy / pure Python; no project geometry) ---------------


def segment_enters_convex(p, q, poly, tol=1e-9) -> bool:
    """Whether segment pq meets the open interior of a convex polygon (any orientation).

    Cyrus-Beck: the interior is the intersection of open half-planes; the set of
    t in [0, 1] inside all of them is an interval, non-empty of positive length
    iff the segment enters the interior.
    """
    poly = np.asarray(poly, dtype=float)
    x, y = poly[:, 0], poly[:, 1]
    if 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 0:
        poly = poly[::-1]
    p = np.asarray(p, dtype=float)
    d = np.asarray(q, dtype=float) - p
    lo, hi = 0.0, 1.0
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        e = b - a
        n = np.hypot(*e)
        c0 = (e[0] * (p[1] - a[1]) - e[1] * (p[0] - a[0])) / n  # signed distance at t=0
        c1 = (e[0] * d[1] - e[1] * d[0]) / n
        if abs(c1) < 1e-12:
            if c0 <= tol:
                return False
            continue
        t = -c0 / c1
        if c1 > 0:
            lo = max(lo, t)
        else:
            hi = min(hi, t)
    seg = np.hypot(*d)
    if seg == 0:
        return lo <= hi and all(
            (b - a)[0] * (p[1] - a[1]) - (b - a)[1] * (p[0] - a[0]) > tol
            for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True))
    return (hi - lo) * seg > tol


def path_is_free_convex(path, world: PolygonWorld) -> bool:
    """Independent path test for worlds of convex obstacles: bounds + Cyrus-Beck."""
    path = np.asarray(path, dtype=float)
    x0, y0, x1, y1 = world.bounds
    tol = 1e-7
    if np.any(path[:, 0] < x0 - tol) or np.any(path[:, 0] > x1 + tol):
        return False
    if np.any(path[:, 1] < y0 - tol) or np.any(path[:, 1] > y1 + tol):
        return False
    return not any(segment_enters_convex(path[i], path[i + 1], poly, tol=1e-6)
                   for i in range(len(path) - 1) for poly in world.obstacles)


def brute_distance(p, segments) -> float:
    """Distance from p to the nearest of (m, 4) segments, vectorised numpy."""
    p = np.asarray(p, dtype=float)
    a, b = segments[:, :2], segments[:, 2:]
    ab = b - a
    t = np.clip(np.sum((p - a) * ab, axis=1) / np.sum(ab * ab, axis=1), 0, 1)
    return float(np.min(np.hypot(*(a + t[:, None] * ab - p).T)))


@st.composite
def convex_worlds(draw, max_cells: int = 3):
    """Random worlds of convex obstacles, one per cell of a 3 x 3 grid over 100 x 100.

    Each obstacle is the hull of random points inside a shrunken cell, so
    obstacles never touch. Returns (world, free points to use as start/goal).
    """
    size = 100.0 / max_cells
    obstacles = []
    for cx in range(max_cells):
        for cy in range(max_cells):
            if not draw(st.booleans()):
                continue
            pts = np.array(draw(st.lists(
                st.tuples(st.floats(0.1, 0.9), st.floats(0.1, 0.9)), min_size=3, max_size=6)))
            pts = (np.array([cx, cy]) + pts) * size
            hull = convex_hull(pts)
            if len(hull) < 3:
                continue
            x, y = hull[:, 0], hull[:, 1]
            if 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 5.0:
                continue
            obstacles.append(hull)
    return PolygonWorld((0.0, 0.0, 100.0, 100.0), tuple(obstacles), name="random")


def free_point(draw, world: PolygonWorld) -> np.ndarray:
    """A free point at least 1e-3 away from every obstacle (rejects the example otherwise)."""
    p = np.array([draw(st.floats(0.0, 100.0)), draw(st.floats(0.0, 100.0))])
    assume(world.is_free(p) and world.distance_to_obstacles(p) > 1e-3)
    return p


# -- the built-in world --------------------------------------------------------------


def test_seed003_is_the_papers_six_hulls(seed003):
    assert seed003.bounds == (0.0, 0.0, 350.0, 350.0)
    assert len(seed003.obstacles) == 6
    # first obstacle: its listed order is not simple, its hull is the rectangle 40-66 x 151-288
    rect = seed003.obstacles[0]
    assert sorted(map(tuple, rect)) == [(40, 151), (40, 288), (66, 151), (66, 288)]
    assert [len(p) for p in seed003.obstacles] == [4, 4, 4, 3, 5, 3]
    for poly in seed003.obstacles:  # stored counter-clockwise
        x, y = poly[:, 0], poly[:, 1]
        assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0
    assert seed003.edges.shape == (23, 4)
    assert seed003.boundary_edges.shape == (4, 4)


def test_unknown_builtin_lists_names():
    with pytest.raises(InputDataError, match="seed003"):
        PolygonWorld.builtin("nope")


def test_json_round_trip(tmp_path, seed003):
    path = tmp_path / "w.json"
    seed003.to_json(path)
    again = PolygonWorld.from_json(path)
    assert again == seed003
    d = json.loads(path.read_text())
    assert set(d) >= {"bounds", "obstacles"}
    assert PolygonWorld.from_dict(seed003.to_dict()) == seed003


def test_clockwise_and_closed_input_is_normalised():
    cw_closed = [[1, 1], [1, 2], [2, 2], [2, 1], [1, 1]]
    w = PolygonWorld((0, 0, 3, 3), (cw_closed,))
    assert len(w.obstacles[0]) == 4
    x, y = w.obstacles[0][:, 0], w.obstacles[0][:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0


# -- validation ----------------------------------------------------------------------

SQUARE = [[1, 1], [2, 1], [2, 2], [1, 2]]


@pytest.mark.parametrize("bounds, obstacles, match", [
    ((0, 0, 0, 3), (), "xmin < xmax"),
    ((0, 0, 3), (), "four"),
    ((0, 0, float("nan"), 3), (), "finite"),
    ("abcd", (), "numbers"),
    ((0, 0, 3, 3), ([[1, 1], [2, 2]],), "obstacle 0 needs at least 3"),
    ((0, 0, 3, 3), ([[1, 1], [2, 2], [3, 3]],), "obstacle 0 is degenerate"),
    ((0, 0, 3, 3), (SQUARE, [[0, 0], [1, 0], [0.5, float("inf")]]),
     "obstacle 1 vertex 2 must be two finite numbers"),
    ((0, 0, 3, 3), ([[0, 0], [2, 2], [2, 0], [0, 3]],), "obstacle 0 is not a simple"),
    ((0, 0, 3, 3), ([[0, 0], [2, 0], [2, 2], [2, 1]],), "obstacle 0 is not a simple"),
    ((0, 0, 3, 3), ([[0.5, 0.5], [1, 0.5], [1, 0.5], [0.5, 1]],), "obstacle 0 is not a simple"),
    ((0, 0, 3, 3), (SQUARE, [[2, 2], [4, 2], [4, 3]]), "obstacle 1 leaves the bounds"),
    ((0, 0, 3, 3), (SQUARE, [[1.5, 1.5], [2.5, 1.5], [2.5, 2.5]]), "obstacles 0 and 1 overlap"),
    ((0, 0, 3, 3), (SQUARE, [[2, 1], [3, 1], [3, 2]]), "obstacles 0 and 1 overlap or touch"),
    ((0, 0, 9, 9), ([[1, 1], [8, 1], [8, 8], [1, 8]], [[3, 3], [4, 3], [4, 4]]),
     "obstacles 0 and 1 overlap"),
    ((0, 0, 3, 3), ([[1, 1], [2, 1], ["a", 2]],), "obstacle 0 vertex 2 must be two finite"),
    ((0, 0, 3, 3), ([[1, 1], [2, 1], ["2", "2"]],), "obstacle 0 vertex 2 must be two finite"),
    ((0, 0, 3, 3), ([[1, 1], [2, 1], [True, 2]],), "obstacle 0 vertex 2 must be two finite"),
    ((0, 0, 3, 3), ([[1, 1], [2, 1], [10**400, 2]],), "obstacle 0 vertex 2 must be two finite"),
    ((0, 0, 3, 3), ([1, 2, 3],), "obstacle 0 vertex 0 must be a pair"),
    ((0, 0, 3, 3), ("abc",), "obstacle 0 must be a list"),
    (("0", 0, 3, 3), (), "four finite numbers"),
    # finite but so large that an area overflows: refused, not a RuntimeWarning
    ((0, 0, 3, 3), ([[1, 1], [2e200, 1], [2, 2e200]],), r"obstacle 0 has a coordinate beyond"),
    ((-1e300, 0, 3, 3), (), r"bounds must lie within \+-1e\+09"),
])
def test_bad_worlds_raise(bounds, obstacles, match):
    with pytest.raises(InputDataError, match=match):
        PolygonWorld(bounds, obstacles)


@pytest.mark.parametrize("d, match", [
    ([1, 2], "JSON object"),
    ({"bounds": [0, 0, 1, 1]}, "missing 'obstacles'"),
    ({"bounds": [0, 0, 1, 1], "obstacles": 5}, "list of polygons"),
])
def test_bad_dicts_raise(d, match):
    with pytest.raises(InputDataError, match=match):
        PolygonWorld.from_dict(d)


def test_bad_json_file(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{not json")
    with pytest.raises(InputDataError, match="bad.json"):
        PolygonWorld.from_json(path)
    with pytest.raises(InputDataError, match="not found"):  # one line, never an OSError
        PolygonWorld.from_json(tmp_path / "missing.json")


# -- point predicates -----------------------------------------------------------------


def test_point_predicates(seed003):
    assert seed003.obstacle_at((50, 200)) == 0
    assert seed003.obstacle_at((40, 200)) == 0  # on the boundary: closed area
    assert seed003.obstacle_at((20, 20)) == -1
    assert seed003.is_free((20, 20))
    assert seed003.is_free((0, 0))  # bounds are closed
    assert not seed003.is_free((40, 200))
    assert not seed003.is_free((-1, 20))


@pytest.mark.parametrize("p, exc, match", [
    ((50, 200), UnreachableError, r"start \(50, 200\) is inside obstacle 0"),
    ((400, 10), UnreachableError, r"start \(400, 10\) is outside the world bounds"),
    ((1, 2, 3), InputDataError, "start must be two finite"),
    ((float("nan"), 2), InputDataError, "start must be two finite"),
    ("xy", InputDataError, "start must be two numbers"),
])
def test_check_point_errors(seed003, p, exc, match):
    with pytest.raises(exc, match=match):
        seed003.check_point("start", p)


def test_check_point_returns_array(seed003):
    p = seed003.check_point("goal", [320, 320])
    assert p.dtype == float and p.tolist() == [320.0, 320.0]


# -- segment predicate ------------------------------------------------------------------


def test_segment_free_touching_is_allowed(seed003):
    assert seed003.segment_free((40, 100), (40, 300))  # slides along the rectangle's left edge
    assert seed003.segment_free((30, 140), (40, 151))  # ends on a vertex
    assert seed003.segment_free((20, 151), (80, 151))  # along the bottom edge, past both ends
    assert not seed003.segment_free((40, 151), (66, 288))  # the rectangle's diagonal
    assert not seed003.segment_free((20, 20), (320, 320))
    assert not seed003.segment_free((20, 20), (400, 20))  # leaves the bounds


def test_segment_free_non_convex_obstacle():
    # a U-shaped obstacle open at the top; the pocket is free space
    u = [[1, 1], [5, 1], [5, 5], [4, 5], [4, 2], [2, 2], [2, 5], [1, 5]]
    w = PolygonWorld((0, 0, 6, 6), (u,))
    assert w.segment_free((2, 5), (4, 5))  # across the mouth, vertex to vertex
    assert w.segment_free((3, 2.5), (3, 5.5))  # inside the pocket
    assert w.segment_free((2, 2), (4, 2))  # along the pocket floor
    assert not w.segment_free((0.5, 3), (3, 3))  # through the left arm
    assert w.segment_free((1, 5), (5, 5))  # along the tops of both arms and across the mouth
    assert not w.segment_free((1, 4.5), (5, 4.5))  # through both arms
    assert w.segment_free((1, 5), (2, 5)) and w.segment_free((1, 1), (5, 1))
    assert not w.segment_free((1, 1), (5, 5))
    assert w.obstacle_at((3, 3)) == -1 and w.obstacle_at((1.5, 3)) == 0


@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_segment_free_matches_cyrus_beck(data):
    world = data.draw(convex_worlds())
    pts = [np.array([data.draw(st.floats(0, 100)), data.draw(st.floats(0, 100))])
           for _ in range(2)]
    verts = world.vertices
    if len(verts) and data.draw(st.booleans()):  # segments through vertices are the hard case
        pts[0] = verts[data.draw(st.integers(0, len(verts) - 1))]
    if len(verts) and data.draw(st.booleans()):
        pts[1] = verts[data.draw(st.integers(0, len(verts) - 1))]
    p, q = pts
    expected = not any(segment_enters_convex(p, q, poly) for poly in world.obstacles)
    assert world.segment_free(p, q) == expected


@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_distance_to_obstacles_matches_brute_force(data):
    world = data.draw(convex_worlds())
    p = np.array([data.draw(st.floats(0, 100)), data.draw(st.floats(0, 100))])
    segs = np.vstack([world.edges, world.boundary_edges])
    assert world.distance_to_obstacles(p) == pytest.approx(brute_distance(p, segs), abs=1e-9)

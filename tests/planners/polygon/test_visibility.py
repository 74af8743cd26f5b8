"""Exact shortest paths: against an independent visibility graph (Cyrus-Beck + scipy)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import shortest_path

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.planners.polygon import visibility
from subtask_opt.planners.polygon.world import PolygonWorld
from tests.planners.polygon.test_world import (
    convex_worlds,
    free_point,
    path_is_free_convex,
    segment_enters_convex,
)


def oracle_length(world: PolygonWorld, start, goal) -> float:
    """Shortest path over ALL obstacle vertices + start + goal, with Cyrus-Beck
    visibility and scipy's Dijkstra: nothing from the project but the world's polygons."""
    if math.dist(start, goal) == 0.0:
        return 0.0
    pts = [np.asarray(start, float), np.asarray(goal, float)]
    pts += [v for poly in world.obstacles for v in poly]
    n = len(pts)
    dense = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            if not any(segment_enters_convex(pts[i], pts[j], poly) for poly in world.obstacles):
                # the tiny offset keeps zero-length edges (coincident points) as edges
                dense[i, j] = dense[j, i] = math.dist(pts[i], pts[j]) + 1e-300
    return float(shortest_path(dense, method="D", directed=False, indices=0)[1])


# The two reference optima stated in the issue (computed there independently).
@pytest.mark.parametrize("start, goal, stated", [
    ((20, 20), (320, 320), 425.4666),
    ((10, 340), (340, 10), 479.5948),
])
def test_seed003_reference_optima(seed003, start, goal, stated):
    res = visibility.plan(seed003, start, goal)
    assert res.success and res.planner == "visibility"
    assert round(res.length, 4) == stated
    assert res.length == pytest.approx(oracle_length(seed003, start, goal), rel=1e-12)
    assert path_is_free_convex(res.path, seed003)
    assert visibility.shortest_path_length(seed003, start, goal) == pytest.approx(res.length)
    # corners of a shortest path are obstacle vertices
    for v in res.path[1:-1]:
        assert np.min(np.hypot(*(seed003.vertices - v).T)) == 0.0
    assert res.info["vertices"] and res.info["graph_nodes"] > 2


def test_all_vertices_give_the_same_length(seed003):
    a = visibility.plan(seed003, (10, 340), (340, 10))
    b = visibility.plan(seed003, (10, 340), (340, 10),
                        params=visibility.VisibilityParams(convex_only=False))
    assert b.length == pytest.approx(a.length)
    assert b.info["graph_nodes"] >= a.info["graph_nodes"]


def test_straight_line_and_same_point(seed003):
    res = visibility.plan(seed003, (10, 10), (300, 20))
    assert len(res.path) == 2 and res.length == pytest.approx(math.hypot(290, 10))
    assert visibility.shortest_path_length(seed003, (5, 5), (5, 5)) == 0.0


def test_non_convex_obstacle_pocket():
    # from inside a U's pocket to below it: out of the mouth and around an arm
    u = [[1, 1], [5, 1], [5, 5], [4, 5], [4, 2], [2, 2], [2, 5], [1, 5]]
    w = PolygonWorld((0, 0, 6, 6), (u,))
    res = visibility.plan(w, (3, 3), (3, 0.5))
    expected = math.dist((3, 3), (4, 5)) + math.dist((4, 5), (5, 5)) + math.dist(
        (5, 5), (5, 1)) + math.dist((5, 1), (3, 0.5))
    assert res.length == pytest.approx(expected)
    assert w.path_free(res.path)


def test_separated_world_has_no_path():
    wall = PolygonWorld((0, 0, 10, 10), ([[0, 4], [10, 4], [10, 6], [0, 6]],))
    res = visibility.plan(wall, (5, 2), (5, 8))
    assert not res.success and "no collision-free path" in res.message
    assert res.path.shape == (0, 2) and math.isinf(res.length)
    assert math.isinf(visibility.shortest_path_length(wall, (5, 2), (5, 8)))


@pytest.mark.parametrize("start, exc", [
    ((50, 200), UnreachableError),
    ((-5, 20), UnreachableError),
    ((1, 2, 3), InputDataError),
])
def test_bad_points_raise(seed003, start, exc):
    with pytest.raises(exc, match="start"):
        visibility.plan(seed003, start, (320, 320))
    with pytest.raises(exc, match="start"):
        visibility.shortest_path_length(seed003, start, (320, 320))


def test_bad_params():
    with pytest.raises(ParameterError, match="convex_only"):
        visibility.VisibilityParams(convex_only="yes")  # type: ignore[arg-type]


@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_random_worlds_match_oracle(data):
    world = data.draw(convex_worlds())
    start, goal = free_point(data.draw, world), free_point(data.draw, world)
    res = visibility.plan(world, start, goal)
    assert res.success
    assert path_is_free_convex(res.path, world)
    assert res.length == pytest.approx(oracle_length(world, start, goal), rel=1e-9, abs=1e-9)
    assert res.length >= math.dist(start, goal) - 1e-9

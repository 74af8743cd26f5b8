"""MAKLINK graph, Dijkstra and improved Dijkstra: structure and paths against oracles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import shortest_path

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.polygon import maklink, visibility
from subtask_opt.planners.polygon.world import PolygonWorld
from tests.planners.polygon.test_world import (
    convex_worlds,
    free_point,
    path_is_free_convex,
    segment_enters_convex,
)


def shoelace(poly) -> float:
    x, y = np.asarray(poly, float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def segments_cross(a, b, c, d) -> bool:
    """Independent test: the open segments ab and cd share a point (orientation signs)."""
    def orient(p, q, r):
        v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        return 0 if abs(v) < 1e-9 else (1 if v > 0 else -1)
    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    # collinear overlap of positive length
    if o1 == o2 == o3 == o4 == 0:
        u = np.subtract(b, a)
        tc, td = (np.dot(np.subtract(p, a), u) / np.dot(u, u) for p in (c, d))
        lo, hi = max(0.0, min(tc, td)), min(1.0, max(tc, td))
        return hi - lo > 1e-9
    return False


def check_graph_invariants(world: PolygonWorld, graph: maklink.MaklinkGraph) -> None:
    x0, y0, x1, y1 = world.bounds
    # the cells and the obstacles tile the bounds
    area = sum(shoelace(c) for c in graph.cells) + sum(shoelace(p) for p in world.obstacles)
    assert area == pytest.approx((x1 - x0) * (y1 - y0), rel=1e-9)
    for cell in graph.cells:
        assert shoelace(cell) > 0
        assert maklink.cell_is_convex(cell)
    links = graph.links
    verts = [tuple(v) for v in world.vertices]
    for k, (a, b) in enumerate(zip(links[:, :2], links[:, 2:], strict=True)):
        assert not any(segment_enters_convex(a, b, p) for p in world.obstacles)
        # one end at least is an obstacle vertex; the other a vertex or on the boundary
        ends_vertex = [tuple(a) in verts, tuple(b) in verts]
        assert any(ends_vertex)
        for end, is_v in zip((a, b), ends_vertex, strict=True):
            if not is_v:
                assert min(abs(end[0] - x0), abs(end[0] - x1), abs(end[1] - y0),
                           abs(end[1] - y1)) < 1e-9
        c0, c1 = graph.link_cells[k]
        assert c0 >= 0 and c1 >= 0 and c0 != c1
        assert k in graph.cell_links[c0] and k in graph.cell_links[c1]
        for j in range(k + 1, len(links)):
            assert not segments_cross(a, b, links[j, :2], links[j, 2:])


@pytest.fixture(scope="module")
def graph003(seed003) -> maklink.MaklinkGraph:
    return maklink.graph_for(seed003)


def test_seed003_graph_is_a_convex_partition(seed003, graph003):
    check_graph_invariants(seed003, graph003)
    # Euler: each link joins two components or splits a cell
    assert len(graph003.cells) == graph003.n_links - len(seed003.obstacles) + 1
    assert maklink.graph_for(seed003) is graph003  # cached


def test_no_link_is_redundant(graph003):
    # removing any single link would merge two cells into a non-convex one
    for k in range(graph003.n_links):
        c0, c1 = graph003.link_cells[k]
        merged = np.vstack([graph003.cells[c0], graph003.cells[c1]])
        union_area = shoelace(graph003.cells[c0]) + shoelace(graph003.cells[c1])
        hull = _hull_area(merged)
        assert hull > union_area * (1 + 1e-9)


def _hull_area(pts) -> float:
    from scipy.spatial import ConvexHull

    return float(ConvexHull(pts).volume)


@pytest.mark.parametrize("start, goal", [((20, 20), (320, 320)), ((10, 340), (340, 10))])
def test_seed003_routes(seed003, graph003, start, goal):
    d = maklink.dijkstra(seed003, start, goal)
    i = maklink.improved_dijkstra(seed003, start, goal)
    opt = visibility.plan(seed003, start, goal).length
    assert d.success and i.success
    assert opt - 1e-9 <= i.length <= d.length
    assert i.info["dijkstra_length"] == pytest.approx(d.length)
    assert path_is_free_convex(d.path, seed003) and path_is_free_convex(i.path, seed003)
    # the Dijkstra route is optimal on the graph (scipy on the same cell adjacency)
    assert d.length == pytest.approx(_scipy_route_length(graph003, np.array(start, float),
                                                         np.array(goal, float)))
    # improved keeps start, goal and a subsequence of the route nodes
    assert all(any(np.allclose(p, q) for q in d.path) for p in i.path)
    # the Dijkstra path crosses exactly its links, at their midpoints
    ids, t = maklink.crossed_links(graph003, d.path)
    assert ids.tolist() == d.info["links"]
    np.testing.assert_allclose(t, 0.5)
    # the improved path, put back on its crossed links, has the same length
    ids, t = maklink.crossed_links(graph003, i.path)
    pts = np.vstack([start, maklink.points_on_links(graph003, ids, t), goal])
    assert float(np.sum(np.hypot(*np.diff(pts, axis=0).T))) == pytest.approx(i.length)


def _scipy_route_length(graph, start, goal) -> float:
    mids = graph.midpoints
    n = graph.n_links
    nodes = np.vstack([mids, start, goal])
    dense = np.zeros((n + 2, n + 2))
    groups = [list(ids) for ids in graph.cell_links]
    for c, ids in enumerate(graph.cell_links):
        members = list(ids)
        if graph.cells_containing(start).count(c):
            members.append(n)
        if graph.cells_containing(goal).count(c):
            members.append(n + 1)
        groups[c] = members
    for members in groups:
        for a in members:
            for b in members:
                if a != b:
                    dense[a, b] = math.dist(nodes[a], nodes[b])
    return float(shortest_path(dense, method="D", directed=False, indices=n)[n + 1])


def test_empty_world_is_one_cell():
    w = PolygonWorld((0, 0, 10, 5), ())
    g = maklink.build_graph(w)
    assert g.n_links == 0 and len(g.cells) == 1
    res = maklink.dijkstra(w, (1, 1), (9, 4))
    assert res.success and len(res.path) == 2


def test_obstacle_touching_the_boundary():
    # a triangle with a vertex on the bottom wall, a square with an edge on the top wall
    w = PolygonWorld((0, 0, 10, 10), ([[4, 0], [6, 3], [3, 3]], [[4, 8], [7, 8], [7, 10], [4, 10]]))
    g = maklink.build_graph(w)
    check_graph_invariants(w, g)
    for start, goal in (((1, 1), (9, 1)), ((1, 9), (9, 9))):
        res = maklink.improved_dijkstra(w, start, goal)
        assert res.success and path_is_free_convex(res.path, w)
        # no slipping through the zero-width gap at the wall
        assert not any(np.allclose(p, (4, 0)) or p[1] >= 10 - 1e-9 for p in res.path[1:-1])
        assert res.length >= visibility.plan(w, start, goal).length - 1e-9


def test_separated_world_has_no_route():
    wall = PolygonWorld((0, 0, 10, 10), ([[0, 4], [10, 4], [10, 6], [0, 6]],))
    res = maklink.dijkstra(wall, (5, 2), (5, 8))
    assert not res.success and "no collision-free path" in res.message
    assert res.path.shape == (0, 2)


def test_bad_input(seed003):
    with pytest.raises(UnreachableError, match=r"goal \(50, 200\) is inside obstacle 0"):
        maklink.dijkstra(seed003, (20, 20), (50, 200))
    for fn, name in ((maklink.dijkstra, "dijkstra"), (maklink.improved_dijkstra, "improved")):
        with pytest.raises(ParameterError, match=f"{name} is deterministic and takes no seed"):
            fn(seed003, (20, 20), (320, 320), seed=0)
        with pytest.raises(ParameterError, match=f"{name} is not iterative"):
            fn(seed003, (20, 20), (320, 320), stop=MaxGenerations(5))
        with pytest.raises(ParameterError, match=f"{name} params must be None"):
            fn(seed003, (20, 20), (320, 320), params={"improve": True})


def test_shortcut_is_free_and_not_longer(seed003):
    # a free zigzag left of and below obstacle 2
    zigzag = np.array([[20, 20], [30, 140], [80, 20], [100, 30]], float)
    out = maklink.shortcut(seed003, zigzag)
    assert np.allclose(out[0], zigzag[0]) and np.allclose(out[-1], zigzag[-1])
    assert seed003.path_free(out)
    assert np.sum(np.hypot(*np.diff(out, axis=0).T)) <= np.sum(
        np.hypot(*np.diff(zigzag, axis=0).T))


@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_random_worlds(data):
    world = data.draw(convex_worlds())
    graph = maklink.build_graph(world)
    check_graph_invariants(world, graph)
    start, goal = free_point(data.draw, world), free_point(data.draw, world)
    d = maklink.dijkstra(world, start, goal)
    i = maklink.improved_dijkstra(world, start, goal)
    assert d.success and i.success
    assert path_is_free_convex(d.path, world) and path_is_free_convex(i.path, world)
    assert visibility.plan(world, start, goal).length - 1e-9 <= i.length <= d.length + 1e-9


def test_crossed_links_rejects_a_path_through_an_obstacle(graph003):
    with pytest.raises(InputDataError, match="enters an obstacle"):
        maklink.crossed_links(graph003, np.array([[20.0, 20.0], [320.0, 320.0]]))

"""MAKLINK free-link graph (Habib & Asama 1991), Dijkstra and improved Dijkstra.

Free links join obstacle vertices to other obstacle vertices or to the outer
boundary so that they, the obstacle edges and the boundary cut the free space
into convex cells. They are built in two passes:

1. Greedy: every usable candidate (vertex-vertex, and vertex to a boundary
   point: the corners and the perpendicular feet of all vertices on the four
   walls) in order of length, kept unless it meets a kept link. The result is
   maximal, and a maximal set leaves only convex cells: a reflex corner of a
   cell (necessarily an obstacle vertex) would see another corner of its cell
   through a diagonal that is itself an unused candidate.
2. Pruning, longest link first: a link goes when the cells on its two sides
   merge into a convex cell, i.e. when the angle left at both of its ends is
   at most 180 deg. What remains is the short, non-redundant link set of
   Habib & Asama (the paper's Fig. 1).

Graph nodes are the link midpoints plus start and goal; two nodes are joined
when they lie on the same convex cell (the segment between them then stays in
the cell and crosses no link) - the paper's Fig. 2. Dijkstra gives the
sub-optimal route of the paper's Fig. 3; "improved Dijkstra" shortens it by the
triangle inequality, joining route nodes directly wherever the straight line
is free (the shortest such shortcut chain, found by a small DP).

The route of any free path through the cells is its sequence of crossed
links; :func:`crossed_links` recovers it for the improved path, which is
where :mod:`.pso` starts.

Both planners are registered (``dijkstra``, ``improved``); they are
deterministic and refuse a seed or stopping criteria. The graph of a world is
kept in a small LRU cache in this module (:func:`graph_for`), never on the
world itself.

Cost: O(n^2) candidate links for n obstacle vertices (about 310 n^2 bytes at
peak), each tested against the obstacles and the links kept so far (numba).
About 5-10 ms for the 23 vertices of ``seed003``, 1-3 s for 216 vertices and 9-15 s
for 600 (after JIT warm-up, on a loaded shared machine).
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.base import register
from subtask_opt.planners.polygon import _kernels as gk
from subtask_opt.planners.polygon._routes import (
    check_deterministic,
    same_point,
    shortest_route,
    world_cache,
)
from subtask_opt.planners.polygon.world import PolygonWorld


@dataclass(frozen=True)
class MaklinkGraph:
    """The free links of a world and the convex cells they cut the free space into.

    Attributes:
        world: the world it was built for.
        points: (p, 2) end points of links, obstacle edges and wall pieces:
            first the obstacle vertices (rows of ``world.vertices``), then
            boundary points.
        link_ends: (l, 2) rows of ``points`` joined by each free link.
        cells: the convex free cells, each a (k, 2) counter-clockwise polygon.
        cell_links: for each cell, the ids of the links on its boundary.
        link_cells: (l, 2) the two cells each link separates.
    """

    world: PolygonWorld
    points: np.ndarray
    link_ends: np.ndarray
    cells: tuple[np.ndarray, ...]
    cell_links: tuple[np.ndarray, ...]
    link_cells: np.ndarray
    _cell_verts: np.ndarray
    _cell_offsets: np.ndarray
    _node_weights: np.ndarray

    @property
    def links(self) -> np.ndarray:
        """(l, 4) the free links as x1, y1, x2, y2."""
        return np.hstack([self.points[self.link_ends[:, 0]], self.points[self.link_ends[:, 1]]])

    @property
    def midpoints(self) -> np.ndarray:
        """(l, 2) the link midpoints, the graph's nodes besides start and goal."""
        return 0.5 * (self.points[self.link_ends[:, 0]] + self.points[self.link_ends[:, 1]])

    @property
    def n_links(self) -> int:
        return int(self.link_ends.shape[0])

    def graph_edges(self) -> np.ndarray:
        """(e, 2) pairs of link ids joined in the graph (same cell), i < j."""
        i, j = np.nonzero(np.triu(np.isfinite(self._node_weights), 1))
        return np.column_stack([i, j])

    def cells_containing(self, p: np.ndarray) -> list[int]:
        """Ids of the cells whose closed area holds p (two or more on a link)."""
        eps = self.world.eps
        return [c for c in range(len(self.cells))
                if gk.point_in_polygon(p[0], p[1], self._cell_verts, self._cell_offsets[c],
                                       self._cell_offsets[c + 1], eps) >= 0]

    def route(self, start: np.ndarray, goal: np.ndarray) -> tuple[float, list[int]]:
        """Dijkstra from start to goal over the link midpoints.

        Returns the length and the crossed link ids in order (``inf, []`` when
        no route exists). Start and goal must be free points (not checked here).
        """
        n = self.n_links
        mids = self.midpoints
        w = np.full((n + 2, n + 2), np.inf)
        w[:n, :n] = self._node_weights
        start_cells = self.cells_containing(start)
        goal_cells = self.cells_containing(goal)
        for row, p, cells in ((n, start, start_cells), (n + 1, goal, goal_cells)):
            for c in cells:
                ids = self.cell_links[c]
                d = np.hypot(*(mids[ids] - p).T)
                w[row, ids] = d
                w[ids, row] = d
        if set(start_cells) & set(goal_cells):
            w[n, n + 1] = w[n + 1, n] = float(np.hypot(*(goal - start)))
        length, nodes = shortest_route(w, n, n + 1)
        return length, nodes[1:-1]


# -- construction ---------------------------------------------------------------------


def build_graph(world: PolygonWorld) -> MaklinkGraph:
    """Build the MAKLINK graph of ``world`` (computed, not cached; see :func:`graph_for`).

    Time and memory grow with the square of the vertex count (the candidate
    links); the world refuses more vertices than fit in the memory limit.
    """
    verts, offsets, boxes, bounds, eps = world.kernel_arrays()
    x0, y0, x1, y1 = world.bounds
    nv = len(verts)
    obstacle_of = np.repeat(np.arange(len(world.obstacles)), np.diff(offsets))

    # Boundary points: corners, then the feet of every vertex on every wall.
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    feet = np.concatenate([
        np.column_stack([verts[:, 0], np.full(nv, y0)]),
        np.column_stack([np.full(nv, x1), verts[:, 1]]),
        np.column_stack([verts[:, 0], np.full(nv, y1)]),
        np.column_stack([np.full(nv, x0), verts[:, 1]]),
    ]) if nv else np.zeros((0, 2))
    points = _unique_points(np.vstack([verts, corners, feet]), nv, eps)
    on_wall = _wall_mask(points, world.bounds, eps)  # (p, 4) bottom, right, top, left

    # Candidate links: vertex-vertex (not an obstacle edge) and vertex-boundary point.
    iu, ju = np.triu_indices(nv, 1)
    same = obstacle_of[iu] == obstacle_of[ju]
    ring = np.diff(offsets)[obstacle_of[iu]]
    step = (ju - iu) % np.maximum(ring, 1)
    is_edge = same & ((step == 1) | (step == ring - 1))
    vv = np.column_stack([iu[~is_edge], ju[~is_edge]])
    boundary_ids = np.arange(nv, len(points))
    vb = np.column_stack([np.repeat(np.arange(nv), len(boundary_ids)),
                          np.tile(boundary_ids, nv)])
    cand = np.vstack([vv, vb]).astype(np.int64).reshape(-1, 2)
    along_wall = np.any(on_wall[cand[:, 0]] & on_wall[cand[:, 1]], axis=1)
    cand = cand[~along_wall]
    lengths = np.hypot(*(points[cand[:, 0]] - points[cand[:, 1]]).T)
    order = np.lexsort((cand[:, 1], cand[:, 0], lengths))  # ties broken deterministically
    cand = np.ascontiguousarray(cand[order])
    links = cand[gk.greedy_links(cand, points, verts, offsets, boxes, bounds, eps)]

    # The plane graph: obstacle edges, wall pieces between used boundary points, links.
    used = np.zeros(len(points), dtype=bool)
    used[links.ravel()] = True
    used[:nv] = True
    used |= on_wall.sum(axis=1) >= 2  # the corners
    obstacle_edges = [(offsets[k] + i, offsets[k] + (i + 1) % (offsets[k + 1] - offsets[k]))
                      for k in range(len(world.obstacles))
                      for i in range(offsets[k + 1] - offsets[k])]
    walls = _wall_pieces(world, points, used, on_wall)
    neighbours = _neighbours(points, obstacle_edges + walls + [tuple(e) for e in links])

    links = _prune(points, links, neighbours, eps)
    return _assemble(world, points, links, neighbours, set(obstacle_edges), eps)


@world_cache
def graph_for(world: PolygonWorld) -> MaklinkGraph:
    """:func:`build_graph`, cached per world (a small LRU in this module)."""
    return build_graph(world)


def _unique_points(pts: np.ndarray, keep_first: int, eps: float) -> np.ndarray:
    """Drop points within eps of an earlier kept one (the first ``keep_first`` are distinct).

    One row at a time (linear memory): the dense pairwise table would be the
    largest array of the whole construction.
    """
    keep = np.ones(len(pts), dtype=bool)
    for i in range(keep_first, len(pts)):
        d = np.hypot(pts[:i, 0] - pts[i, 0], pts[:i, 1] - pts[i, 1])
        if np.any((d <= eps) & keep[:i]):
            keep[i] = False
    return np.ascontiguousarray(pts[keep])


def _wall_mask(points: np.ndarray, bounds: tuple[float, ...], eps: float) -> np.ndarray:
    x0, y0, x1, y1 = bounds
    return np.column_stack([np.abs(points[:, 1] - y0) <= eps, np.abs(points[:, 0] - x1) <= eps,
                            np.abs(points[:, 1] - y1) <= eps, np.abs(points[:, 0] - x0) <= eps])


def _wall_pieces(world: PolygonWorld, points: np.ndarray, used: np.ndarray,
                 on_wall: np.ndarray) -> list[tuple[int, int]]:
    """Boundary segments between consecutive used boundary points, counter-clockwise,
    without those an obstacle edge already covers."""
    x0, y0, x1, y1 = world.bounds
    w, h = x1 - x0, y1 - y0
    ids = np.flatnonzero(used & on_wall.any(axis=1))
    p = points[ids]
    # position along the perimeter, counter-clockwise from (x0, y0)
    s = np.where(on_wall[ids, 0] & (p[:, 0] < x1 - world.eps), p[:, 0] - x0,
        np.where(on_wall[ids, 1] & (p[:, 1] < y1 - world.eps), w + p[:, 1] - y0,
        np.where(on_wall[ids, 2] & (p[:, 0] > x0 + world.eps), w + h + x1 - p[:, 0],
                 2 * w + h + y1 - p[:, 1])))
    ring = ids[np.argsort(s)]
    pieces = []
    for a, b in zip(ring, np.roll(ring, -1), strict=True):
        mid = 0.5 * (points[a] + points[b])
        if world.obstacle_at(mid) < 0:
            pieces.append((int(a), int(b)))
    return pieces


def _neighbours(points: np.ndarray, edges: list[tuple[int, int]]) -> dict[int, list[int]]:
    """Each point's neighbours sorted counter-clockwise by direction."""
    nb: dict[int, list[int]] = {}
    for a, b in edges:
        nb.setdefault(int(a), []).append(int(b))
        nb.setdefault(int(b), []).append(int(a))
    for u, vs in nb.items():
        d = points[vs] - points[u]
        nb[u] = [vs[i] for i in np.argsort(np.arctan2(d[:, 1], d[:, 0]), kind="stable")]
    return nb


def _angle(points: np.ndarray, u: int, a: int, b: int) -> float:
    """Counter-clockwise angle at u from direction u->a to direction u->b, in (0, 2 pi]."""
    da = points[a] - points[u]
    db = points[b] - points[u]
    ang = math.atan2(db[1], db[0]) - math.atan2(da[1], da[0])
    while ang <= 0:
        ang += 2 * math.pi
    return ang


def _prune(points: np.ndarray, links: np.ndarray, nb: dict[int, list[int]],
           eps: float) -> np.ndarray:
    """Remove links, longest first, whose two cells merge into a convex one (updates nb)."""
    lengths = np.hypot(*(points[links[:, 0]] - points[links[:, 1]]).T)
    keep = np.ones(len(links), dtype=bool)
    tol = 1e-9
    for k in np.argsort(-lengths, kind="stable"):
        u, v = int(links[k, 0]), int(links[k, 1])
        convex = True
        for a, b in ((u, v), (v, u)):
            ring = nb[a]
            i = ring.index(b)
            before, after = ring[i - 1], ring[(i + 1) % len(ring)]
            if len(ring) < 3 or _angle(points, a, before, after) > math.pi + tol:
                convex = False
                break
        if convex:
            keep[k] = False
            nb[u].remove(v)
            nb[v].remove(u)
    return links[keep]


def _assemble(world: PolygonWorld, points: np.ndarray, links: np.ndarray,
              nb: dict[int, list[int]], obstacle_edges: set[tuple[int, int]],
              eps: float) -> MaklinkGraph:
    """Trace the cells of the plane graph and build the node adjacency."""
    link_id = {}
    for k, (a, b) in enumerate(links):
        link_id[(int(a), int(b))] = k
        link_id[(int(b), int(a))] = k
    # Faces lie on the left of their half-edges; an obstacle's own counter-clockwise
    # edges bound its interior, so they are not traced.
    seen = set(obstacle_edges)
    cells: list[np.ndarray] = []
    cell_links: list[np.ndarray] = []
    link_cells = np.full((len(links), 2), -1, dtype=np.int64)
    for u, vs in nb.items():
        for v in vs:
            if (u, v) in seen:
                continue
            face = []
            a, b = u, v
            while (a, b) not in seen:
                seen.add((a, b))
                face.append(a)
                ring = nb[b]
                c = ring[ring.index(a) - 1]
                a, b = b, c
            poly = points[face]
            x, y = poly[:, 0], poly[:, 1]
            if 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) <= 0:
                continue  # the outside of the bounds
            ids = [link_id[(face[i], face[(i + 1) % len(face)])]
                   for i in range(len(face)) if (face[i], face[(i + 1) % len(face)]) in link_id]
            c_id = len(cells)
            for k in ids:
                link_cells[k, 0 if link_cells[k, 0] < 0 else 1] = c_id
            cells.append(_drop_straight(poly, eps))
            cell_links.append(np.array(sorted(set(ids)), dtype=np.int64))
    sizes = [len(c) for c in cells]
    cell_offsets = np.zeros(len(cells) + 1, dtype=np.int64)
    cell_offsets[1:] = np.cumsum(sizes)
    cell_verts = np.ascontiguousarray(np.concatenate(cells) if cells else np.zeros((0, 2)))
    mids = 0.5 * (points[links[:, 0]] + points[links[:, 1]]) if len(links) else np.zeros((0, 2))
    w = np.full((len(links), len(links)), np.inf)
    for members in cell_links:
        for i in members:
            for j in members:
                if i != j:
                    w[i, j] = math.hypot(*(mids[i] - mids[j]))
    return MaklinkGraph(world=world, points=points, link_ends=links.reshape(-1, 2),
                        cells=tuple(cells), cell_links=tuple(cell_links), link_cells=link_cells,
                        _cell_verts=cell_verts, _cell_offsets=cell_offsets, _node_weights=w)


def _drop_straight(poly: np.ndarray, eps: float) -> np.ndarray:
    """Remove corners of 180 deg (boundary points where a pruned link ended)."""
    prev = poly - np.roll(poly, 1, axis=0)
    nxt = np.roll(poly, -1, axis=0) - poly
    turn = (prev[:, 0] * nxt[:, 1] - prev[:, 1] * nxt[:, 0]) / np.maximum(
        np.hypot(*prev.T) * np.hypot(*nxt.T), 1e-300)
    return np.ascontiguousarray(poly[np.abs(turn) > 1e-12])


def cell_is_convex(cell: np.ndarray, tol: float = 1e-9) -> bool:
    """Whether a counter-clockwise polygon has no reflex corner."""
    prev = cell - np.roll(cell, 1, axis=0)
    nxt = np.roll(cell, -1, axis=0) - cell
    turn = (prev[:, 0] * nxt[:, 1] - prev[:, 1] * nxt[:, 0]) / (
        np.hypot(*prev.T) * np.hypot(*nxt.T))
    return bool(np.all(turn >= -tol))


# -- routes ---------------------------------------------------------------------------


def shortcut(world: PolygonWorld, path: np.ndarray) -> np.ndarray:
    """Shortest sub-polyline of ``path`` (same first and last point) whose segments are free.

    The paper's "improved Dijkstra": by the triangle inequality a free direct
    join of two route nodes is never longer than the route between them.
    """
    n = len(path)
    best = np.full(n, np.inf)
    prev = np.full(n, -1)
    best[0] = 0.0
    for j in range(1, n):
        for i in range(j):
            if not math.isfinite(best[i]):
                continue
            d = best[i] + math.hypot(*(path[j] - path[i]))
            if d < best[j] - 1e-12 and (j == i + 1 or world.segment_free(path[i], path[j])):
                best[j] = d
                prev[j] = i
    keep = [n - 1]
    while keep[-1] != 0:
        keep.append(int(prev[keep[-1]]))
    return path[keep[::-1]]


def crossed_links(graph: MaklinkGraph, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The links a free polyline crosses, in order, and where (parameter t in [0, 1]).

    Consecutive crossings lie on a common convex cell, so moving each crossing
    along its link (as the PSO does) keeps the path free. A path through an
    obstacle vertex crosses the fan of cells around it; those links are
    crossed at that vertex (t = 0 or 1).

    Raises:
        InputDataError: the path is not collision-free.
        RuntimeError: a crossing could not be resolved (numerically ambiguous contact).
    """
    path = np.asarray(path, dtype=float)
    if not graph.world.path_free(path):
        raise InputDataError("crossed_links: the path enters an obstacle or leaves the bounds")
    eps = graph.world.eps
    links = graph.links
    events: list[float] = []  # path parameter of every contact with a link
    for i in range(len(path) - 1):
        p, q = path[i], path[i + 1]
        events.append(float(i))
        for k in range(len(links)):
            a, b = links[k, :2], links[k, 2:]
            if gk.segment_contact(p[0], p[1], q[0], q[1], a[0], a[1], b[0], b[1],
                                  eps) == gk.CONTACT_NONE:
                continue
            for s in _contact_params(p, q, a, b, eps):
                events.append(i + s)
    events.append(float(len(path) - 1))
    events = sorted(set(round(e, 12) for e in events))

    def at(s: float) -> np.ndarray:
        i = min(int(math.floor(s)), len(path) - 2)
        return path[i] + (s - i) * (path[i + 1] - path[i])

    seq: list[int] = []
    where: list[float] = []
    current = -1
    for s0, s1 in zip(events[:-1], events[1:], strict=True):
        cands = graph.cells_containing(at(0.5 * (s0 + s1)))
        if not cands or current in cands:
            continue
        if current < 0:
            current = cands[0]
            continue
        x = at(s0)
        chain = _cell_chain(graph, current, set(cands), x, eps)
        for k in chain:
            a, b = links[k, :2], links[k, 2:]
            d = b - a
            seq.append(k)
            where.append(float(np.clip(np.dot(x - a, d) / np.dot(d, d), 0.0, 1.0)))
        current = _last_cell(graph, current, chain)
    return np.array(seq, dtype=np.int64), np.array(where)


def _contact_params(p, q, a, b, eps) -> list[float]:
    """Parameters along pq of its contact with segment ab (1 point, or 2 if collinear)."""
    d = q - p
    e = b - a
    den = d[0] * e[1] - d[1] * e[0]
    dd = float(np.dot(d, d))
    if dd == 0.0:
        return [0.0]
    if abs(den) > eps * math.sqrt(dd) * math.hypot(*e):
        s = ((a[0] - p[0]) * e[1] - (a[1] - p[1]) * e[0]) / den
        return [min(max(s, 0.0), 1.0)]
    return [min(max(float(np.dot(x - p, d)) / dd, 0.0), 1.0) for x in (a, b)]


def _cell_chain(graph: MaklinkGraph, start_cell: int, targets: set[int], x: np.ndarray,
                eps: float) -> list[int]:
    """Fewest links through x (within 1000 eps) leading from start_cell into targets."""
    links = graph.links
    near = {k for k in range(graph.n_links)
            if gk.point_segment_distance(x[0], x[1], *links[k]) <= 1e3 * eps}
    parent: dict[int, tuple[int, int]] = {start_cell: (-1, -1)}
    queue = deque([start_cell])
    while queue:
        c = queue.popleft()
        if c in targets:
            chain = []
            while parent[c][0] >= 0:
                chain.append(parent[c][1])
                c = parent[c][0]
            return chain[::-1]
        for k in graph.cell_links[c]:
            if k not in near:
                continue
            for nxt in graph.link_cells[k]:
                if nxt >= 0 and nxt not in parent:
                    parent[int(nxt)] = (c, int(k))
                    queue.append(int(nxt))
    raise RuntimeError(f"no link near {x.tolist()} leads out of cell {start_cell}: "
                       "the path is not free or touches a link ambiguously")


def _last_cell(graph: MaklinkGraph, current: int, chain: list[int]) -> int:
    for k in chain:
        a, b = graph.link_cells[k]
        current = int(b if a == current else a)
    return current


def points_on_links(graph: MaklinkGraph, ids: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(k, 2) the points at parameters ``t`` along links ``ids``."""
    links = graph.links[ids]
    return links[:, :2] + t[:, None] * (links[:, 2:] - links[:, :2])


@register("polygon", "dijkstra",
          description="Dijkstra over the MAKLINK free-link graph (link midpoints)")
def dijkstra(world: PolygonWorld, start: Any, goal: Any, *, params: Any = None,
             seed: int | None = None, stop: Any = None) -> PlanResult:
    """Dijkstra's shortest route over the MAKLINK graph (the paper's Fig. 3).

    The path runs from start through the midpoints of the crossed free links
    to goal. Deterministic: ``params``, ``seed`` and ``stop`` must be None.
    ``info`` holds ``links`` (crossed link ids), ``graph_links`` and ``graph_cells``.

    Raises:
        ParameterError: params, seed or stop given.
        InputDataError, UnreachableError: start or goal malformed, outside the
            bounds, inside an obstacle or on its boundary.
    """
    check_deterministic("dijkstra", params, None, seed, stop)
    return _plan(world, start, goal, improve=False)


@register("polygon", "improved",
          description="improved Dijkstra: the MAKLINK route shortened by the triangle "
                      "inequality")
def improved_dijkstra(world: PolygonWorld, start: Any, goal: Any, *, params: Any = None,
                      seed: int | None = None, stop: Any = None) -> PlanResult:
    """The Dijkstra route shortened by the triangle inequality (:func:`shortcut`).

    Deterministic: ``params``, ``seed`` and ``stop`` must be None. ``info``
    holds ``links``, ``graph_links``, ``graph_cells`` and ``dijkstra_length``.

    Raises:
        ParameterError: params, seed or stop given.
        InputDataError, UnreachableError: start or goal malformed, outside the
            bounds, inside an obstacle or on its boundary.
    """
    check_deterministic("improved", params, None, seed, stop)
    return _plan(world, start, goal, improve=True)


def _plan(world: PolygonWorld, start: Any, goal: Any, *, improve: bool) -> PlanResult:
    t0 = time.perf_counter()
    s = world.check_point("start", start)
    g = world.check_point("goal", goal)
    name = "improved" if improve else "dijkstra"
    if same_point(world.eps, s, g):
        return PlanResult(path=np.array([s, g]), success=True, planner=name,
                          message="ok (start equals goal)", runtime_s=time.perf_counter() - t0,
                          info={"links": [], **({"dijkstra_length": 0.0} if improve else {})})
    graph = graph_for(world)
    length, ids = graph.route(s, g)
    info: dict[str, Any] = {"graph_links": graph.n_links, "graph_cells": len(graph.cells)}
    if not math.isfinite(length):
        return PlanResult(path=np.zeros((0, 2)), success=False, planner=name,
                          outcome=Outcome.NO_PATH,
                          message="no collision-free path: start and goal are separated by "
                                  "obstacles", runtime_s=time.perf_counter() - t0, info=info)
    path = np.vstack([s, graph.midpoints[ids].reshape(-1, 2), g])
    info["links"] = [int(k) for k in ids]
    if improve:
        info["dijkstra_length"] = length
        path = shortcut(world, path)
    return PlanResult(path=path, success=True, message="ok", planner=name,
                      runtime_s=time.perf_counter() - t0, info=info)

"""Exact shortest paths among polygon obstacles over the visibility graph.

A shortest collision-free path between two points in a polygonal world is a
polyline whose inner corners are obstacle vertices - convex ones, where the
path wraps around the obstacle (Lozano-Perez & Wesley 1979). So the shortest
path over the graph of mutually visible convex vertices, plus start and goal,
is the true optimum; :mod:`.maklink` and :mod:`.pso` can only approach it
from above.

Vertices where an obstacle touches the outer boundary are left out: the
free angle there is below 180 deg on both sides, so no shortest path bends at
them, and a path bending there would slip through the zero-width gap between
obstacle and wall (the other planners see that gap as closed too).

The vertex-to-vertex part of the graph depends on the world alone and is kept
in a small per-world cache in this module, so :func:`shortest_path_length`
(called many times by the reactive-navigation benchmark) only tests the ~2n
segments from start and goal.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError
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
class VisibilityParams:
    """Options of the visibility-graph planner.

    Attributes:
        convex_only: use only convex obstacle vertices as graph nodes (a
            shortest path never bends at a reflex vertex, so the answer is the
            same and the graph smaller). False keeps every vertex (except
            those touching the outer boundary, which are never usable).
    """

    convex_only: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.convex_only, bool):
            raise ParameterError(
                f"VisibilityParams.convex_only must be True or False, got {self.convex_only!r}")


@dataclass(frozen=True)
class VisibilityGraph:
    """Obstacle vertices and their mutual visibility (start and goal not included).

    Attributes:
        points: (m, 2) the graph's vertices.
        vertex_index: (m,) their row in ``world.vertices``.
        weights: (m, m) Euclidean length of each visible pair, inf otherwise.
    """

    points: np.ndarray
    vertex_index: np.ndarray
    weights: np.ndarray

    @property
    def n_edges(self) -> int:
        return int(np.count_nonzero(np.isfinite(self.weights))) // 2


def convex_vertex_mask(world: PolygonWorld) -> np.ndarray:
    """Bool mask over ``world.vertices``: True where the obstacle's interior angle < 180 deg."""
    masks = []
    for poly in world.obstacles:
        prev = poly - np.roll(poly, 1, axis=0)
        nxt = np.roll(poly, -1, axis=0) - poly
        turn = prev[:, 0] * nxt[:, 1] - prev[:, 1] * nxt[:, 0]
        masks.append(turn > world.eps * np.hypot(*prev.T))  # obstacles are counter-clockwise
    return np.concatenate(masks) if masks else np.zeros(0, dtype=bool)


def build_graph(world: PolygonWorld, params: VisibilityParams | None = None) -> VisibilityGraph:
    """The vertex-to-vertex visibility graph of ``world`` (computed, not cached)."""
    params = params or VisibilityParams()
    usable = ~world.on_bounds
    if params.convex_only:
        usable &= convex_vertex_mask(world)
    idx = np.flatnonzero(usable)
    pts = np.ascontiguousarray(world.vertices[idx])
    verts, offsets, boxes, bounds, eps = world.kernel_arrays()
    vis = gk.visibility_matrix(pts, verts, offsets, boxes, bounds, eps)
    diff = pts[:, None, :] - pts[None, :, :]
    weights = np.where(vis, np.hypot(diff[..., 0], diff[..., 1]), np.inf)
    return VisibilityGraph(points=pts, vertex_index=idx, weights=weights)


def graph_for(world: PolygonWorld, params: VisibilityParams | None = None) -> VisibilityGraph:
    """:func:`build_graph`, cached per world and params (a small LRU in this module)."""
    return _cached_graph(world, params or VisibilityParams())


@world_cache
def _cached_graph(world: PolygonWorld, params: VisibilityParams) -> VisibilityGraph:
    return build_graph(world, params)


def _solve(world: PolygonWorld, graph: VisibilityGraph, start: np.ndarray,
           goal: np.ndarray) -> tuple[float, list[int]]:
    """Length and node sequence (indices into graph.points, -1 start, -2 goal)."""
    if same_point(world.eps, start, goal):
        return 0.0, [-1, -2]
    if world.segment_free(start, goal):
        return float(math.hypot(*(goal - start))), [-1, -2]
    m = len(graph.points)
    verts, offsets, boxes, bounds, eps = world.kernel_arrays()
    w = np.full((m + 2, m + 2), np.inf)
    w[:m, :m] = graph.weights
    for row, p in ((m, start), (m + 1, goal)):
        vis = gk.visible_from(p[0], p[1], graph.points, verts, offsets, boxes, bounds, eps)
        d = np.where(vis, np.hypot(*(graph.points - p).T), np.inf)
        w[row, :m] = d
        w[:m, row] = d
    length, nodes = shortest_route(w, m, m + 1)
    if not nodes:
        return math.inf, []
    return length, [-1] + nodes[1:-1] + [-2]


def shortest_path_length(world: PolygonWorld, start: Any, goal: Any) -> float:
    """Length of the shortest collision-free path (inf when none exists).

    Raises:
        InputDataError, UnreachableError: start or goal malformed, outside the
            bounds or inside an obstacle.
    """
    s = world.check_point("start", start)
    g = world.check_point("goal", goal)
    return _solve(world, graph_for(world), s, g)[0]


@register("polygon", "visibility",
          description="exact shortest path over the visibility graph of the obstacle vertices")
def plan(world: PolygonWorld, start: Any, goal: Any, *, params: VisibilityParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Exact shortest path from ``start`` to ``goal`` over the visibility graph.

    Deterministic: ``seed`` and ``stop`` must be None. ``info`` holds
    ``graph_nodes``, ``graph_edges`` and ``vertices`` (rows of
    ``world.vertices`` the path bends at).

    Raises:
        ParameterError: a seed or stopping criteria given, or params not a
            :class:`VisibilityParams`.
        InputDataError, UnreachableError: start or goal malformed, outside the
            bounds or inside an obstacle.
    """
    check_deterministic("visibility", params, VisibilityParams, seed, stop)
    params = params or VisibilityParams()
    t0 = time.perf_counter()
    s = world.check_point("start", start)
    g = world.check_point("goal", goal)
    graph = graph_for(world, params)
    length, nodes = _solve(world, graph, s, g)
    runtime = time.perf_counter() - t0
    info: dict[str, Any] = {"graph_nodes": len(graph.points) + 2,
                            "graph_edges": graph.n_edges}
    if not nodes:
        return PlanResult(path=np.zeros((0, 2)), success=False, planner="visibility",
                          outcome=Outcome.NO_PATH,
                          message="no collision-free path: start and goal are separated by "
                                  "obstacles", runtime_s=runtime, info=info)
    inner = nodes[1:-1]
    path = np.vstack([s, *(graph.points[i] for i in inner), g])
    info["vertices"] = [int(graph.vertex_index[i]) for i in inner]
    return PlanResult(path=path, success=True, message="ok", planner="visibility",
                      runtime_s=runtime, info=info)

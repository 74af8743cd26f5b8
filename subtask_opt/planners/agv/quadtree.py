"""Quadtree decomposition of an occupancy grid and a planner over its free leaves.

The grid is embedded in a square of side ``2**k`` (the area outside the grid
counts as obstacle) and split recursively: a node whose cells are all free is
*white*, all blocked *black*, otherwise *grey* and split into four children,
down to ``min_size`` cells (paper: the finest resolution, one cell). A grey
node at ``min_size`` stays a grey leaf and is not routable.

The tree answers the AGV's collision question for a segment ahead
(:meth:`Quadtree.segment_free`): descend from the root into the nodes whose
closed square the segment meets; white nodes are cleared whole, a black leaf
(or a grey leaf at ``min_size``) blocks. In open space this touches a handful
of large leaves instead of every cell under the segment.

The planner (:func:`plan`, registered as the AGV planner ``"quadtree"``)
searches the graph of white leaves that share an
edge (Dijkstra; a step goes leaf centre -> midpoint of the shared edge -> next
centre, a polyline that stays inside the two leaves), then straightens the
polyline by keeping the farthest waypoint in line of sight. Two leaves that
only touch at a corner are not neighbours: like the grid planners, the AGV does
not squeeze between diagonal obstacles, so a path exists in the quadtree
exactly when one exists on the 8-connected grid.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.geometry import polyline_length
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.base import check_seed, register
from subtask_opt.planners.grid.world import GridWorld

WHITE = 0
BLACK = 1
GREY = 2


@dataclass(frozen=True)
class QuadtreeParams:
    """Options of the decomposition.

    Attributes:
        min_size: side (cells) of the smallest node; a power of two >= 1.
        straighten: shorten the leaf path by line-of-sight shortcuts.
    """

    min_size: int = 1
    straighten: bool = True

    def __post_init__(self) -> None:
        require_int("QuadtreeParams", "min_size", self.min_size, 1)
        if self.min_size & (self.min_size - 1):
            raise ParameterError(
                f"QuadtreeParams.min_size must be a power of two, got {self.min_size!r}")
        if not isinstance(self.straighten, bool):
            raise ParameterError(
                f"QuadtreeParams.straighten must be a bool, got {self.straighten!r}")


@dataclass(frozen=True)
class Quadtree:
    """A quadtree over a grid.

    Attributes:
        shape: (height, width) of the grid.
        nodes: int array (n, 5) of every node: x0, y0, size (cells), colour
            (:data:`WHITE`, :data:`BLACK`, :data:`GREY`), depth (root 0).
        leaf: bool array (n,), which nodes are leaves.
        label: int array ``[y, x]``: index into ``nodes`` of the leaf holding
            each grid cell.
        children: int array (n, 4): indices of the four quarters of a split
            node, -1 for a leaf or a quarter wholly outside the grid.
    """

    shape: tuple[int, int]
    nodes: np.ndarray
    leaf: np.ndarray
    label: np.ndarray
    children: np.ndarray

    def segment_free(self, a: Any, b: Any, clearance: float = 0.0) -> bool:
        """Whether the segment a-b (points (x, y), any reals) touches only
        white leaves and stays off the grid's border line; with a positive
        ``clearance`` (cells), whether it keeps more than that distance from
        every blocked cell and from the border line."""
        h, w = self.shape
        return bool(K.tree_segment_free(self.nodes, self.children, w, h, float(a[0]),
                                        float(a[1]), float(b[0]), float(b[1]),
                                        float(clearance)))

    def leaf_at(self, xy: Any) -> int:
        """Index of the leaf holding the cell nearest to point ``xy``."""
        h, w = self.shape
        x = min(max(int(round(float(xy[0]))), 0), w - 1)
        y = min(max(int(round(float(xy[1]))), 0), h - 1)
        return int(self.label[y, x])

    @property
    def leaves(self) -> np.ndarray:
        """Rows of ``nodes`` that are leaves."""
        return self.nodes[self.leaf]

    def count(self, colour: int) -> int:
        """Number of leaves of a colour."""
        return int(np.count_nonzero(self.leaf & (self.nodes[:, 3] == colour)))

    def depth(self) -> int:
        return int(self.nodes[:, 4].max())


def decompose(occupancy: np.ndarray, params: QuadtreeParams | None = None) -> Quadtree:
    """Quadtree of a bool grid ``[y, x]`` (``True`` = blocked)."""
    params = QuadtreeParams() if params is None else params
    occ = np.asarray(occupancy, dtype=bool)
    h, w = occ.shape
    side = 1
    while side < max(h, w):
        side *= 2
    side = max(side, params.min_size)
    padded = np.ones((side, side), dtype=bool)
    padded[:h, :w] = occ
    # summed-area table: blocked cells in any square in O(1)
    sat = np.zeros((side + 1, side + 1), dtype=np.int64)
    sat[1:, 1:] = padded.cumsum(0).cumsum(1)
    nodes: list[tuple[int, int, int, int, int]] = []
    leaf: list[bool] = []
    parents: list[tuple[int, int]] = []
    label = np.full((h, w), -1, dtype=np.int64)
    stack = [(0, 0, side, 0, -1, 0)]
    while stack:
        x0, y0, size, depth, parent, quarter = stack.pop()
        if x0 >= w or y0 >= h:
            continue  # wholly outside the grid: not part of the map
        n_blocked = sat[y0 + size, x0 + size] - sat[y0, x0 + size] - sat[y0 + size, x0] \
            + sat[y0, x0]
        if n_blocked == 0:
            colour = WHITE
        elif n_blocked == size * size:
            colour = BLACK
        else:
            colour = GREY
        is_leaf = colour != GREY or size <= params.min_size
        idx = len(nodes)
        nodes.append((x0, y0, size, colour, depth))
        leaf.append(is_leaf)
        parents.append((parent, quarter))
        if is_leaf:
            label[y0:y0 + size, x0:x0 + size] = idx
        else:
            half = size // 2
            for q, (dy, dx) in enumerate(((half, half), (half, 0), (0, half), (0, 0))):
                stack.append((x0 + dx, y0 + dy, half, depth + 1, idx, q))
    children = np.full((len(nodes), 4), -1, dtype=np.int64)
    for idx, (parent, quarter) in enumerate(parents):
        if parent >= 0:
            children[parent, quarter] = idx
    return Quadtree((h, w), np.array(nodes, dtype=np.int64), np.array(leaf), label, children)


def free_adjacency(tree: Quadtree) -> dict[int, dict[int, tuple[float, float]]]:
    """White leaves sharing an edge: ``adj[a][b]`` = midpoint of the shared edge."""
    label = tree.label
    white = tree.leaf & (tree.nodes[:, 3] == WHITE)
    adj: dict[int, dict[int, tuple[float, float]]] = {}
    for a_lab, b_lab in ((label[:, :-1], label[:, 1:]), (label[:-1, :], label[1:, :])):
        diff = (a_lab != b_lab) & white[a_lab] & white[b_lab]
        for a, b in set(zip(a_lab[diff].tolist(), b_lab[diff].tolist(), strict=True)):
            mid = _shared_midpoint(tree.nodes[a], tree.nodes[b])
            adj.setdefault(a, {})[b] = mid
            adj.setdefault(b, {})[a] = mid
    return adj


def _shared_midpoint(na: np.ndarray, nb: np.ndarray) -> tuple[float, float]:
    ax, ay, asz = int(na[0]), int(na[1]), int(na[2])
    bx, by, bsz = int(nb[0]), int(nb[1]), int(nb[2])
    if ax + asz == bx or bx + bsz == ax:  # vertical shared edge
        x = (bx if ax + asz == bx else ax) - 0.5
        lo, hi = max(ay, by), min(ay + asz, by + bsz)
        return x, (lo + hi) / 2.0 - 0.5
    y = (by if ay + asz == by else ay) - 0.5
    lo, hi = max(ax, bx), min(ax + asz, bx + bsz)
    return (lo + hi) / 2.0 - 0.5, y


def _centre(node: np.ndarray) -> tuple[float, float]:
    half = (int(node[2]) - 1) / 2.0
    return int(node[0]) + half, int(node[1]) + half


def straighten(tree: Quadtree, path: np.ndarray) -> np.ndarray:
    """Greedy line-of-sight shortcutting: from each kept point jump to the
    farthest later point whose segment touches only white leaves."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] <= 2:
        return path.copy()
    out = [path[0]]
    i = 0
    n = path.shape[0]
    while i < n - 1:
        j = n - 1
        while j > i + 1 and not tree.segment_free(path[i], path[j]):
            j -= 1
        out.append(path[j])
        i = j
    return np.array(out)


@register("agv", "quadtree", description="shortest path over the free leaves of a quadtree "
                                         "of the map, straightened by line of sight")
def plan(world: GridWorld, start: Any, goal: Any, *, params: QuadtreeParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Plan over the white leaves of the quadtree of ``world``.

    ``seed`` is accepted for the common planner interface (the search is
    deterministic) and ``stop`` must be None (not iterative). ``info`` holds
    ``nodes`` (white leaves, the graph size), ``leaves`` (all leaves),
    ``leaf_path`` (leaves visited), ``raw_length`` (before straightening).

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
        ParameterError: bad ``params``, ``seed`` or a ``stop``.
    """
    check_seed(seed)
    if stop is not None:
        raise ParameterError(f"the quadtree planner is not iterative: stop must be None, "
                             f"got {stop!r}")
    if not isinstance(world, GridWorld):
        raise ParameterError(f"quadtree.plan needs a GridWorld, got {type(world).__name__}")
    params = QuadtreeParams() if params is None else params
    if not isinstance(params, QuadtreeParams):
        raise ParameterError(f"quadtree.plan params must be QuadtreeParams, got {params!r}")
    sx, sy = world.check_cell("start", start)
    gx, gy = world.check_cell("goal", goal)
    t0 = time.perf_counter()
    tree = decompose(world.occupancy, params)
    adj = free_adjacency(tree)
    src, dst = int(tree.label[sy, sx]), int(tree.label[gy, gx])
    centres = {i: _centre(tree.nodes[i]) for i in adj}
    centres.setdefault(src, _centre(tree.nodes[src]))
    centres.setdefault(dst, _centre(tree.nodes[dst]))
    dist = {src: 0.0}
    prev: dict[int, int] = {}
    heap = [(0.0, src)]
    while heap:
        d, a = heapq.heappop(heap)
        if a == dst:
            break
        if d > dist.get(a, math.inf):
            continue
        ca = centres[a]
        for b, mid in adj.get(a, {}).items():
            cb = centres[b]
            nd = d + math.dist(ca, mid) + math.dist(mid, cb)
            if nd < dist.get(b, math.inf):
                dist[b] = nd
                prev[b] = a
                heapq.heappush(heap, (nd, b))
    n_white = tree.count(WHITE)
    info: dict[str, Any] = {"nodes": n_white, "leaves": int(tree.leaf.sum())}
    if dst not in dist:
        return PlanResult(np.zeros((0, 2)), False,
                          f"no path: goal {(gx, gy)} is not reachable from start {(sx, sy)}",
                          "quadtree", time.perf_counter() - t0, info=info,
                          outcome=Outcome.NO_PATH)
    chain = [dst]
    while chain[-1] != src:
        chain.append(prev[chain[-1]])
    chain.reverse()
    pts: list[tuple[float, float]] = [(float(sx), float(sy)), centres[src]]
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        pts.append(adj[a][b])
        pts.append(centres[b])
    pts.append((float(gx), float(gy)))
    raw = _dedupe(np.array(pts, dtype=float))
    path = straighten(tree, raw) if params.straighten else raw
    info.update(leaf_path=[int(c) for c in chain], raw_length=polyline_length(raw))
    return PlanResult(path, True, "ok", "quadtree", time.perf_counter() - t0, info=info,
                      outcome=Outcome.SUCCESS)


def _dedupe(path: np.ndarray) -> np.ndarray:
    keep = np.ones(path.shape[0], dtype=bool)
    keep[1:] = np.any(np.diff(path, axis=0) != 0, axis=1)
    return path[keep]


def compare_with_grid(world: GridWorld, start: Any, goal: Any, *,
                      params: QuadtreeParams | None = None, repeats: int = 5) -> dict[str, Any]:
    """Quadtree planner versus the 8-connected (octile) distance transform on
    the same map: graph nodes, best-of-``repeats`` time (after a warm-up), path length.
    """
    from subtask_opt.planners.grid.distance_transform import DTParams
    from subtask_opt.planners.grid.distance_transform import plan as grid_plan

    require_int("compare_with_grid", "repeats", repeats, 1)
    rows = {}
    for name, fn in (("quadtree", lambda: plan(world, start, goal, params=params)),
                     ("grid", lambda: grid_plan(world, start, goal,
                                                params=DTParams("octile")))):
        fn()  # warm-up (JIT)
        best = math.inf
        for _ in range(repeats):
            res = fn()
            best = min(best, res.runtime_s)
        nodes = res.info["nodes"] if name == "quadtree" else int(np.count_nonzero(world.free))
        rows[name] = {"success": res.success, "nodes": nodes, "time_s": best,
                      "length": res.length if res.success else None,
                      "waypoints": int(res.path.shape[0])}
    return rows

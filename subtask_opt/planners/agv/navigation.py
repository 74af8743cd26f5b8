"""Corners, check points, navigation and route sections of the AGV (seed 004).

Everything here works on the AGV's *routing map*: the cells whose 2-bit
local-map state is ``00`` (free; :func:`routing_map`). Mixed (``01``),
approachable (``10``) and inaccessible (``11``) cells are all blocked for
routing, as §3.2.2 of the paper says ("only cells with (b1 b2) = 00 can be
chosen for a route; the map stores b1 OR b2"). Line of sight is asked of the
quadtree of that map (:meth:`Quadtree.segment_free`).

**Corner detection (rules 2-1 ... 2-7).** As printed, rule 2-2 sends every
free cell (``global-map[row][column] = 0``) to rule 2-7, and each of rules
2-3 ... 2-6 then *also* requires ``global-map[row][column] = '0'`` - a
condition rule 2-2 has just excluded. So rules 2-3 ... 2-6 can never fire, the
ELSE branch marks every obstacle cell as an edge, and the rules as printed
detect no corner at all (every obstacle cell is one). The reading used here:
in rules 2-3 ... 2-6 the ``'0'`` tests are tests for ``'1'`` (obstacle), and
each rule names one line of three cells through ``[row][column]``: vertical
(2-3, printed with ``[row-1][column-1]``, read as ``[row-1][column]`` like the
other three rules, which are all symmetric about the centre), horizontal
(2-4), and the two diagonals (2-5, 2-6). An obstacle cell lying inside such a
line of obstacle cells is not an edge; one that lies inside none of the four
lines is an edge (a convex corner or the end of a wall). Rule 2-1 (skip the
search when the way ahead is clear) and rule 2-7 (the raster scan) are the
loop around it. The AGV never drives to the corner cell itself: its *near
points* are the free diagonal neighbours outside the corner whose two side
cells are free too; the corner's outer vertex (between the corner cell and
its near point) is the landmark used as a check point (§3.3.2).

**Navigation (rules 3-1 ... 3-4).** From the current point: if the goal is in
line of sight go straight to it (3-1); otherwise give each visible near point
the value ``distance + cost-to-go + turn_weight * |turn angle|`` and head for
the best one (the paper's "nearest corner with the smallest angle"; the
cost-to-go, a Dijkstra over the quadtree's free leaves, is what makes the
choice complete - the bare greedy rule can cycle) and repeat from it (3-4).
Only near points with a smaller cost-to-go than the current point count, so
the route is finite; when no near point qualifies the AGV moves one leaf
along the quadtree path (square across the middle of the shared edge). Rules
3-2 and 3-3 (keep or reduce the acceleration) belong to the simulation's
t-second check. Straight legs keep a clearance from walls (``navigate``'s
``clearance``), a margin for the AGV's position error.

**Path-planning rules 1-5 (§3.1) as the route-segmentation step**
(:func:`segment_route`):

* Rule 1 (recognise the free configuration space Cs): Cs is the set of ``00``
  cells of the local map (:func:`routing_map`).
* Rule 2 (partition Cs into C1 ... Cn): the white leaves of the quadtree of
  the routing map. Each leaf is a free square, so any segment inside one leaf
  is collision-free.
* Rule 3 (split the route at crossings where the AGV turns and where the
  state of the road changes): a section ends at every sub-goal (a turn) and
  wherever the route passes from a leaf of one road class to a leaf of the
  other. The road class of a leaf is *open* when its side is at least
  ``open_leaf`` cells and *narrow* otherwise (small leaves are where free
  space is pinched by obstacles).
* Rule 4 (the number of sections of a route follows the kinds of road in it):
  every maximal run of same-class leaves along a leg is one section, so a leg
  through open - narrow - open space has three.
* Rule 5 (a road the AGV already knows is not split): in a grid world the
  global map is known beforehand, so "known" is read as *proven free by the
  partition*: a leg that lies inside one white leaf (a convex free square)
  is one ``"known"`` section and needs no further split or check.

When the AGV starts a leg, the simulation checks it with the quadtree (is it
still free in the AGV's current map, which holds the obstacles it has taken as
static; and which seen obstacles stand in the leaves of its sections) - the
paper's "check the next section for collisions ahead with the quadtree"
(§4.2.2, conclusion). A leg found blocked triggers a re-plan.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import NoPathError, ParameterError
from subtask_opt.planners.agv.certainty_grid import local_map_states, routable
from subtask_opt.planners.agv.quadtree import (
    WHITE,
    Quadtree,
    _centre,
    _shared_midpoint,
    decompose,
    free_adjacency,
)

__all__ = ["Section", "detect_corners", "landmarks", "navigate", "near_points",
           "room_corners", "routing_map", "segment_route"]


def routing_map(states: np.ndarray) -> np.ndarray:
    """Bool ``[y, x]``: ``True`` where the AGV may not route (``b1 OR b2 != 0``)."""
    return routable(states) != 0


def states_of_occupancy(occupancy: np.ndarray) -> np.ndarray:
    """2-bit states of a plain occupancy grid (no mixed cells: a cell is
    either empty or an obstacle)."""
    occ = np.asarray(occupancy, dtype=bool)
    return local_map_states(occ.astype(np.int64), 0)


def detect_corners(occupancy: np.ndarray) -> np.ndarray:
    """Obstacle cells that are edges by rules 2-2 ... 2-6, read as in the
    module docstring (bool ``[y, x]``).

    A blocked cell is *not* an edge when, along one of the four lines through
    it, both opposite neighbours are blocked too; the map border counts as
    free so that obstacles touching it keep their corners.
    """
    occ = np.asarray(occupancy, dtype=bool)
    p = np.pad(occ, 1, constant_values=False)
    h, w = occ.shape

    def nb(dy: int, dx: int) -> np.ndarray:
        return p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]

    inline = ((nb(-1, 0) & nb(1, 0)) | (nb(0, -1) & nb(0, 1))
              | (nb(-1, -1) & nb(1, 1)) | (nb(-1, 1) & nb(1, -1)))
    return occ & ~inline


def _corner_pairs(occ: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(corner cells (k, 2), their near points (k, 2)) as (x, y)."""
    h, w = occ.shape
    free = np.pad(~occ, 1, constant_values=False)
    cy, cx = np.nonzero(corners)
    cs, ns = [], []
    for dy in (-1, 1):
        for dx in (-1, 1):
            ok = free[1 + cy + dy, 1 + cx + dx] & free[1 + cy + dy, 1 + cx] \
                & free[1 + cy, 1 + cx + dx]
            cs.append(np.column_stack([cx[ok], cy[ok]]))
            ns.append(np.column_stack([cx[ok] + dx, cy[ok] + dy]))
    return (np.vstack(cs).astype(float).reshape(-1, 2),
            np.vstack(ns).astype(float).reshape(-1, 2))


def near_points(occupancy: np.ndarray, corners: np.ndarray | None = None) -> np.ndarray:
    """Sub-goal points (k, 2) as cell centres (x, y), sorted and unique: the
    free diagonal neighbours of edge cells whose two side cells are free."""
    occ = np.asarray(occupancy, dtype=bool)
    corners = detect_corners(occ) if corners is None else corners
    _, near = _corner_pairs(occ, corners)
    if len(near) == 0:
        return near
    return np.unique(near, axis=0)


def landmarks(occupancy: np.ndarray) -> np.ndarray:
    """Check points (k, 2): the outer vertices of the corners, i.e. the
    points half-way between a corner cell and its near point."""
    occ = np.asarray(occupancy, dtype=bool)
    c, n = _corner_pairs(occ, detect_corners(occ))
    if len(c) == 0:
        return c
    return np.unique((c + n) / 2.0, axis=0)


def room_corners(occupancy: np.ndarray) -> np.ndarray:
    """Check points (k, 2) where the map's border walls meet: the outer
    vertex of each of the four corner cells that is free (the area outside
    the map is wall, so these are corners of the room the AGV sees)."""
    occ = np.asarray(occupancy, dtype=bool)
    h, w = occ.shape
    out = [(x + 0.5 * sx, y + 0.5 * sy) for x, y, sx, sy in
           ((0, 0, -1, -1), (w - 1, 0, 1, -1), (0, h - 1, -1, 1), (w - 1, h - 1, 1, 1))
           if not occ[y, x]]
    return np.unique(np.array(out, dtype=float).reshape(-1, 2), axis=0)


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    nu, nv = math.hypot(u[0], u[1]), math.hypot(v[0], v[1])
    if nu == 0 or nv == 0:
        return 0.0
    return math.acos(max(-1.0, min(1.0, float(u @ v) / (nu * nv))))


def leaf_costs(tree: Quadtree, target: Any) -> tuple[dict[int, float], dict[int, int]]:
    """Cost-to-go over the quadtree: Dijkstra from the white leaf holding
    ``target`` over white leaves sharing an edge (a step: leaf centre ->
    midpoint of the shared edge -> next centre). Returns (cost of each
    reachable leaf, next leaf towards the target)."""
    adj = free_adjacency(tree)
    tgt = np.asarray(target, dtype=float)
    root = tree.leaf_at(tgt)
    cost = {root: math.dist(_centre(tree.nodes[root]), tgt)}
    nxt: dict[int, int] = {}
    heap = [(cost[root], root)]
    while heap:
        d, a = heapq.heappop(heap)
        if d > cost.get(a, math.inf):
            continue
        ca = _centre(tree.nodes[a])
        for b, mid in adj.get(a, {}).items():
            nd = d + math.dist(ca, mid) + math.dist(mid, _centre(tree.nodes[b]))
            if nd < cost.get(b, math.inf):
                cost[b] = nd
                nxt[b] = a
                heapq.heappush(heap, (nd, b))
    return cost, nxt


def _point_cost(tree: Quadtree, cost: dict[int, float], p: np.ndarray) -> float:
    leaf = tree.leaf_at(p)
    if int(tree.nodes[leaf, 3]) != WHITE or leaf not in cost:
        return math.inf
    return cost[leaf] + math.dist(_centre(tree.nodes[leaf]), (float(p[0]), float(p[1])))


def navigate(tree: Quadtree, occupancy: np.ndarray, start: Any, target: Any, *,
             turn_weight: float = 1.0, points: np.ndarray | None = None,
             clearance: float = 0.0) -> np.ndarray:
    """Sub-goals (k, 2) from ``start`` to ``target`` by rules 3-1 ... 3-4.

    ``tree`` is the quadtree of ``occupancy`` (the routing map); the
    cost-to-go of a point is its leaf's Dijkstra cost over the quadtree
    (:func:`leaf_costs`) plus the distance to the leaf's centre. ``start``
    may be any point of a free leaf; ``target`` is a free cell centre. The
    last row is ``target``. ``points`` overrides the near points.
    ``clearance`` (cells): a straight leg (rules 3-1, 3-4) must keep more than
    this distance from blocked cells and the map border
    (:meth:`Quadtree.segment_free`). The one-leaf steps of the fallback are
    not tested (so the search stays complete): they cross into the next leaf
    square to the shared edge, between points half a cell inside either leaf,
    which keeps half a cell from every blocked cell when the step starts half
    a cell inside its leaf (cell centres do).

    Raises:
        NoPathError: the target cannot be reached on this map.
    """
    occ = np.asarray(occupancy, dtype=bool)
    h, w = occ.shape
    pos = np.array(start, dtype=float)
    tgt = np.array(target, dtype=float)
    tcell = (int(round(tgt[0])), int(round(tgt[1])))
    if not (0 <= tcell[0] < w and 0 <= tcell[1] < h) or occ[tcell[1], tcell[0]]:
        raise NoPathError(f"target {tcell} is not a free cell of the routing map")
    cost, toward = leaf_costs(tree, tgt)
    pts = near_points(occ) if points is None else np.asarray(points, dtype=float)
    pcost = np.array([_point_cost(tree, cost, p) for p in pts]) if len(pts) else np.zeros(0)
    heading = tgt - pos
    out: list[np.ndarray] = []
    for _ in range(len(pts) + 2 * len(tree.nodes) + 2):
        if tree.segment_free(pos, tgt, clearance):  # rule 3-1
            out.append(tgt)
            return np.array(out)
        here = _point_cost(tree, cost, pos)
        if not math.isfinite(here):
            raise NoPathError(f"no route from ({pos[0]:.2f}, {pos[1]:.2f}) to target {tcell}")
        best, best_val = None, math.inf
        for i in np.flatnonzero(pcost < here - 1e-9):
            c = pts[i]
            if not tree.segment_free(pos, c, clearance):
                continue
            d = c - pos
            val = math.hypot(d[0], d[1]) + pcost[i] + turn_weight * _angle(heading, d)
            if val < best_val:
                best, best_val = c, val
        if best is None:
            # no visible near point leads closer: one leaf along the quadtree path
            a = tree.leaf_at(pos)
            if a not in toward:
                raise NoPathError(f"no route from ({pos[0]:.2f}, {pos[1]:.2f}) to target "
                                  f"{tcell}")
            b = toward[a]
            best = np.array(_centre(tree.nodes[b]))
            for q in _crossing(tree, a, b):
                if not (np.array_equal(q, pos) or np.array_equal(q, best)):
                    out.append(q)
        heading = best - pos
        out.append(best.copy())
        pos = best.copy()
    raise NoPathError(f"navigation to {tcell} did not converge")  # pragma: no cover


@dataclass(frozen=True)
class Section:
    """One section of a route (rules 3-5).

    Attributes:
        start, end: end points (x, y) in cells.
        road: ``"open"`` or ``"narrow"`` (the class of its leaves), or
            ``"known"`` for a leg inside one white leaf (rule 5).
        leaves: indices of the quadtree leaves it passes, in order.
        leg: index of the route leg (start -> first sub-goal is leg 0).
    """

    start: tuple[float, float]
    end: tuple[float, float]
    road: str
    leaves: tuple[int, ...]
    leg: int


def segment_route(route: np.ndarray, tree: Quadtree, *, open_leaf: int = 4,
                  step: float = 0.1) -> list[Section]:
    """Split a route (k, 2) into sections by rules 3-5 (module docstring).

    ``open_leaf``: side (cells) from which a leaf counts as open road;
    ``step``: sampling step (cells) used to find where the route changes leaf.
    """
    if isinstance(open_leaf, bool) or not isinstance(open_leaf, int) or open_leaf < 1:
        raise ParameterError(f"segment_route.open_leaf must be an integer >= 1, "
                             f"got {open_leaf!r}")
    route = np.asarray(route, dtype=float).reshape(-1, 2)
    sections: list[Section] = []
    for leg, (a, b) in enumerate(zip(route[:-1], route[1:], strict=True)):
        length = math.hypot(*(b - a))
        n = max(2, int(math.ceil(length / step)) + 1)
        ts = np.linspace(0.0, 1.0, n)
        leaves = [tree.leaf_at(a + t * (b - a)) for t in ts]
        distinct = list(dict.fromkeys(leaves))
        if len(distinct) == 1 and int(tree.nodes[distinct[0], 3]) == WHITE:
            sections.append(Section(_xy(a), _xy(b), "known", (distinct[0],), leg))
            continue
        classes = ["open" if int(tree.nodes[lf, 2]) >= open_leaf else "narrow"
                   for lf in leaves]
        s0, cls, run = 0, classes[0], [leaves[0]]
        for i in range(1, n):
            if classes[i] != cls:
                p = a + ts[i] * (b - a)
                sections.append(Section(_xy(a + ts[s0] * (b - a)) if s0 else _xy(a), _xy(p),
                                        cls, tuple(dict.fromkeys(run)), leg))
                s0, cls, run = i, classes[i], [leaves[i]]
            else:
                run.append(leaves[i])
        start = a + ts[s0] * (b - a) if s0 else a
        sections.append(Section(_xy(start), _xy(b), cls, tuple(dict.fromkeys(run)), leg))
    return sections


def _crossing(tree: Quadtree, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
    """How the fallback crosses from white leaf ``a`` into ``b``: the points
    half a cell inside ``a`` and inside ``b``, either side of the midpoint of
    their shared edge (so the step runs square across it). A point half a cell
    inside a free leaf keeps half a cell from everything outside it, and so
    does a segment between two such points of one leaf (the leaf is convex)."""
    na, nb = tree.nodes[a], tree.nodes[b]
    mid = np.array(_shared_midpoint(na, nb))
    if int(na[0]) + int(na[2]) == int(nb[0]):
        n = np.array([1.0, 0.0])
    elif int(nb[0]) + int(nb[2]) == int(na[0]):
        n = np.array([-1.0, 0.0])
    elif int(na[1]) + int(na[2]) == int(nb[1]):
        n = np.array([0.0, 1.0])
    else:
        n = np.array([0.0, -1.0])
    return mid - 0.5 * n, mid + 0.5 * n


def free_adjacency_midpoint(tree: Quadtree, a: int, b: int) -> tuple[float, float]:
    """Midpoint of the edge shared by white leaves ``a`` and ``b``."""
    return _shared_midpoint(tree.nodes[a], tree.nodes[b])


def _xy(p: np.ndarray) -> tuple[float, float]:
    return float(p[0]), float(p[1])


def build_tree(occupancy: np.ndarray) -> Quadtree:
    """The quadtree (finest size one cell) of a routing map."""
    return decompose(np.asarray(occupancy, dtype=bool))

"""Waypoint chromosomes for the GA path planner on an occupancy grid.

A chromosome is a variable-length list of cells, each gene a flat index
``y * width + x``: the first gene is the start, the last the goal, and the
ones between are the waypoints of a polyline. ``data`` is the grid
(height x width float64, non-zero = blocked); ``aux`` holds the scalars, a
:class:`WaypointAux` named tuple (build it with :func:`make_aux`).

The cost to minimise is ``length + Q * hits``: the Euclidean length of the
polyline plus ``Q`` for every blocked cell a segment touches. The thesis
maximises ``F = C f + Q`` with ``f = 1 / length``; for collision-free paths
both orders agree, and counting the cells a path crosses gives the search a
slope towards feasibility where a flat penalty gives none.

Two initialisations (``WaypointAux.init``):

* ``INIT_RANDOM`` (the thesis): random cells in random number, drawn again
  (up to ``init_tries`` times) until the path is collision-free;
* ``INIT_VISIBILITY``: the branch to the goal of a random tree grown along
  lines of sight (an RRT on cell centres), so every member starts feasible
  but different.

``shortcut`` turns on the ``improve`` operator (a memetic step): drop
every waypoint whose neighbours see each other (never longer, by the triangle
inequality) and slide each waypoint to a neighbouring cell while that
shortens the path.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError
from subtask_opt.ga.dispatch import OperatorSet
from subtask_opt.planners.grid._kernels import segment_hits

INIT_RANDOM = 0
INIT_VISIBILITY = 1


class WaypointAux(NamedTuple):
    """The scalar parameters of the waypoint operators (numba caches them by type)."""

    start_x: int
    start_y: int
    goal_x: int
    goal_y: int
    penalty: float
    """``Q``: cost added per blocked cell a segment touches."""
    init: int
    """``INIT_RANDOM`` or ``INIT_VISIBILITY``."""
    init_tries: int
    """Draws of a new member before the least-colliding one is kept (>= 1)."""
    shortcut: bool
    """Whether ``improve`` drops skippable waypoints and slides the rest."""


def make_aux(start: tuple[int, int], goal: tuple[int, int], *, penalty: float, init: int,
             init_tries: int, shortcut: bool) -> WaypointAux:
    """The :class:`WaypointAux` of a run, with the kernels' scalar types."""
    if init not in (INIT_RANDOM, INIT_VISIBILITY):
        raise ParameterError(f"make_aux: init must be INIT_RANDOM ({INIT_RANDOM}) or "
                             f"INIT_VISIBILITY ({INIT_VISIBILITY}), got {init!r}")
    return WaypointAux(int(start[0]), int(start[1]), int(goal[0]), int(goal[1]), float(penalty),
                       int(init), int(init_tries), bool(shortcut))


@njit(cache=True)
def _sees(data, a, b):
    w = data.shape[1]
    return segment_hits(data, a % w, a // w, b % w, b // w, True) == 0


@njit(cache=True)
def _seg_len(w, a, b):
    dx = a % w - b % w
    dy = a // w - b // w
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True)
def path_cost(genes, length, data, aux):
    """Polyline length plus ``Q`` per blocked cell touched by a segment."""
    w = data.shape[1]
    total = 0.0
    hits = 0
    for i in range(length - 1):
        a = genes[i]
        b = genes[i + 1]
        total += _seg_len(w, a, b)
        hits += segment_hits(data, a % w, a // w, b % w, b // w, False)
    return total + aux.penalty * hits


@njit(cache=True)
def _segment_cost(data, aux, a, b):
    w = data.shape[1]
    hits = segment_hits(data, a % w, a // w, b % w, b // w, False)
    return _seg_len(w, a, b) + aux.penalty * hits


@njit(cache=True)
def _drop_skippable(genes, length, data):
    """Remove every waypoint whose two neighbours see each other."""
    k = 1
    while k < length - 1:
        if _sees(data, genes[k - 1], genes[k + 1]):
            for m in range(k, length - 1):
                genes[m] = genes[m + 1]
            length -= 1
            if k > 1:
                k -= 1
        else:
            k += 1
    return length


@njit(cache=True)
def _free(data, x, y):
    """Whether cell (x, y) is on the grid and free."""
    h, w = data.shape
    return 0 <= x < w and 0 <= y < h and data[y, x] == 0.0


@njit(cache=True)
def _random_free(data, rng):
    h, w = data.shape
    for _ in range(64):
        x = rng.integers(0, w)
        y = rng.integers(0, h)
        if data[y, x] == 0.0:
            return y * w + x
    return -1


@njit(cache=True)
def _random_path(genes, data, aux, rng):
    """Start, 0..cap-2 random free cells, goal."""
    w = data.shape[1]
    cap = genes.shape[0]
    genes[0] = aux.start_y * w + aux.start_x
    k_inner = rng.integers(0, min(cap - 2, 6) + 1) if cap > 2 else 0
    length = 1
    for _ in range(k_inner):
        c = _random_free(data, rng)
        if c >= 0:
            genes[length] = c
            length += 1
    genes[length] = aux.goal_y * w + aux.goal_x
    return length + 1


@njit(cache=True)
def _visibility_tree(genes, data, aux, rng):
    """A random path along lines of sight, grown as a rapidly-exploring random
    tree: each random free cell (the goal one time in five) joins the nearest
    tree node that sees it, until the goal joins. The path is the goal's
    branch with skippable waypoints dropped; returns 0 if it does not fit."""
    h, w = data.shape
    cap = genes.shape[0]
    n = h * w
    start = aux.start_y * w + aux.start_x
    goal = aux.goal_y * w + aux.goal_x
    nodes = np.empty(n, dtype=np.int64)
    parent = np.empty(n, dtype=np.int64)
    in_tree = np.zeros(n, dtype=np.bool_)
    order = np.empty(n, dtype=np.int64)
    dists = np.empty(n)
    nodes[0] = start
    parent[0] = -1
    in_tree[start] = True
    size = 1
    for _ in range(min(50 * n, 5000)):  # bounded: a failed draw is retried or replaced
        c = goal if rng.random() < 0.2 else _random_free(data, rng)
        if c < 0 or in_tree[c]:
            continue
        for i in range(size):
            dists[i] = _seg_len(w, nodes[i], c)
        order[:size] = np.argsort(dists[:size])
        for i in range(size):
            if _sees(data, nodes[order[i]], c):
                nodes[size] = c
                parent[size] = order[i]
                in_tree[c] = True
                size += 1
                break
        if in_tree[goal]:
            break
    if not in_tree[goal]:
        return 0
    branch = np.empty(size, dtype=np.int64)
    k = 0
    i = size - 1
    while i >= 0:
        branch[k] = nodes[i]
        k += 1
        i = parent[i]
    path = branch[:k][::-1].copy()
    k = _drop_skippable(path, k, data)
    if k > cap:
        return 0
    genes[:k] = path[:k]
    return k


@njit(cache=True)
def random_path(genes, data, aux, rng, best, best_len):
    """``randomize``: a new member, redrawn until collision-free (up to the
    configured number of tries; the least-colliding draw otherwise)."""
    tries = max(1, aux.init_tries)
    use_walk = aux.init == INIT_VISIBILITY
    keep = np.empty_like(genes)
    keep_len = _random_path(keep, data, aux, rng)  # the fallback if every draw fails
    keep_cost = path_cost(keep, keep_len, data, aux)
    for _ in range(tries):
        if use_walk:
            length = _visibility_tree(genes, data, aux, rng)
            if length == 0:
                continue
        else:
            length = _random_path(genes, data, aux, rng)
        cost = path_cost(genes, length, data, aux)
        if cost < aux.penalty:  # no blocked cell touched
            return length
        if cost < keep_cost:
            keep_cost = cost
            keep_len = length
            keep[:length] = genes[:length]
    genes[:keep_len] = keep[:keep_len]
    return keep_len


@njit(cache=True)
def one_point_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """Single-point crossover: the head of ``a`` up to a random cut, then the
    tail of ``b`` from another random cut (length capped at the row size)."""
    cap = child.shape[0]
    i = rng.integers(1, len_a)  # child keeps a[:i] (at least the start)
    j = rng.integers(1, len_b)  # and b[j:] (at least the goal)
    if i + len_b - j > cap:
        j = len_b - (cap - i)
    for k in range(i):
        child[k] = genes_a[k]
    for k in range(j, len_b):
        child[i + k - j] = genes_b[k]
    return i + len_b - j


@njit(cache=True)
def nonuniform_mutation(genes, length, data, aux, rng, strength):
    """Move, insert or delete one waypoint; moves shrink as ``strength`` -> 1.

    A move shifts a waypoint by up to ``span * (1 - r ** ((1 - strength) ** 2))``
    cells per axis (Michalewicz' non-uniform mutation, r uniform in [0, 1)),
    so the search is coarse early and fine late; a blocked or off-grid target
    is redrawn a few times, then the move is skipped.
    """
    h, w = data.shape
    cap = genes.shape[0]
    span = max(h, w)
    u = rng.random()
    if length > 2 and u < 0.15:  # delete
        k = rng.integers(1, length - 1)
        for m in range(k, length - 1):
            genes[m] = genes[m + 1]
        return length - 1
    if length == 2 or (u < 0.3 and length < cap):  # insert near the middle of a segment
        if length >= cap:
            return length
        k = rng.integers(0, length - 1)
        a = genes[k]
        b = genes[k + 1]
        mx = (a % w + b % w) // 2
        my = (a // w + b // w) // 2
        for _ in range(8):
            x = mx + rng.integers(-span // 3, span // 3 + 1)
            y = my + rng.integers(-span // 3, span // 3 + 1)
            if _free(data, x, y):
                for m in range(length, k + 1, -1):
                    genes[m] = genes[m - 1]
                genes[k + 1] = y * w + x
                return length + 1
        return length
    if length <= 2:
        return length
    k = rng.integers(1, length - 1)
    x0 = genes[k] % w
    y0 = genes[k] // w
    scale = (1.0 - strength) ** 2
    for _ in range(8):
        dx = int(round(span * (1.0 - rng.random() ** scale)))
        dy = int(round(span * (1.0 - rng.random() ** scale)))
        if rng.random() < 0.5:
            dx = -dx
        if rng.random() < 0.5:
            dy = -dy
        if dx == 0 and dy == 0:
            dx = rng.integers(-1, 2)
            dy = rng.integers(-1, 2)
        x = x0 + dx
        y = y0 + dy
        if _free(data, x, y):
            genes[k] = y * w + x
            break
    return length


@njit(cache=True)
def _nudge(genes, length, data, aux):
    """Hill-climb each waypoint over its 8 neighbour cells while that shortens
    the path (it slides waypoints onto the obstacle corners an optimal
    any-angle path turns at). Returns whether anything moved."""
    h, w = data.shape
    moved = False
    for _ in range(4 * h * w):
        improved = False
        for k in range(1, length - 1):
            a = genes[k - 1]
            b = genes[k + 1]
            cur = genes[k]
            best = cur
            best_cost = _segment_cost(data, aux, a, cur) + _segment_cost(data, aux, cur, b)
            x0 = cur % w
            y0 = cur // w
            for dy in range(-1, 2):
                for dx in range(-1, 2):
                    x = x0 + dx
                    y = y0 + dy
                    if (dx == 0 and dy == 0) or not _free(data, x, y):
                        continue
                    c = y * w + x
                    cost = _segment_cost(data, aux, a, c) + _segment_cost(data, aux, c, b)
                    if cost < best_cost - 1e-12:
                        best_cost = cost
                        best = c
            if best != cur:
                genes[k] = best
                improved = True
                moved = True
        if not improved:
            break
    return moved


@njit(cache=True)
def shortcut(genes, length, data, aux):
    """``improve``: drop repeated cells; if enabled, drop skippable waypoints
    and slide the rest downhill (:func:`_nudge`) until neither helps."""
    out = 1
    for i in range(1, length):
        if genes[i] != genes[out - 1]:
            genes[out] = genes[i]
            out += 1
    length = out
    if not aux.shortcut:
        return length
    length = _drop_skippable(genes, length, data)
    for _ in range(genes.shape[0]):
        if not _nudge(genes, length, data, aux):
            break
        length = _drop_skippable(genes, length, data)
    return length


OPERATORS = OperatorSet(random_path, path_cost, one_point_crossover, nonuniform_mutation,
                        shortcut)
"""The waypoint path kind's operators (registered by :mod:`subtask_opt.chromosomes`)."""

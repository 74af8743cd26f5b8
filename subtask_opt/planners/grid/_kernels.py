"""Numba kernels of the grid planners (arrays and scalars in, arrays out).

Grids arrive as ``blocked`` uint8/bool arrays indexed ``[y, x]``; cells outside
the grid count as blocked. Moves follow one rule everywhere: a straight move is
collision-free when it touches no *closed* blocked cell square. Between cell
centres that is :func:`segment_hits` (exact integer arithmetic); for the
driven robot of VFF/VFH it is :func:`move_clear` (the same closed-square test
in floats). An 8-connected diagonal step touches the shared corner of its two
side cells, so the rule asks both to be free (no corner cutting). The one
deliberate exception is the thesis' own rule (Fig. 2.4), which the 3:4 transform
and the MDT take with ``cut``: a move may touch a blocked cell at a corner (enter
no blocked cell's open square), as a diagonal step past one blocked side cell does
(:func:`segment_clear`); no planner ever passes between two blocked cells that
touch at a corner.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.planners._graph_kernels import nearest_unsettled

# 8-neighbourhood; the first four are the side steps.
_DX = np.array([1, -1, 0, 0, 1, 1, -1, -1], dtype=np.int64)
_DY = np.array([0, 0, 1, -1, 1, -1, 1, -1], dtype=np.int64)


@njit(cache=True)
def _step_allowed(blocked, x, y, k, cut):
    """Whether the move k of the 8-neighbourhood from free cell (x, y) is allowed
    (``cut``: a diagonal may pass one blocked side cell, see :func:`_diagonal_ok`)."""
    h, w = blocked.shape
    nx = x + _DX[k]
    ny = y + _DY[k]
    if nx < 0 or ny < 0 or nx >= w or ny >= h or blocked[ny, nx]:
        return False
    if k >= 4:
        return _diagonal_ok(blocked[y, nx], blocked[ny, x], cut)
    return True


@njit(cache=True)
def _diagonal_ok(side_a, side_b, cut):
    """A diagonal step with side cells ``side_a``, ``side_b`` (non-zero = blocked).

    Without corner cutting both side cells must be free (the closed-square
    rule). With it (the thesis' Fig. 2.4), one blocked side cell is allowed,
    never two: the gap between two blocked cells touching at a corner stays shut.
    """
    if side_a and side_b:
        return False
    return cut or not (side_a or side_b)


@njit(cache=True)
def _padded(blocked):
    """Flat copy of ``blocked`` with a blocked border: neighbour lookups need no
    bounds checks. Cell (x, y) sits at ``(y + 1) * (w + 2) + x + 1``."""
    h, w = blocked.shape
    out = np.ones((h + 2) * (w + 2), dtype=np.uint8)
    for y in range(h):
        for x in range(w):
            out[(y + 1) * (w + 2) + x + 1] = 1 if blocked[y, x] else 0
    return out


@njit(cache=True)
def _relax_all(pad, w2, u, d, w_side, w_diag, cut, dist, seen, settled, stamp, nbr, cost):
    """Fill ``nbr``/``cost`` with the allowed, unsettled, improved neighbours of
    ``u`` (padded index, value ``d``), updating ``dist``/``seen``; return how many."""
    m = 0
    for k in range(8):
        sx = _DX[k]
        sy = _DY[k] * w2
        v = u + sx + sy
        if pad[v] or settled[v] == stamp:
            continue
        if k >= 4 and not _diagonal_ok(pad[u + sx], pad[u + sy], cut):
            continue
        nd = d + (w_side if k < 4 else w_diag)
        if seen[v] != stamp or nd < dist[v]:
            seen[v] = stamp
            dist[v] = nd
            nbr[m] = v
            cost[m] = nd
            m += 1
    return m


@njit(cache=True)
def _propagate(pad, w2, src, w_side, w_diag, cut, targets, dist, seen, settled, want, stamp,
               ring):
    """Goal-rooted propagation on a padded grid into caller-owned buffers.

    Dinitz's bucket queue instead of a heap: bucket ``b`` holds cells whose
    value lies in ``[b, b + 1) * w_side``. No step costs less than ``w_side``,
    so no cell of the lowest non-empty bucket can improve another of the same
    bucket: all of them are final and can be settled in any order. A value
    never exceeds the current bucket by more than ``w_diag``, so a small ring
    of buckets suffices; ``ring`` (rows = buckets) grows on demand and the
    (possibly new) ring is returned.

    ``dist[v]`` is valid where ``seen[v] == stamp`` and final where
    ``settled[v] == stamp``; ``want[v] == stamp`` marks a target. Stamps let
    the buffers be reused between calls without clearing. Stops once every
    cell of ``targets`` is final (never, if it is empty).
    """
    n_ring = ring.shape[0]
    sizes = np.zeros(n_ring, dtype=np.int64)
    nbr = np.empty(8, dtype=np.int64)
    cost = np.empty(8)
    n_want = 0
    for t in targets:
        if want[t] != stamp:
            want[t] = stamp
            n_want += 1
    dist[src] = 0.0
    seen[src] = stamp
    ring[0, 0] = src
    sizes[0] = 1
    pending = 1
    bucket = 0
    while pending > 0:
        slot = bucket % n_ring
        if sizes[slot] == 0:
            bucket += 1
            continue
        sizes[slot] -= 1
        pending -= 1
        u = ring[slot, sizes[slot]]
        if settled[u] == stamp:
            continue
        settled[u] = stamp
        if want[u] == stamp:
            n_want -= 1
            if n_want == 0:
                break
        m = _relax_all(pad, w2, u, dist[u], w_side, w_diag, cut, dist, seen, settled, stamp, nbr,
                       cost)
        for i in range(m):
            target = int(cost[i] / w_side) % n_ring
            if sizes[target] == ring.shape[1]:
                grown = np.empty((n_ring, 2 * ring.shape[1]), dtype=np.int64)
                grown[:, : ring.shape[1]] = ring
                ring = grown
            ring[target, sizes[target]] = nbr[i]
            sizes[target] += 1
            pending += 1
    return ring


# -- binary heap on parallel arrays (key, item) with lazy deletion ------------------------
@njit(cache=True)
def _heap_push(keys, items, size, key, item):
    i = size
    keys[i] = key
    items[i] = item
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= keys[i]:
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        items[parent], items[i] = items[i], items[parent]
        i = parent
    return size + 1


@njit(cache=True)
def _heap_pop(keys, items, size):
    key = keys[0]
    item = items[0]
    size -= 1
    keys[0] = keys[size]
    items[0] = items[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and keys[left + 1] < keys[left]:
            child = left + 1
        if keys[i] <= keys[child]:
            break
        keys[child], keys[i] = keys[i], keys[child]
        items[child], items[i] = items[i], items[child]
        i = child
    return key, item, size


@njit(cache=True)
def _focused(pad, w2, src, dst, w_side, w_diag, dist, seen, settled, stamp, heap, marks):
    """The goal-rooted propagation of :func:`_propagate`, ordered by value plus
    an estimate of the distance left to the one cell ``dst`` wanted (A*).

    The estimate is the larger of the obstacle-free octile distance and, for
    each landmark L (rows of ``marks``: full fields from L), the triangle
    bound ``|d(L, dst) - d(L, v)|`` (ALT). Both never exceed the true remaining
    distance and change by at most a step's cost between neighbours, so every
    settled cell still gets its exact value; only cells that cannot lie on a
    shortest path to ``dst`` are skipped. ``heap`` is a (keys, items) pair
    grown on demand. Returns the distance at ``dst`` (``inf`` if unreachable)
    and the (possibly new) heap.
    """
    keys, items = heap
    n_marks = marks.shape[0]
    at_dst = np.empty(n_marks)
    for j in range(n_marks):
        at_dst[j] = marks[j, dst]
    nbr = np.empty(8, dtype=np.int64)
    cost = np.empty(8)
    tx = dst % w2
    ty = dst // w2
    dist[src] = 0.0
    seen[src] = stamp
    size = _heap_push(keys, items, 0, 0.0, src)
    while size > 0:
        _, u, size = _heap_pop(keys, items, size)
        if settled[u] == stamp:
            continue
        settled[u] = stamp
        if u == dst:
            return dist[u], (keys, items)
        m = _relax_all(pad, w2, u, dist[u], w_side, w_diag, False, dist, seen, settled, stamp,
                       nbr, cost)
        for i in range(m):
            v = nbr[i]
            ax = abs(v % w2 - tx)
            ay = abs(v // w2 - ty)
            est = w_diag * min(ax, ay) + w_side * (max(ax, ay) - min(ax, ay))
            for j in range(n_marks):
                lv = marks[j, v]
                if lv < np.inf and at_dst[j] < np.inf:
                    est = max(est, abs(at_dst[j] - lv))
            if size == keys.shape[0]:
                grown_k = np.empty(2 * size)
                grown_i = np.empty(2 * size, dtype=np.int64)
                grown_k[:size] = keys
                grown_i[:size] = items
                keys, items = grown_k, grown_i
            size = _heap_push(keys, items, size, cost[i] + est, v)
    return np.inf, (keys, items)


@njit(cache=True)
def landmark_fields(blocked, w_side, w_diag, n_marks):
    """Full fields from ``n_marks`` landmarks spread by farthest-point choice
    (each new landmark is the cell farthest from all earlier ones), for the
    ALT estimate of :func:`_focused`. Rows are indexed like the padded grid
    of :func:`_padded`; ``inf`` where unreachable."""
    w2 = blocked.shape[1] + 2
    pad = _padded(blocked)
    n2 = pad.shape[0]
    marks = np.full((n_marks, n2), np.inf)
    nearest = np.full(n2, np.inf)
    dist = np.empty(n2)
    seen = np.zeros(n2, dtype=np.int32)
    settled = np.zeros(n2, dtype=np.int32)
    want = np.zeros(n2, dtype=np.int32)
    ring = np.empty((int(w_diag / w_side) + 2, 1024), dtype=np.int64)
    none = np.zeros(0, dtype=np.int64)
    src = -1
    for v in range(n2):
        if not pad[v]:
            src = v
            break
    for j in range(n_marks):
        if src < 0:
            return marks[:j].copy()
        ring = _propagate(pad, w2, src, w_side, w_diag, False, none, dist, seen, settled, want,
                          j + 1, ring)
        far = -1
        far_d = -1.0
        for v in range(n2):
            if settled[v] == j + 1:
                marks[j, v] = dist[v]
                if dist[v] < nearest[v]:
                    nearest[v] = dist[v]
            if nearest[v] < np.inf and nearest[v] > far_d:
                far_d = nearest[v]
                far = v
        src = far
    return marks


@njit(cache=True)
def chamfer_field(blocked, gx, gy, w_side, w_diag, cut, targets):
    """Goal-rooted distance transform on the 8-connected grid.

    Side steps cost ``w_side`` and diagonal steps ``w_diag`` (3 and 4 for the
    thesis' chamfer, 1 and sqrt(2) for the exact octile metric). Processing
    cells in order of value (a bucket queue) makes one pass exact, where
    Jarvis' raster propagation repeats sweeps until nothing changes; both
    reach the same fixed point. Unreachable cells stay ``inf``. If
    ``targets`` (flat indices ``y * w + x``) is non-empty the transform stops
    once all of them are final; cells not yet final then hold ``inf``.
    """
    h, w = blocked.shape
    w2 = w + 2
    pad = _padded(blocked)
    n2 = pad.shape[0]
    dist = np.empty(n2)
    seen = np.zeros(n2, dtype=np.int32)
    settled = np.zeros(n2, dtype=np.int32)
    want = np.zeros(n2, dtype=np.int32)
    ptargets = (targets // w + 1) * w2 + targets % w + 1
    ring = np.empty((int(w_diag / w_side) + 2, 1024), dtype=np.int64)
    _propagate(pad, w2, (gy + 1) * w2 + gx + 1, w_side, w_diag, cut, ptargets, dist, seen,
               settled, want, 1, ring)
    out = np.full((h, w), np.inf)
    for y in range(h):
        for x in range(w):
            p = (y + 1) * w2 + x + 1
            if settled[p] == 1 or (targets.shape[0] == 0 and seen[p] == 1):
                out[y, x] = dist[p]
    return out


@njit(cache=True)
def octile_queries(blocked, goals, starts, w_side, w_diag, focused, marks):
    """Distance start -> goal for many (start, goal) pairs (flat ``y * w + x``).

    Pairs must be sorted by goal. Without ``focused``, consecutive pairs with
    the same goal share one transform that stops once their starts are final;
    with it, each pair runs the A*-ordered transform of :func:`_focused`
    guided by the landmark fields ``marks`` (from :func:`landmark_fields`;
    may have no rows).
    Buffers are reused across transforms. Returns the distances (``inf`` if
    unreachable).
    """
    h, w = blocked.shape
    w2 = w + 2
    pad = _padded(blocked)
    n2 = pad.shape[0]
    m = goals.shape[0]
    pgoals = (goals // w + 1) * w2 + goals % w + 1
    pstarts = (starts // w + 1) * w2 + starts % w + 1
    out = np.empty(m)
    dist = np.empty(n2)
    seen = np.zeros(n2, dtype=np.int32)
    settled = np.zeros(n2, dtype=np.int32)
    want = np.zeros(n2, dtype=np.int32)
    ring = np.empty((int(w_diag / w_side) + 2, 1024), dtype=np.int64)
    heap = (np.empty(1024), np.empty(1024, dtype=np.int64))
    stamp = 0
    i = 0
    while i < m:
        stamp += 1
        if focused:
            out[i], heap = _focused(pad, w2, pgoals[i], pstarts[i], w_side, w_diag, dist, seen,
                                    settled, stamp, heap, marks)
            i += 1
            continue
        j = i
        while j < m and pgoals[j] == pgoals[i]:
            j += 1
        ring = _propagate(pad, w2, pgoals[i], w_side, w_diag, False, pstarts[i:j], dist, seen,
                          settled, want, stamp, ring)
        for r in range(i, j):
            out[r] = dist[pstarts[r]] if settled[pstarts[r]] == stamp else np.inf
        i = j
    return out


# Next-cell rules of :func:`_descend`.
_RULE_NEIGHBOUR, _RULE_REALISING, _RULE_LEAST_VISIBLE = range(3)


@njit(cache=True)
def _next_neighbour(blocked, dist, x, y, w_side, w_diag, cut):
    """:func:`descend`'s step: the allowed neighbour of least value + step cost."""
    best_total = np.inf
    best_val = np.inf
    bx, by = -1, -1
    for k in range(8):
        if not _step_allowed(blocked, x, y, k, cut):
            continue
        nx = x + _DX[k]
        ny = y + _DY[k]
        val = dist[ny, nx]
        total = val + (w_side if k < 4 else w_diag)
        if total < best_total - 1e-9 or (abs(total - best_total) <= 1e-9 and val < best_val):
            best_total = total
            best_val = val
            bx, by = nx, ny
    return bx, by, best_val


@njit(cache=True)
def _next_realising(blocked, dist, x, y, cut):
    """:func:`visibility_descend`'s step: the visible cell of least value among
    those with value + segment length = the current value."""
    h, w = blocked.shape
    cur = dist[y, x]
    tol = 1e-9 * max(1.0, cur)
    best_val = cur
    bx, by = -1, -1
    for ny in range(h):
        for nx in range(w):
            val = dist[ny, nx]
            if not val < best_val:
                continue
            ddx = nx - x
            ddy = ny - y
            if val + math.sqrt(ddx * ddx + ddy * ddy) > cur + tol:
                continue
            if segment_clear(blocked, x, y, nx, ny, cut):
                best_val = val
                bx, by = nx, ny
    return bx, by, best_val


@njit(cache=True)
def _next_least_visible(blocked, dist, x, y, cut):
    """:func:`descend_least_visible`'s step: the visible cell of least value
    (ties: the nearer one)."""
    h, w = blocked.shape
    best_val = dist[y, x]
    best_len = np.inf
    bx, by = -1, -1
    for ny in range(h):
        for nx in range(w):
            val = dist[ny, nx]
            if val > best_val:
                continue
            ddx = nx - x
            ddy = ny - y
            seg = math.sqrt(ddx * ddx + ddy * ddy)
            if seg == 0.0 or (val == best_val and seg >= best_len):
                continue
            if segment_clear(blocked, x, y, nx, ny, cut):
                best_val = val
                best_len = seg
                bx, by = nx, ny
    return bx, by, best_val


@njit(cache=True)
def _descend(blocked, dist, sx, sy, rule, w_side, w_diag, cut):
    """Walk from (sx, sy) to the zero of ``dist``, one ``rule`` step at a time
    (``w_side`` and ``w_diag`` matter to ``_RULE_NEIGHBOUR`` only; ``cut`` is the
    corner rule of every rule's moves).
    Returns a (k, 2) int64 array of cells, or an empty one when the start is
    unreachable or a step finds no cell of smaller value (not a valid field)."""
    h, w = blocked.shape
    if not math.isfinite(dist[sy, sx]):
        return np.zeros((0, 2), dtype=np.int64)
    out = np.empty((h * w + 1, 2), dtype=np.int64)
    x, y = sx, sy
    out[0, 0] = x
    out[0, 1] = y
    k_out = 1
    while dist[y, x] > 0.0 and k_out <= h * w:
        if rule == _RULE_NEIGHBOUR:
            bx, by, best_val = _next_neighbour(blocked, dist, x, y, w_side, w_diag, cut)
        elif rule == _RULE_REALISING:
            bx, by, best_val = _next_realising(blocked, dist, x, y, cut)
        else:
            bx, by, best_val = _next_least_visible(blocked, dist, x, y, cut)
        if bx < 0 or not best_val < dist[y, x]:
            return np.zeros((0, 2), dtype=np.int64)
        x, y = bx, by
        out[k_out, 0] = x
        out[k_out, 1] = y
        k_out += 1
    return out[:k_out].copy()


@njit(cache=True)
def descend(blocked, dist, sx, sy, w_side, w_diag, cut):
    """Steepest descent on a chamfer/octile field from (sx, sy) to its zero.

    Each step goes to the allowed neighbour minimising value + step cost, i.e.
    the neighbour the value was propagated from (ties: the lower value, then
    the first in neighbourhood order), so the path realises the field value.
    Returns a (k, 2) int64 array of cells, or an empty one if unreachable.
    """
    return _descend(blocked, dist, sx, sy, _RULE_NEIGHBOUR, w_side, w_diag, cut)


# -- line of sight between cell centres ------------------------------------------------
@njit(cache=True)
def _column_hits(blocked, cx, cy_lo, cy_hi, first_only):
    """Blocked cells (cells outside the grid count) of column ``cx``, rows
    ``cy_lo..cy_hi``; with ``first_only`` 1 at the first one."""
    h, w = blocked.shape
    hits = 0
    for cy in range(cy_lo, cy_hi + 1):
        if cy < 0 or cy >= h or cx < 0 or cx >= w or blocked[cy, cx]:
            hits += 1
            if first_only:
                return 1
    return hits


@njit(cache=True)
def segment_hits(blocked, x0, y0, x1, y1, first_only):
    """Number of blocked cells whose closed square the segment touches.

    Exact integer arithmetic (coordinates doubled and scaled by dx); with
    ``first_only`` it returns 1 at the first blocked cell. Cells outside the
    grid count as blocked.
    """
    if x0 > x1:
        x0, y0, x1, y1 = x1, y1, x0, y0
    dx = x1 - x0
    dy = y1 - y0
    if dx == 0:
        return _column_hits(blocked, x0, min(y0, y1), max(y0, y1), first_only)
    hits = 0
    for cx in range(x0, x1 + 1):
        xa = max(2 * x0, 2 * cx - 1)
        xb = min(2 * x1, 2 * cx + 1)
        na = 2 * y0 * dx + dy * (xa - 2 * x0)
        nb = 2 * y0 * dx + dy * (xb - 2 * x0)
        nlo = min(na, nb)
        nhi = max(na, nb)
        cy_lo = -((dx - nlo) // (2 * dx))  # ceil((nlo - dx) / (2 dx))
        cy_hi = (nhi + dx) // (2 * dx)
        hits += _column_hits(blocked, cx, cy_lo, cy_hi, first_only)
        if first_only and hits > 0:
            return 1
    return hits


@njit(cache=True)
def _segment_clear_open(blocked, x0, y0, x1, y1):
    """The thesis' rule between cell centres: the segment enters no blocked cell's open
    square and passes through no corner point between two blocked cells that touch
    there (cells outside the grid count as blocked). Exact integer arithmetic, as
    :func:`segment_hits`."""
    if x0 > x1:
        x0, y0, x1, y1 = x1, y1, x0, y0
    dx = x1 - x0
    dy = y1 - y0
    if dx == 0:
        # a column at a cell centre touches no other column
        return _column_hits(blocked, x0, min(y0, y1), max(y0, y1), True) == 0
    for cx in range(x0, x1 + 1):
        xa = max(2 * x0, 2 * cx - 1)
        xb = min(2 * x1, 2 * cx + 1)
        na = 2 * y0 * dx + dy * (xa - 2 * x0)
        nb = 2 * y0 * dx + dy * (xb - 2 * x0)
        nlo = min(na, nb)
        nhi = max(na, nb)
        # rows whose open interval (cy - 1/2, cy + 1/2) meets (nlo, nhi) / (2 dx)
        cy_lo = (nlo - dx) // (2 * dx) + 1
        cy_hi = -((-(nhi + dx)) // (2 * dx)) - 1
        if _column_hits(blocked, cx, cy_lo, cy_hi, True):
            return False
        if cx < x1 and nb % (2 * dx) == dx:
            # through the corner point (cx + 1/2, k + 1/2): it goes from one cell to the
            # diagonally opposite one and touches the other two at that point only
            k = (nb - dx) // (2 * dx)
            if dy > 0:
                ax, ay, bx, by = cx + 1, k, cx, k + 1
            else:
                ax, ay, bx, by = cx, k, cx + 1, k + 1
            if _column_hits(blocked, ax, ay, ay, True) and _column_hits(blocked, bx, by, by,
                                                                           True):
                return False
    return True


@njit(cache=True)
def segment_clear(blocked, x0, y0, x1, y1, cut):
    """Whether the straight move between cell centres is allowed: without ``cut`` it
    touches no closed blocked square (:func:`segment_hits`); with ``cut`` (the thesis'
    rule) it may touch blocked squares at a corner, never between two of them."""
    if cut:
        return _segment_clear_open(blocked, x0, y0, x1, y1)
    return segment_hits(blocked, x0, y0, x1, y1, True) == 0


@njit(cache=True)
def _free_cells(blocked, gx, gy):
    """The free cells in row-major order: (xs, ys, index of (gx, gy) or -1)."""
    h, w = blocked.shape
    n_free = 0
    for y in range(h):
        for x in range(w):
            if not blocked[y, x]:
                n_free += 1
    xs = np.empty(n_free, dtype=np.int64)
    ys = np.empty(n_free, dtype=np.int64)
    k = 0
    src = -1
    for y in range(h):
        for x in range(w):
            if not blocked[y, x]:
                xs[k] = x
                ys[k] = y
                if x == gx and y == gy:
                    src = k
                k += 1
    return xs, ys, src


@njit(cache=True)
def _to_grid(shape, xs, ys, values):
    """The (h, w) field holding ``values`` at the cells (xs, ys), ``inf`` elsewhere."""
    out = np.full(shape, np.inf)
    for i in range(xs.shape[0]):
        out[ys[i], xs[i]] = values[i]
    return out


@njit(cache=True)
def visibility_field(blocked, gx, gy, cut):
    """Any-angle distance field: Dijkstra on the line-of-sight graph.

    Vertices are the free cell centres, edges join every pair with a
    collision-free straight segment (:func:`segment_clear` with ``cut``),
    weighted by its Euclidean length. The
    graph is dense, so the O(n^2) array Dijkstra (no heap) is the right one:
    settle the nearest cell, then relax every unsettled cell it can see.
    Returns the (h, w) field (``inf`` blocked or unreachable).
    """
    xs, ys, src = _free_cells(blocked, gx, gy)
    n_free = xs.shape[0]
    dist = np.full(n_free, np.inf)
    done = np.zeros(n_free, dtype=np.bool_)
    dist[src] = 0.0
    for _ in range(n_free):
        u = nearest_unsettled(dist, done)
        if u < 0:
            break
        done[u] = True
        du = dist[u]
        ux = xs[u]
        uy = ys[u]
        for v in range(n_free):
            if done[v]:
                continue
            ddx = xs[v] - ux
            ddy = ys[v] - uy
            nd = du + math.sqrt(ddx * ddx + ddy * ddy)
            if nd < dist[v] and segment_clear(blocked, ux, uy, xs[v], ys[v], cut):
                dist[v] = nd
    return _to_grid(blocked.shape, xs, ys, dist)


@njit(cache=True)
def visibility_descend(blocked, dist, sx, sy, cut):
    """Follow an any-angle field from (sx, sy): each jump goes to the visible
    cell of least value among those that realise the current value
    (value + segment length = current value), so the path has the field's
    length and as few waypoints as the field allows."""
    return _descend(blocked, dist, sx, sy, _RULE_REALISING, 1.0, 1.0, cut)


@njit(cache=True)
def visibility_levels(blocked, gx, gy, cut):
    """The thesis' own MDT fill (section 2.2.4), level by level.

    Level 1: every free cell that sees the goal gets its straight-line
    distance. Level k + 1: every still empty free cell that sees a level-k cell
    gets ``min(value + segment length)`` over the level-k cells it sees. A
    filled cell is never revisited, so the values are upper bounds of the exact
    any-angle distances (:func:`visibility_field`), equal where the best chain
    also has the fewest segments. Returns the (h, w) field (``inf`` blocked or
    unreachable).
    """
    xs, ys, src = _free_cells(blocked, gx, gy)
    n_free = xs.shape[0]
    value = np.full(n_free, np.inf)
    new_value = np.full(n_free, np.inf)
    frontier = np.empty(n_free, dtype=np.int64)
    nxt = np.empty(n_free, dtype=np.int64)
    value[src] = 0.0
    frontier[0] = src
    n_front = 1
    while n_front > 0:
        n_next = 0
        for c in range(n_free):
            if value[c] < np.inf:
                continue
            best = np.inf
            for f in range(n_front):
                u = frontier[f]
                ddx = xs[c] - xs[u]
                ddy = ys[c] - ys[u]
                nd = value[u] + math.sqrt(ddx * ddx + ddy * ddy)
                if nd < best and segment_clear(blocked, xs[u], ys[u], xs[c], ys[c], cut):
                    best = nd
            if best < np.inf:
                new_value[c] = best
                nxt[n_next] = c
                n_next += 1
        for f in range(n_next):
            value[nxt[f]] = new_value[nxt[f]]
        frontier[:n_next] = nxt[:n_next]
        n_front = n_next
    return _to_grid(blocked.shape, xs, ys, value)


@njit(cache=True)
def descend_least_visible(blocked, dist, sx, sy, cut):
    """The thesis' step 5: from (sx, sy) jump to the visible cell of least
    value (ties: the nearer one) until the zero cell. Every cell of a level
    field sees the cell it was filled from, which holds a smaller value, so
    each jump lowers the value and the walk ends."""
    return _descend(blocked, dist, sx, sy, _RULE_LEAST_VISIBLE, 1.0, 1.0, cut)


# -- local planners: a simulated robot with a certainty grid ---------------------------
# Outcome codes of vff_run / vfh_run.
REACHED, COLLISION, LOCAL_MINIMUM, OSCILLATION, STEP_LIMIT, NO_VALLEY = range(6)


class RobotKernelParams(NamedTuple):
    """The simulated robot of VFF and VFH as the kernels read it (angles in rad)."""

    window: float
    speed: float
    max_turn: float
    max_steps: int
    goal_tolerance: float
    stall_steps: int
    stall_gain: float
    stall_radius: float
    certainty_increment: float
    certainty_max: float


class VFFKernelParams(NamedTuple):
    """VFF force constants (eq. 2.1-2.6) as :func:`vff_run` reads them."""

    f_cr: float
    f_ct: float
    k_s: float


class VFHKernelParams(NamedTuple):
    """VFH histogram constants (eq. 2.7-2.11) as :func:`vfh_run` reads them (alpha in rad)."""

    alpha: float
    a: float
    b: float
    smoothing: int
    centre_weight: float
    threshold: float
    s_max: int


@njit(cache=True)
def wrap(angle):
    """Angle in [-pi, pi): the numba twin of :func:`subtask_opt.base.geometry.wrap_angle`
    (which numba cannot compile); a test checks that the two agree."""
    return angle - 2.0 * math.pi * math.floor((angle + math.pi) / (2.0 * math.pi))


@njit(cache=True)
def _sense(blocked, certainty, x, y, radius, increment, c_max):
    """Raise the certainty of every blocked cell within ``radius`` of (x, y)
    (a perfect range sensor feeding a histogram grid)."""
    h, w = blocked.shape
    cx = int(math.floor(x + 0.5))
    cy = int(math.floor(y + 0.5))
    r = int(math.ceil(radius))
    for j in range(max(cy - r, 0), min(cy + r, h - 1) + 1):
        for i in range(max(cx - r, 0), min(cx + r, w - 1) + 1):
            if blocked[j, i] and (i - x) ** 2 + (j - y) ** 2 <= radius * radius:
                certainty[j, i] = min(certainty[j, i] + increment, c_max)


@njit(cache=True)
def _clip_axis(t0, t1, p0, d, lo, hi):
    """One axis of Liang-Barsky: the parameter interval [t0, t1] of
    ``p0 + t d`` cut to [lo, hi]; an empty one (t0 > t1) if the line misses."""
    if d == 0.0:
        if p0 < lo or p0 > hi:
            return 1.0, 0.0
        return t0, t1
    ta = (lo - p0) / d
    tb = (hi - p0) / d
    return max(t0, min(ta, tb)), min(t1, max(ta, tb))


@njit(cache=True)
def _touches_box(x0, y0, x1, y1, lo_x, lo_y, hi_x, hi_y):
    """Whether the segment (x0, y0)-(x1, y1) meets the closed box (Liang-Barsky)."""
    t0, t1 = _clip_axis(0.0, 1.0, x0, x1 - x0, lo_x, hi_x)
    t0, t1 = _clip_axis(t0, t1, y0, y1 - y0, lo_y, hi_y)
    return t0 <= t1


@njit(cache=True)
def move_clear(blocked, x0, y0, x1, y1):
    """Whether the straight move (x0, y0) -> (x1, y1) touches no closed blocked
    cell square (cells outside the grid count as blocked): the rule of
    :func:`segment_hits`, for points anywhere in the plane."""
    h, w = blocked.shape
    i_lo = int(math.ceil(min(x0, x1) - 0.5))
    i_hi = int(math.floor(max(x0, x1) + 0.5))
    j_lo = int(math.ceil(min(y0, y1) - 0.5))
    j_hi = int(math.floor(max(y0, y1) + 0.5))
    for j in range(j_lo, j_hi + 1):
        for i in range(i_lo, i_hi + 1):
            if 0 <= i < w and 0 <= j < h and not blocked[j, i]:
                continue
            if _touches_box(x0, y0, x1, y1, i - 0.5, j - 0.5, i + 0.5, j + 0.5):
                return False
    return True


@njit(cache=True)
def _move(blocked, traj, step, heading, speed):
    """Advance one step along ``heading``; return False on a collision (the
    step touches a closed blocked square, :func:`move_clear`)."""
    x0 = traj[step - 1, 0]
    y0 = traj[step - 1, 1]
    x = x0 + speed * math.cos(heading)
    y = y0 + speed * math.sin(heading)
    traj[step, 0] = x
    traj[step, 1] = y
    return move_clear(blocked, x0, y0, x, y)


@njit(cache=True)
def _arrived(blocked, x, y, gx, gy, tol):
    """Within ``tol`` of the goal centre and able to drive straight onto it."""
    return math.hypot(gx - x, gy - y) <= tol and move_clear(blocked, x, y, gx, gy)


@njit(cache=True)
def _stall(traj, step, gx, gy, best_d, last_gain, robot):
    """Stall test after ``step``: returns (code or -1, best distance, step of last gain).

    A run stalls when the distance to the goal has not improved by
    ``robot.stall_gain`` cells for ``robot.stall_steps`` steps: a local minimum
    if the robot also stayed within ``robot.stall_radius`` of where it was
    then, an oscillation (a loop or back-and-forth) otherwise.
    """
    d = math.hypot(traj[step, 0] - gx, traj[step, 1] - gy)
    if d < best_d - robot.stall_gain:
        return -1, d, step
    if step - last_gain >= robot.stall_steps:
        back = step - robot.stall_steps
        moved = math.hypot(traj[step, 0] - traj[back, 0], traj[step, 1] - traj[back, 1])
        return (LOCAL_MINIMUM if moved < robot.stall_radius else OSCILLATION), best_d, last_gain
    return -1, best_d, last_gain


@njit(cache=True)
def _drive_start(blocked, sx, sy, gx, gy, robot):
    """The state of a fresh drive: (certainty grid, trajectory buffer with the
    start, heading at the goal, distance to the goal)."""
    certainty = np.zeros(blocked.shape)
    traj = np.empty((robot.max_steps + 1, 2))
    traj[0, 0] = sx
    traj[0, 1] = sy
    return certainty, traj, math.atan2(gy - sy, gx - sx), math.hypot(gx - sx, gy - sy)


@njit(cache=True)
def _observe(blocked, certainty, traj, step, gx, gy, robot):
    """Start of ``step``: returns (x, y, arrived) for the robot at
    ``traj[step - 1]``; unless it has arrived, it senses into ``certainty``."""
    x = traj[step - 1, 0]
    y = traj[step - 1, 1]
    if _arrived(blocked, x, y, gx, gy, robot.goal_tolerance):
        return x, y, True
    _sense(blocked, certainty, x, y, robot.window, robot.certainty_increment,
           robot.certainty_max)
    return x, y, False


@njit(cache=True)
def _drive_step(blocked, traj, step, heading, turn, gx, gy, best_d, last_gain, robot):
    """End of ``step``: turn by ``turn`` (limited to ``robot.max_turn``), move,
    test for a stall. Returns (code or -1, heading, best distance, step of
    last gain); the code is ``COLLISION`` or a :func:`_stall` code."""
    heading = wrap(heading + max(-robot.max_turn, min(robot.max_turn, turn)))
    if not _move(blocked, traj, step, heading, robot.speed):
        return COLLISION, heading, best_d, last_gain
    code, best_d, last_gain = _stall(traj, step, gx, gy, best_d, last_gain, robot)
    return code, heading, best_d, last_gain


@njit(cache=True)
def _drive_end(blocked, traj, gx, gy, robot):
    """Outcome of a drive that used every step: arrived, or the step limit."""
    n = robot.max_steps
    if _arrived(blocked, traj[n, 0], traj[n, 1], gx, gy, robot.goal_tolerance):
        return REACHED, traj
    return STEP_LIMIT, traj


@njit(cache=True)
def vff_run(blocked, sx, sy, gx, gy, robot, force):
    """Virtual force field (Borenstein & Koren 1989), eq. 2.1-2.6.

    ``robot`` is a :class:`RobotKernelParams`, ``force`` a
    :class:`VFFKernelParams`. Returns (outcome code, trajectory).
    """
    radius = robot.window
    h, w = blocked.shape
    certainty, traj, heading, best_d = _drive_start(blocked, sx, sy, gx, gy, robot)
    last_gain = 0
    r = int(math.ceil(radius))
    for step in range(1, robot.max_steps + 1):
        x, y, arrived = _observe(blocked, certainty, traj, step, gx, gy, robot)
        if arrived:
            return REACHED, traj[:step].copy()
        fx = 0.0
        fy = 0.0
        cx = int(math.floor(x + 0.5))
        cy = int(math.floor(y + 0.5))
        for j in range(max(cy - r, 0), min(cy + r, h - 1) + 1):
            for i in range(max(cx - r, 0), min(cx + r, w - 1) + 1):
                c = certainty[j, i]
                if c <= 0.0:
                    continue
                dx = x - i
                dy = y - j
                d = math.hypot(dx, dy)
                if d <= 1e-9 or d > radius:
                    continue
                mag = force.f_cr * c / (d * d)  # eq. 2.1, along the unit vector cell -> robot
                fx += mag * dx / d
                fy += mag * dy / d
        dg = max(math.hypot(gx - x, gy - y), 1e-12)
        rx = fx + force.f_ct * (gx - x) / dg  # eq. 2.3, 2.4
        ry = fy + force.f_ct * (gy - y) / dg
        delta = math.atan2(ry, rx)
        omega = force.k_s * wrap(delta - heading)  # eq. 2.5, 2.6
        code, heading, best_d, last_gain = _drive_step(blocked, traj, step, heading, omega,
                                                       gx, gy, best_d, last_gain, robot)
        if code >= 0:
            return code, traj[: step + 1].copy()
    return _drive_end(blocked, traj, gx, gy, robot)


@njit(cache=True)
def polar_histogram(certainty, x, y, radius, n_sectors, a, b, l_smooth, centre_weight):
    """Smoothed polar obstacle density around (x, y), eq. 2.7-2.11.

    Each cell within ``radius`` adds ``m = C^2 (a - b d)`` to the sector of
    its direction ``beta`` (eq. 2.7-2.10). Smoothing (eq. 2.11): sector
    ``k + i`` (``0 < |i| <= l``) gets weight ``l + 1 - |i|`` (1, 2, ... from the
    ends, as printed), sector ``k`` gets ``centre_weight``, and the sum is
    divided by ``2l + 1``.
    """
    h, w = certainty.shape
    hist = np.zeros(n_sectors)
    cx = int(math.floor(x + 0.5))
    cy = int(math.floor(y + 0.5))
    r = int(math.ceil(radius))
    width = 2.0 * math.pi / n_sectors
    for j in range(max(cy - r, 0), min(cy + r, h - 1) + 1):
        for i in range(max(cx - r, 0), min(cx + r, w - 1) + 1):
            c = certainty[j, i]
            if c <= 0.0:
                continue
            d = math.hypot(i - x, j - y)
            if d > radius or d <= 1e-9:
                continue
            beta = math.atan2(j - y, i - x)
            if beta < 0.0:
                beta += 2.0 * math.pi
            k = int(beta / width) % n_sectors
            hist[k] += c * c * max(a - b * d, 0.0)
    smooth = np.zeros(n_sectors)
    norm = 2 * l_smooth + 1
    for k in range(n_sectors):
        s = centre_weight * hist[k]
        for i in range(1, l_smooth + 1):
            s += (l_smooth + 1 - i) * (hist[(k + i) % n_sectors] + hist[(k - i) % n_sectors])
        smooth[k] = s / norm
    return smooth


@njit(cache=True)
def vfh_steer(smooth, target_sector, threshold, s_max):
    """Steering sector (float, may be fractional) from a smoothed histogram.

    Candidate valleys are runs of sectors below ``threshold``. If the target
    sector is free and at least ``s_max / 2`` free sectors lie on both of its
    sides, steer straight at it; otherwise take the free sector ``k_n``
    nearest the target, extend the valley away from the target up to
    ``s_max`` sectors to ``k_f``, and steer at their middle. Returns -1 when
    no sector is free.
    """
    n = smooth.shape[0]
    half = s_max // 2
    if smooth[target_sector] < threshold:
        ok = True
        for i in range(1, half + 1):
            if smooth[(target_sector + i) % n] >= threshold or \
                    smooth[(target_sector - i) % n] >= threshold:
                ok = False
                break
        if ok:
            return float(target_sector)
    kn = 0
    side = 0
    for dist in range(0, n // 2 + 1):
        if smooth[(target_sector + dist) % n] < threshold:
            kn = target_sector + dist
            side = 1
            break
        if smooth[(target_sector - dist) % n] < threshold:
            kn = target_sector - dist
            side = -1
            break
    if side == 0:
        return -1.0
    kf = kn
    for _ in range(s_max - 1):
        nxt = kf + side
        if smooth[nxt % n] >= threshold:
            break
        kf = nxt
    return 0.5 * (kn + kf)


@njit(cache=True)
def vfh_run(blocked, sx, sy, gx, gy, robot, hist):
    """Vector field histogram (Borenstein & Koren 1991), eq. 2.7-2.11.

    ``robot`` is a :class:`RobotKernelParams`, ``hist`` a
    :class:`VFHKernelParams`. Returns (outcome code, trajectory).
    """
    n_sectors = int(round(2.0 * math.pi / hist.alpha))  # eq. 2.9
    width = 2.0 * math.pi / n_sectors
    certainty, traj, heading, best_d = _drive_start(blocked, sx, sy, gx, gy, robot)
    last_gain = 0
    for step in range(1, robot.max_steps + 1):
        x, y, arrived = _observe(blocked, certainty, traj, step, gx, gy, robot)
        if arrived:
            return REACHED, traj[:step].copy()
        smooth = polar_histogram(certainty, x, y, robot.window, n_sectors, hist.a, hist.b,
                                 hist.smoothing, hist.centre_weight)
        to_goal = math.atan2(gy - y, gx - x)
        if to_goal < 0.0:
            to_goal += 2.0 * math.pi
        kt = int(to_goal / width) % n_sectors
        k = vfh_steer(smooth, kt, hist.threshold, hist.s_max)
        if k == -1.0:
            return NO_VALLEY, traj[:step].copy()
        want = to_goal if k == float(kt) else (k + 0.5) * width
        code, heading, best_d, last_gain = _drive_step(blocked, traj, step, heading,
                                                       wrap(want - heading), gx, gy, best_d,
                                                       last_gain, robot)
        if code >= 0:
            return code, traj[: step + 1].copy()
    return _drive_end(blocked, traj, gx, gy, robot)

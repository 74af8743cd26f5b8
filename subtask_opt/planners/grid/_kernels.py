"""Numba kernels of the grid planners (arrays and scalars in, arrays out).

Grids arrive as ``blocked`` uint8/bool arrays indexed ``[y, x]``. Moves follow
one rule everywhere: a diagonal step needs both side cells free (no corner
cutting), and a straight segment between cell centres is collision-free when
it touches no *closed* blocked cell square. The two rules agree: a diagonal
step touches the shared corner of its two side cells.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# 8-neighbourhood; the first four are the side steps.
_DX = np.array([1, -1, 0, 0, 1, 1, -1, -1], dtype=np.int64)
_DY = np.array([0, 0, 1, -1, 1, -1, 1, -1], dtype=np.int64)


@njit(cache=True)
def _step_allowed(blocked, x, y, k):
    """Whether the move k of the 8-neighbourhood from free cell (x, y) is allowed."""
    h, w = blocked.shape
    nx = x + _DX[k]
    ny = y + _DY[k]
    if nx < 0 or ny < 0 or nx >= w or ny >= h or blocked[ny, nx]:
        return False
    if k >= 4 and (blocked[y, nx] or blocked[ny, x]):
        return False
    return True


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
def _relax_all(pad, w2, u, d, w_side, w_diag, dist, seen, settled, stamp, nbr, cost):
    """Fill ``nbr``/``cost`` with the allowed, unsettled, improved neighbours of
    ``u`` (padded index, value ``d``), updating ``dist``/``seen``; return how many."""
    m = 0
    for k in range(8):
        sx = _DX[k]
        sy = _DY[k] * w2
        v = u + sx + sy
        if pad[v] or settled[v] == stamp:
            continue
        if k >= 4 and (pad[u + sx] or pad[u + sy]):
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
def _propagate(pad, w2, src, w_side, w_diag, targets, dist, seen, settled, want, stamp, ring):
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
        m = _relax_all(pad, w2, u, dist[u], w_side, w_diag, dist, seen, settled, stamp, nbr, cost)
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
        m = _relax_all(pad, w2, u, dist[u], w_side, w_diag, dist, seen, settled, stamp, nbr, cost)
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
        ring = _propagate(pad, w2, src, w_side, w_diag, none, dist, seen, settled, want, j + 1,
                          ring)
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
def chamfer_field(blocked, gx, gy, w_side, w_diag, targets):
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
    _propagate(pad, w2, (gy + 1) * w2 + gx + 1, w_side, w_diag, ptargets, dist, seen, settled,
               want, 1, ring)
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
        ring = _propagate(pad, w2, pgoals[i], w_side, w_diag, pstarts[i:j], dist, seen, settled,
                          want, stamp, ring)
        for r in range(i, j):
            out[r] = dist[pstarts[r]] if settled[pstarts[r]] == stamp else np.inf
        i = j
    return out


@njit(cache=True)
def descend(blocked, dist, sx, sy, w_side, w_diag):
    """Steepest descent on a chamfer/octile field from (sx, sy) to its zero.

    Each step goes to the allowed neighbour minimising value + step cost, i.e.
    the neighbour the value was propagated from (ties: the lower value, then
    the first in neighbourhood order), so the path realises the field value.
    Returns a (k, 2) int64 array of cells, or an empty one if unreachable.
    """
    h, w = blocked.shape
    if not math.isfinite(dist[sy, sx]):
        return np.zeros((0, 2), dtype=np.int64)
    out = np.empty((h * w + 1, 2), dtype=np.int64)
    x, y = sx, sy
    out[0, 0] = x
    out[0, 1] = y
    k_out = 1
    while dist[y, x] > 0.0 and k_out <= h * w:
        best_total = np.inf
        best_val = np.inf
        bx, by = -1, -1
        for k in range(8):
            if not _step_allowed(blocked, x, y, k):
                continue
            nx = x + _DX[k]
            ny = y + _DY[k]
            val = dist[ny, nx]
            total = val + (w_side if k < 4 else w_diag)
            if total < best_total - 1e-9 or (abs(total - best_total) <= 1e-9 and val < best_val):
                best_total = total
                best_val = val
                bx, by = nx, ny
        if bx < 0 or not best_val < dist[y, x]:
            return np.zeros((0, 2), dtype=np.int64)  # not a valid field
        x, y = bx, by
        out[k_out, 0] = x
        out[k_out, 1] = y
        k_out += 1
    return out[:k_out].copy()


# -- line of sight between cell centres ------------------------------------------------
@njit(cache=True)
def segment_hits(blocked, x0, y0, x1, y1, first_only):
    """Number of blocked cells whose closed square the segment touches.

    Exact integer arithmetic (coordinates doubled and scaled by dx); with
    ``first_only`` it returns 1 at the first blocked cell. Cells outside the
    grid count as blocked.
    """
    h, w = blocked.shape
    if x0 > x1:
        x0, y0, x1, y1 = x1, y1, x0, y0
    dx = x1 - x0
    dy = y1 - y0
    hits = 0
    if dx == 0:
        lo = min(y0, y1)
        hi = max(y0, y1)
        for cy in range(lo, hi + 1):
            if cy < 0 or cy >= h or x0 < 0 or x0 >= w or blocked[cy, x0]:
                hits += 1
                if first_only:
                    return 1
        return hits
    for cx in range(x0, x1 + 1):
        xa = max(2 * x0, 2 * cx - 1)
        xb = min(2 * x1, 2 * cx + 1)
        na = 2 * y0 * dx + dy * (xa - 2 * x0)
        nb = 2 * y0 * dx + dy * (xb - 2 * x0)
        nlo = min(na, nb)
        nhi = max(na, nb)
        cy_lo = -((dx - nlo) // (2 * dx))  # ceil((nlo - dx) / (2 dx))
        cy_hi = (nhi + dx) // (2 * dx)
        for cy in range(cy_lo, cy_hi + 1):
            if cy < 0 or cy >= h or cx < 0 or cx >= w or blocked[cy, cx]:
                hits += 1
                if first_only:
                    return 1
    return hits


@njit(cache=True)
def visibility_field(blocked, gx, gy):
    """Any-angle distance field: Dijkstra on the line-of-sight graph.

    Vertices are the free cell centres, edges join every pair with a
    collision-free straight segment, weighted by its Euclidean length. The
    graph is dense, so the O(n^2) array Dijkstra (no heap) is the right one:
    settle the nearest cell, then relax every unsettled cell it can see.
    Returns the (h, w) field (``inf`` blocked or unreachable).
    """
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
    dist = np.full(n_free, np.inf)
    done = np.zeros(n_free, dtype=np.bool_)
    dist[src] = 0.0
    for _ in range(n_free):
        u = -1
        du = np.inf
        for i in range(n_free):
            if not done[i] and dist[i] < du:
                du = dist[i]
                u = i
        if u < 0:
            break
        done[u] = True
        ux = xs[u]
        uy = ys[u]
        for v in range(n_free):
            if done[v]:
                continue
            ddx = xs[v] - ux
            ddy = ys[v] - uy
            nd = du + math.sqrt(ddx * ddx + ddy * ddy)
            if nd < dist[v] and segment_hits(blocked, ux, uy, xs[v], ys[v], True) == 0:
                dist[v] = nd
    out = np.full((h, w), np.inf)
    for i in range(n_free):
        out[ys[i], xs[i]] = dist[i]
    return out


@njit(cache=True)
def visibility_descend(blocked, dist, sx, sy):
    """Follow an any-angle field from (sx, sy): each jump goes to the visible
    cell of least value among those that realise the current value
    (value + segment length = current value), so the path has the field's
    length and as few waypoints as the field allows."""
    h, w = blocked.shape
    if not math.isfinite(dist[sy, sx]):
        return np.zeros((0, 2), dtype=np.int64)
    out = np.empty((h * w + 1, 2), dtype=np.int64)
    x, y = sx, sy
    out[0, 0] = x
    out[0, 1] = y
    k_out = 1
    while dist[y, x] > 0.0 and k_out <= h * w:
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
                if segment_hits(blocked, x, y, nx, ny, True) == 0:
                    best_val = val
                    bx, by = nx, ny
        if bx < 0:
            return np.zeros((0, 2), dtype=np.int64)
        x, y = bx, by
        out[k_out, 0] = x
        out[k_out, 1] = y
        k_out += 1
    return out[:k_out].copy()


# -- local planners: a simulated robot with a certainty grid ---------------------------
# Outcome codes of vff_run / vfh_run.
REACHED, COLLISION, LOCAL_MINIMUM, OSCILLATION, STEP_LIMIT, NO_VALLEY = range(6)


@njit(cache=True)
def _wrap(angle):
    """Angle in [-pi, pi)."""
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
def _move(blocked, traj, step, heading, speed):
    """Advance one step along ``heading``; return False on a collision."""
    h, w = blocked.shape
    x = traj[step - 1, 0] + speed * math.cos(heading)
    y = traj[step - 1, 1] + speed * math.sin(heading)
    traj[step, 0] = x
    traj[step, 1] = y
    cx = int(math.floor(x + 0.5))
    cy = int(math.floor(y + 0.5))
    return 0 <= cx < w and 0 <= cy < h and not blocked[cy, cx]


@njit(cache=True)
def _stall(traj, step, gx, gy, best_d, last_gain, window, min_gain):
    """Stall test after ``step``: returns (code or -1, best distance, step of last gain).

    A run stalls when the distance to the goal has not improved by
    ``min_gain`` cells for ``window`` steps: a local minimum if the robot
    also stayed within one cell of where it was ``window`` steps ago, an
    oscillation (a loop or back-and-forth) otherwise.
    """
    d = math.hypot(traj[step, 0] - gx, traj[step, 1] - gy)
    if d < best_d - min_gain:
        return -1, d, step
    if step - last_gain >= window:
        back = step - window
        moved = math.hypot(traj[step, 0] - traj[back, 0], traj[step, 1] - traj[back, 1])
        return (LOCAL_MINIMUM if moved < 1.0 else OSCILLATION), best_d, last_gain
    return -1, best_d, last_gain


@njit(cache=True)
def vff_run(blocked, sx, sy, gx, gy, p):
    """Virtual force field (Borenstein & Koren 1989), eq. 2.1-2.6.

    ``p`` = [window radius, Fcr, Fct, Ks, max turn (rad/step), speed
    (cells/step), max steps, goal tolerance, stall window, stall gain,
    certainty increment, certainty max]. Returns (outcome code, trajectory).
    """
    radius, f_cr, f_ct, k_s, max_turn, speed = p[0], p[1], p[2], p[3], p[4], p[5]
    max_steps, tol, s_window, s_gain, c_inc, c_max = int(p[6]), p[7], int(p[8]), p[9], p[10], p[11]
    h, w = blocked.shape
    certainty = np.zeros((h, w))
    traj = np.empty((max_steps + 1, 2))
    traj[0, 0] = sx
    traj[0, 1] = sy
    heading = math.atan2(gy - sy, gx - sx)
    best_d = math.hypot(gx - sx, gy - sy)
    last_gain = 0
    r = int(math.ceil(radius))
    for step in range(1, max_steps + 1):
        x = traj[step - 1, 0]
        y = traj[step - 1, 1]
        if math.hypot(gx - x, gy - y) <= tol:
            return REACHED, traj[:step].copy()
        _sense(blocked, certainty, x, y, radius, c_inc, c_max)
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
                mag = f_cr * c / (d * d)  # eq. 2.1, along the unit vector cell -> robot
                fx += mag * dx / d
                fy += mag * dy / d
        dg = math.hypot(gx - x, gy - y)
        rx = fx + f_ct * (gx - x) / dg  # eq. 2.3, 2.4
        ry = fy + f_ct * (gy - y) / dg
        delta = math.atan2(ry, rx)
        omega = k_s * _wrap(delta - heading)  # eq. 2.5, 2.6
        heading = _wrap(heading + max(-max_turn, min(max_turn, omega)))
        if not _move(blocked, traj, step, heading, speed):
            return COLLISION, traj[: step + 1].copy()
        code, best_d, last_gain = _stall(traj, step, gx, gy, best_d, last_gain, s_window, s_gain)
        if code >= 0:
            return code, traj[: step + 1].copy()
    if math.hypot(gx - traj[max_steps, 0], gy - traj[max_steps, 1]) <= tol:
        return REACHED, traj
    return STEP_LIMIT, traj


@njit(cache=True)
def polar_histogram(certainty, x, y, radius, n_sectors, a, b, l_smooth):
    """Smoothed polar obstacle density around (x, y), eq. 2.7-2.11.

    Each cell within ``radius`` adds ``m = C^2 (a - b d)`` to the sector of
    its direction ``beta`` (eq. 2.7-2.10); the result is smoothed with
    weights 1, 2, ..., l+1, ..., 2, 1 over 2l+1 sectors (eq. 2.11).
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
        s = 0.0
        for i in range(-l_smooth, l_smooth + 1):
            s += (l_smooth + 1 - abs(i)) * hist[(k + i) % n_sectors]
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
def vfh_run(blocked, sx, sy, gx, gy, p):
    """Vector field histogram (Borenstein & Koren 1991), eq. 2.7-2.11.

    ``p`` = [window radius, alpha (rad), a, b, l, threshold, s_max, max turn
    (rad/step), speed, max steps, goal tolerance, stall window, stall gain,
    certainty increment, certainty max]. Returns (outcome code, trajectory).
    """
    radius, alpha, a, b, l_smooth, threshold = p[0], p[1], p[2], p[3], int(p[4]), p[5]
    s_max, max_turn, speed, max_steps = int(p[6]), p[7], p[8], int(p[9])
    tol, s_window, s_gain, c_inc, c_max = p[10], int(p[11]), p[12], p[13], p[14]
    h, w = blocked.shape
    n_sectors = int(round(2.0 * math.pi / alpha))  # eq. 2.9
    width = 2.0 * math.pi / n_sectors
    certainty = np.zeros((h, w))
    traj = np.empty((max_steps + 1, 2))
    traj[0, 0] = sx
    traj[0, 1] = sy
    heading = math.atan2(gy - sy, gx - sx)
    best_d = math.hypot(gx - sx, gy - sy)
    last_gain = 0
    for step in range(1, max_steps + 1):
        x = traj[step - 1, 0]
        y = traj[step - 1, 1]
        if math.hypot(gx - x, gy - y) <= tol:
            return REACHED, traj[:step].copy()
        _sense(blocked, certainty, x, y, radius, c_inc, c_max)
        smooth = polar_histogram(certainty, x, y, radius, n_sectors, a, b, l_smooth)
        to_goal = math.atan2(gy - y, gx - x)
        if to_goal < 0.0:
            to_goal += 2.0 * math.pi
        kt = int(to_goal / width) % n_sectors
        k = vfh_steer(smooth, kt, threshold, s_max)
        if k == -1.0:
            return NO_VALLEY, traj[:step].copy()
        want = to_goal if k == float(kt) else (k + 0.5) * width
        turn = _wrap(want - heading)
        heading = _wrap(heading + max(-max_turn, min(max_turn, turn)))
        if not _move(blocked, traj, step, heading, speed):
            return COLLISION, traj[: step + 1].copy()
        code, best_d, last_gain = _stall(traj, step, gx, gy, best_d, last_gain, s_window, s_gain)
        if code >= 0:
            return code, traj[: step + 1].copy()
    if math.hypot(gx - traj[max_steps, 0], gy - traj[max_steps, 1]) <= tol:
        return REACHED, traj
    return STEP_LIMIT, traj

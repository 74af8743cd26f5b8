"""Numba kernels of the polygon planners: exact segment/polygon predicates,
distances, a dense Dijkstra, and the inertia-weight PSO loop.

Obstacles travel into the kernels flattened: ``verts`` (n, 2) holds every
vertex, polygon ``i`` occupies rows ``offsets[i]:offsets[i + 1]`` in
counter-clockwise order, and ``boxes`` (n_obs, 4) holds each polygon's
bounding box. ``eps`` is an absolute length tolerance (a tiny fraction of the
world's size): distances below it count as contact.

"Touching" (a vertex or an edge of an obstacle lying on a segment) is allowed
by :func:`segment_free`; only entering an obstacle's open interior is not,
so shortest paths that wrap around vertices are free.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.planners._graph_kernels import nearest_unsettled


class PSOConfig(NamedTuple):
    """Kernel parameters of :func:`pso_run` (built by ``PSOParams.kernel_config``)."""

    w_start: float
    w_end: float
    c1: float
    c2: float
    v_max: float
    inertia_iterations: float

# Results of segment_contact.
CONTACT_NONE, CONTACT_TOUCH, CONTACT_CROSS = 0, 1, 2


@njit(cache=True)
def point_segment_distance(px, py, x1, y1, x2, y2):
    """Euclidean distance from (px, py) to the closed segment (x1, y1)-(x2, y2)."""
    dx = x2 - x1
    dy = y2 - y1
    den = dx * dx + dy * dy
    t = 0.0
    if den > 0.0:
        t = ((px - x1) * dx + (py - y1) * dy) / den
        t = min(max(t, 0.0), 1.0)
    return math.hypot(px - (x1 + t * dx), py - (y1 + t * dy))


@njit(cache=True)
def _side(ax, ay, bx, by, cx, cy, eps):
    """Sign of c relative to the line a->b: +1 left, -1 right, 0 within eps of it."""
    lx = bx - ax
    ly = by - ay
    length = math.hypot(lx, ly)
    if length == 0.0:
        return 0
    d = (lx * (cy - ay) - ly * (cx - ax)) / length
    if d > eps:
        return 1
    if d < -eps:
        return -1
    return 0


@njit(cache=True)
def segment_contact(ax, ay, bx, by, cx, cy, dx, dy, eps):
    """How the closed segments ab and cd meet.

    Returns ``CONTACT_CROSS`` (2) when they cross at a single point interior
    to both, ``CONTACT_TOUCH`` (1) for any other common point (an endpoint on
    the other segment, or collinear overlap) and ``CONTACT_NONE`` (0).
    """
    if (max(ax, bx) < min(cx, dx) - eps or max(cx, dx) < min(ax, bx) - eps
            or max(ay, by) < min(cy, dy) - eps or max(cy, dy) < min(ay, by) - eps):
        return CONTACT_NONE
    s1 = _side(ax, ay, bx, by, cx, cy, eps)
    s2 = _side(ax, ay, bx, by, dx, dy, eps)
    s3 = _side(cx, cy, dx, dy, ax, ay, eps)
    s4 = _side(cx, cy, dx, dy, bx, by, eps)
    if s1 * s2 < 0 and s3 * s4 < 0:
        return CONTACT_CROSS
    if (s1 != 0 and s1 == s2) or (s3 != 0 and s3 == s4):
        return CONTACT_NONE
    # Some endpoint lies on the other segment's line: common point iff it lies
    # on the segment itself (or, for collinear segments, the ranges overlap).
    if s1 == 0 and point_segment_distance(cx, cy, ax, ay, bx, by) <= eps:
        return CONTACT_TOUCH
    if s2 == 0 and point_segment_distance(dx, dy, ax, ay, bx, by) <= eps:
        return CONTACT_TOUCH
    if s3 == 0 and point_segment_distance(ax, ay, cx, cy, dx, dy) <= eps:
        return CONTACT_TOUCH
    if s4 == 0 and point_segment_distance(bx, by, cx, cy, dx, dy) <= eps:
        return CONTACT_TOUCH
    return CONTACT_NONE


@njit(cache=True)
def point_in_polygon(px, py, verts, start, stop, eps):
    """Location of (px, py) relative to polygon rows start:stop of ``verts``.

    Returns 1 inside, 0 on the boundary (within eps), -1 outside.
    """
    inside = False
    j = stop - 1
    for i in range(start, stop):
        x1 = verts[j, 0]
        y1 = verts[j, 1]
        x2 = verts[i, 0]
        y2 = verts[i, 1]
        if point_segment_distance(px, py, x1, y1, x2, y2) <= eps:
            return 0
        if (y1 > py) != (y2 > py):
            xc = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
            if px < xc:
                inside = not inside
        j = i
    return 1 if inside else -1


@njit(cache=True)
def obstacle_at(px, py, verts, offsets, boxes, eps):
    """Index of the obstacle whose closed area holds (px, py), or -1."""
    for k in range(offsets.shape[0] - 1):
        if (px < boxes[k, 0] - eps or px > boxes[k, 2] + eps
                or py < boxes[k, 1] - eps or py > boxes[k, 3] + eps):
            continue
        if point_in_polygon(px, py, verts, offsets[k], offsets[k + 1], eps) >= 0:
            return k
    return -1


@njit(cache=True)
def segment_free(px, py, qx, qy, verts, offsets, boxes, bounds, eps):
    """True when segment pq stays in ``bounds`` and enters no obstacle's interior.

    A segment that crosses no edge properly can only pass from outside to
    inside a polygon through a vertex or at its own endpoints; so it is cut at
    every such contact and the midpoint of each piece is tested.

    An obstacle touching the outer boundary leaves a gap of zero width there;
    a segment running along the boundary may not pass through it (touch an
    obstacle anywhere but at its own ends).
    """
    for x, y in ((px, py), (qx, qy)):
        if (x < bounds[0] - eps or x > bounds[2] + eps
                or y < bounds[1] - eps or y > bounds[3] + eps):
            return False
    along_wall = ((abs(px - bounds[0]) <= eps and abs(qx - bounds[0]) <= eps)
                  or (abs(px - bounds[2]) <= eps and abs(qx - bounds[2]) <= eps)
                  or (abs(py - bounds[1]) <= eps and abs(qy - bounds[1]) <= eps)
                  or (abs(py - bounds[3]) <= eps and abs(qy - bounds[3]) <= eps))
    dx = qx - px
    dy = qy - py
    seg_len2 = dx * dx + dy * dy
    seg_len = math.sqrt(seg_len2)
    lox = min(px, qx) - eps
    hix = max(px, qx) + eps
    loy = min(py, qy) - eps
    hiy = max(py, qy) + eps
    ts = np.empty(verts.shape[0] + 2)
    tol = eps * seg_len  # cross products below are distances times seg_len
    for k in range(offsets.shape[0] - 1):
        if boxes[k, 0] > hix or boxes[k, 2] < lox or boxes[k, 1] > hiy or boxes[k, 3] < loy:
            continue
        # the polygon's box wholly on one side of the segment's line: no contact
        c00 = dx * (boxes[k, 1] - py) - dy * (boxes[k, 0] - px)
        c10 = dx * (boxes[k, 1] - py) - dy * (boxes[k, 2] - px)
        c01 = dx * (boxes[k, 3] - py) - dy * (boxes[k, 0] - px)
        c11 = dx * (boxes[k, 3] - py) - dy * (boxes[k, 2] - px)
        if (min(min(c00, c10), min(c01, c11)) > tol
                or max(max(c00, c10), max(c01, c11)) < -tol):
            continue
        start = offsets[k]
        stop = offsets[k + 1]
        ts[0] = 0.0
        ts[1] = 1.0
        n_t = 2
        j = stop - 1
        for i in range(start, stop):
            c = segment_contact(px, py, qx, qy, verts[j, 0], verts[j, 1],
                                verts[i, 0], verts[i, 1], eps)
            if c == CONTACT_CROSS:
                return False
            if seg_len2 > 0.0 and point_segment_distance(
                    verts[i, 0], verts[i, 1], px, py, qx, qy) <= eps:
                t = ((verts[i, 0] - px) * dx + (verts[i, 1] - py) * dy) / seg_len2
                if along_wall and eps < t * seg_len < seg_len - eps:
                    return False
                m = n_t  # insertion keeps ts[:n_t] sorted (a handful of entries)
                while m > 0 and ts[m - 1] > t:
                    ts[m] = ts[m - 1]
                    m -= 1
                ts[m] = t
                n_t += 1
            j = i
        for m in range(n_t - 1):
            t0 = ts[m]
            t1 = ts[m + 1]
            if (t1 - t0) * seg_len <= eps:
                continue
            tm = 0.5 * (t0 + t1)
            loc = point_in_polygon(px + tm * dx, py + tm * dy, verts, start, stop, eps)
            if loc > 0 or (loc == 0 and along_wall):
                return False
        if seg_len2 == 0.0 and point_in_polygon(px, py, verts, start, stop, eps) > 0:
            return False
    return True


@njit(cache=True)
def visibility_matrix(points, verts, offsets, boxes, bounds, eps):
    """(n, n) bool matrix: segment between points i and j is free (diagonal False)."""
    n = points.shape[0]
    vis = np.zeros((n, n), dtype=np.bool_)
    for i in range(n):
        for j in range(i + 1, n):
            ok = segment_free(points[i, 0], points[i, 1], points[j, 0], points[j, 1],
                              verts, offsets, boxes, bounds, eps)
            vis[i, j] = ok
            vis[j, i] = ok
    return vis


@njit(cache=True)
def visible_from(px, py, points, verts, offsets, boxes, bounds, eps):
    """(n,) bool: segment from (px, py) to each of ``points`` is free."""
    n = points.shape[0]
    vis = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        vis[i] = segment_free(px, py, points[i, 0], points[i, 1], verts, offsets, boxes,
                              bounds, eps)
    return vis


@njit(cache=True)
def _clear_of_points(a, b, points, eps):
    """No row of ``points`` other than a and b lies on the segment points[a]-points[b]."""
    ax, ay, bx, by = points[a, 0], points[a, 1], points[b, 0], points[b, 1]
    lox = min(ax, bx) - eps
    hix = max(ax, bx) + eps
    loy = min(ay, by) - eps
    hiy = max(ay, by) + eps
    for m in range(points.shape[0]):
        px = points[m, 0]
        py = points[m, 1]
        if m == a or m == b or px < lox or px > hix or py < loy or py > hiy:
            continue
        if point_segment_distance(px, py, ax, ay, bx, by) <= eps:
            return False
    return True


@njit(cache=True)
def greedy_links(ends, points, verts, offsets, boxes, bounds, eps):
    """Keep candidate links (rows of ``ends``, sorted by length) greedily; return the mask.

    A candidate is kept when it meets no kept link except at a shared end, is
    free (:func:`segment_free`) and passes through no other point of
    ``points`` (so links meet obstacles and each other only at their ends).
    The cheap crossing test runs first: most long candidates fail it.
    """
    n_c = ends.shape[0]
    accepted = np.zeros(n_c, dtype=np.bool_)
    kept = np.empty(n_c, dtype=np.int64)
    n_kept = 0
    # the kept link that last rejected a candidate from each point: it tends to
    # reject that point's next (longer) candidates too, so it is tried first
    blocker = np.full(points.shape[0], -1, dtype=np.int64)
    for k in range(n_c):
        a = ends[k, 0]
        b = ends[k, 1]
        ax, ay, bx, by = points[a, 0], points[a, 1], points[b, 0], points[b, 1]
        hit = -1
        for first in (blocker[a], blocker[b]):
            if first >= 0 and _links_meet(ends, points, k, first, eps):
                hit = first
                break
        if hit >= 0:
            continue
        # many candidates cut through obstacles: the obstacle test (culled by
        # bounding boxes) is cheaper than scanning every kept link
        if not segment_free(ax, ay, bx, by, verts, offsets, boxes, bounds, eps):
            continue
        for m in range(n_kept):
            if _links_meet(ends, points, k, kept[m], eps):
                hit = kept[m]
                break
        if hit >= 0:
            blocker[a] = hit
            blocker[b] = hit
        elif _clear_of_points(a, b, points, eps):
            accepted[k] = True
            kept[n_kept] = k
            n_kept += 1
    return accepted


@njit(cache=True)
def _links_meet(ends, points, i, j, eps):
    """Links i and j (rows of ``ends``) meet other than at a shared end."""
    a = ends[i, 0]
    b = ends[i, 1]
    c = ends[j, 0]
    d = ends[j, 1]
    if a == c or a == d or b == c or b == d:
        return False  # straight links through no other point meet only at the shared end
    return segment_contact(points[a, 0], points[a, 1], points[b, 0], points[b, 1],
                           points[c, 0], points[c, 1], points[d, 0], points[d, 1],
                           eps) != CONTACT_NONE


@njit(cache=True)
def distance_to_edges(px, py, edges):
    """Smallest distance from (px, py) to the segments in rows of ``edges`` (m, 4)."""
    best = np.inf
    for i in range(edges.shape[0]):
        d = point_segment_distance(px, py, edges[i, 0], edges[i, 1], edges[i, 2], edges[i, 3])
        if d < best:
            best = d
    return best


@njit(cache=True)
def self_contact(verts, start, stop, eps):
    """First edge index (relative to start) of a polygon that breaks simplicity, or -1.

    Edge i joins vertex i to vertex i + 1. Non-adjacent edges may not meet at
    all; adjacent edges may only share their common vertex (no fold-back).
    """
    n = stop - start
    for a in range(n):
        a0 = start + a
        a1 = start + (a + 1) % n
        for b in range(a + 1, n):
            b0 = start + b
            b1 = start + (b + 1) % n
            adjacent = b == a + 1 or (a == 0 and b == n - 1)
            if adjacent:
                # the shared vertex and the two far ends: fold-back when the
                # far end of one edge lies on the other edge
                if b == a + 1:
                    far_x, far_y = verts[b1, 0], verts[b1, 1]
                    ox0, oy0, ox1, oy1 = verts[a0, 0], verts[a0, 1], verts[a1, 0], verts[a1, 1]
                    back_x, back_y = verts[a0, 0], verts[a0, 1]
                    bx0, by0, bx1, by1 = verts[b0, 0], verts[b0, 1], verts[b1, 0], verts[b1, 1]
                else:
                    far_x, far_y = verts[b0, 0], verts[b0, 1]
                    ox0, oy0, ox1, oy1 = verts[a0, 0], verts[a0, 1], verts[a1, 0], verts[a1, 1]
                    back_x, back_y = verts[a1, 0], verts[a1, 1]
                    bx0, by0, bx1, by1 = verts[b0, 0], verts[b0, 1], verts[b1, 0], verts[b1, 1]
                if (point_segment_distance(far_x, far_y, ox0, oy0, ox1, oy1) <= eps
                        or point_segment_distance(back_x, back_y, bx0, by0, bx1, by1) <= eps):
                    return a
                continue
            if segment_contact(verts[a0, 0], verts[a0, 1], verts[a1, 0], verts[a1, 1],
                               verts[b0, 0], verts[b0, 1], verts[b1, 0], verts[b1, 1],
                               eps) != CONTACT_NONE:
                return a
    return -1


@njit(cache=True)
def polygons_meet(verts, s1, e1, s2, e2, eps):
    """True when two simple polygons share any point (edges meet or one contains the other)."""
    j = e1 - 1
    for i in range(s1, e1):
        m = e2 - 1
        for k in range(s2, e2):
            if segment_contact(verts[j, 0], verts[j, 1], verts[i, 0], verts[i, 1],
                               verts[m, 0], verts[m, 1], verts[k, 0], verts[k, 1],
                               eps) != CONTACT_NONE:
                return True
            m = k
        j = i
    if point_in_polygon(verts[s1, 0], verts[s1, 1], verts, s2, e2, eps) >= 0:
        return True
    return point_in_polygon(verts[s2, 0], verts[s2, 1], verts, s1, e1, eps) >= 0


@njit(cache=True)
def dijkstra_dense(weights, source, target):
    """Shortest path on a dense weight matrix (inf = no edge).

    Returns (distance to target, predecessor array); O(n^2), which beats a heap
    for the few hundred nodes of these graphs.
    """
    n = weights.shape[0]
    dist = np.full(n, np.inf)
    prev = np.full(n, -1, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    dist[source] = 0.0
    for _ in range(n):
        u = nearest_unsettled(dist, done)
        if u < 0 or u == target:
            break
        done[u] = True
        for v in range(n):
            w = weights[u, v]
            if not done[v] and w < np.inf and dist[u] + w < dist[v]:
                dist[v] = dist[u] + w
                prev[v] = u
    return dist[target], prev


@njit(cache=True)
def crossing_path_length(t, links, start, goal):
    """Length of start -> point on link k at parameter t[k] (k = 0..) -> goal."""
    x0 = start[0]
    y0 = start[1]
    total = 0.0
    for k in range(t.shape[0]):
        x1 = links[k, 0] + t[k] * (links[k, 2] - links[k, 0])
        y1 = links[k, 1] + t[k] * (links[k, 3] - links[k, 1])
        total += math.hypot(x1 - x0, y1 - y0)
        x0 = x1
        y0 = y1
    return total + math.hypot(goal[0] - x0, goal[1] - y0)


@njit(cache=True)
def pso_run(x, v, pbest, pbest_cost, gbest, gbest_cost, counters, links, start, goal,
            cfg, rng, n_gens, stall_limit, target, hist_best, hist_mean):
    """Run up to ``n_gens`` inertia-weight PSO iterations in place; return how many ran.

    Each particle is one parameter in [0, 1] per crossed link. ``cfg`` is a
    :class:`PSOConfig`; the inertia weight falls linearly from w_start to
    w_end over inertia_iterations iterations (Shi & Eberhart). ``counters`` =
    (iteration, iteration of last improvement).
    """
    n_part, dim = x.shape
    w_start = cfg.w_start
    w_end = cfg.w_end
    c1 = cfg.c1
    c2 = cfg.c2
    v_max = cfg.v_max
    horizon = cfg.inertia_iterations
    ran = 0
    for step in range(n_gens):
        if gbest_cost[0] <= target or counters[0] - counters[1] >= stall_limit:
            break
        w = w_start - (w_start - w_end) * min(counters[0] / horizon, 1.0)
        total = 0.0
        for i in range(n_part):
            for d in range(dim):
                r1 = rng.random()
                r2 = rng.random()
                vel = (w * v[i, d] + c1 * r1 * (pbest[i, d] - x[i, d])
                       + c2 * r2 * (gbest[d] - x[i, d]))
                vel = min(max(vel, -v_max), v_max)
                pos = x[i, d] + vel
                if pos < 0.0:
                    pos = 0.0
                    vel = 0.0
                elif pos > 1.0:
                    pos = 1.0
                    vel = 0.0
                v[i, d] = vel
                x[i, d] = pos
            cost = crossing_path_length(x[i], links, start, goal)
            total += cost
            if cost < pbest_cost[i]:
                pbest_cost[i] = cost
                pbest[i, :] = x[i]
        counters[0] += 1
        i_best = np.argmin(pbest_cost)
        if pbest_cost[i_best] < gbest_cost[0]:
            gbest_cost[0] = pbest_cost[i_best]
            gbest[:] = pbest[i_best]
            counters[1] = counters[0]
        hist_best[step] = gbest_cost[0]
        hist_mean[step] = total / n_part
        ran += 1
    return ran

"""Numba kernels of the AGV simulation and of the quadtree.

Cells follow the grid convention: ``occ[y, x]`` (``True`` = blocked), the
centre of cell ``(x, y)`` at the point ``(x, y)``, the cell covering the closed
square ``[x - 0.5, x + 0.5] x [y - 0.5, y + 0.5]``.

Line of sight has one rule in the whole package: a segment is blocked when it
touches the *closed* square of a blocked cell (or of a cell outside the grid).
The grid family's exact integer kernel
(:func:`subtask_opt.planners.grid._kernels.segment_hits`) applies it to
segments between cell centres; :func:`tree_segment_free` applies the same rule
to segments with any end points, by descending the quadtree (the AGV drifts
off cell centres). A test checks that both agree on every segment between
cell centres. The AGV's routes also keep a clearance from walls: with
``clearance > 0`` a segment is blocked when it comes within that distance of a
blocked square (:func:`segment_near_box`); 0 is the rule above.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class Motion(NamedTuple):
    """How the AGV is rolled forward by the t-second look-ahead.

    Attributes:
        v0: speed now (cells/s).
        v_target: speed it accelerates or brakes towards.
        a_max: acceleration limit (cells/s^2).
        dt: step of the look-ahead (s).
        steps: number of steps (the time factor is ``steps * dt``).
    """

    v0: float
    v_target: float
    a_max: float
    dt: float
    steps: int


@njit(cache=True)
def _clip(num, den, t0n, t0d, t1n, t1d):
    """One Liang-Barsky half-plane ``den * t <= num`` on the interval
    [t0n/t0d, t1n/t1d] (denominators > 0); fractions are compared by
    cross-multiplication so half-integer inputs stay exact."""
    if den == 0.0:
        if num < 0.0:
            return False, t0n, t0d, t1n, t1d
        return True, t0n, t0d, t1n, t1d
    if den > 0.0:  # t <= num / den: lowers t1
        if num * t1d < t1n * den:
            t1n, t1d = num, den
    else:  # t >= num / den = (-num) / (-den): raises t0
        if (-num) * t0d > t0n * (-den):
            t0n, t0d = -num, -den
    return t0n * t1d <= t1n * t0d, t0n, t0d, t1n, t1d


@njit(cache=True)
def segment_meets_box(x0, y0, x1, y1, lo_x, lo_y, hi_x, hi_y):
    """Whether the segment (x0, y0)-(x1, y1) meets the closed box."""
    dx = x1 - x0
    dy = y1 - y0
    t0n, t0d, t1n, t1d = 0.0, 1.0, 1.0, 1.0
    ok, t0n, t0d, t1n, t1d = _clip(x0 - lo_x, -dx, t0n, t0d, t1n, t1d)
    if not ok:
        return False
    ok, t0n, t0d, t1n, t1d = _clip(hi_x - x0, dx, t0n, t0d, t1n, t1d)
    if not ok:
        return False
    ok, t0n, t0d, t1n, t1d = _clip(y0 - lo_y, -dy, t0n, t0d, t1n, t1d)
    if not ok:
        return False
    ok, t0n, t0d, t1n, t1d = _clip(hi_y - y0, dy, t0n, t0d, t1n, t1d)
    return ok


@njit(cache=True)
def _point_box_dist2(px, py, lo_x, lo_y, hi_x, hi_y):
    """Squared distance from a point to the closed box (0 inside)."""
    dx = max(lo_x - px, 0.0, px - hi_x)
    dy = max(lo_y - py, 0.0, py - hi_y)
    return dx * dx + dy * dy


@njit(cache=True)
def _point_segment_dist2(px, py, x0, y0, x1, y1):
    """Squared distance from a point to the segment (x0, y0)-(x1, y1)."""
    dx = x1 - x0
    dy = y1 - y0
    den = dx * dx + dy * dy
    f = 0.0
    if den > 0.0:
        f = min(1.0, max(0.0, ((px - x0) * dx + (py - y0) * dy) / den))
    ex = x0 + f * dx - px
    ey = y0 + f * dy - py
    return ex * ex + ey * ey


@njit(cache=True)
def segment_near_box(x0, y0, x1, y1, lo_x, lo_y, hi_x, hi_y, clearance):
    """Whether the segment comes within ``clearance`` of the closed box
    (distance <= clearance; with 0, whether it meets the box, exactly).

    Two disjoint convex sets are closest between a vertex of one and the
    other, so the distance is the least of the end points' distances to the
    box and the box corners' distances to the segment.
    """
    if clearance <= 0.0:
        return segment_meets_box(x0, y0, x1, y1, lo_x, lo_y, hi_x, hi_y)
    if not segment_meets_box(x0, y0, x1, y1, lo_x - clearance, lo_y - clearance,
                             hi_x + clearance, hi_y + clearance):
        return False
    if segment_meets_box(x0, y0, x1, y1, lo_x, lo_y, hi_x, hi_y):
        return True
    c2 = clearance * clearance
    if _point_box_dist2(x0, y0, lo_x, lo_y, hi_x, hi_y) <= c2 \
            or _point_box_dist2(x1, y1, lo_x, lo_y, hi_x, hi_y) <= c2:
        return True
    return (_point_segment_dist2(lo_x, lo_y, x0, y0, x1, y1) <= c2
            or _point_segment_dist2(hi_x, lo_y, x0, y0, x1, y1) <= c2
            or _point_segment_dist2(lo_x, hi_y, x0, y0, x1, y1) <= c2
            or _point_segment_dist2(hi_x, hi_y, x0, y0, x1, y1) <= c2)


@njit(cache=True)
def tree_segment_free(nodes, children, width, height, x0, y0, x1, y1, clearance):
    """Whether a segment keeps more than ``clearance`` from every blocked
    quadtree leaf (with 0: touches only white leaves).

    ``nodes`` (n, 5): x0, y0, size, colour (0 white, 1 black, 2 grey), depth;
    ``children`` (n, 4): child indices, -1 where none (a leaf, or a quarter
    wholly outside the grid). The cells outside the grid count as blocked: a
    segment within ``clearance`` of the grid's border line (or reaching it)
    is blocked.
    """
    lo = -0.5 + clearance
    if min(x0, x1) <= lo or min(y0, y1) <= lo or max(x0, x1) >= width - 0.5 - clearance \
            or max(y0, y1) >= height - 0.5 - clearance:
        return False
    stack = np.empty(4 * 64 + 4, dtype=np.int64)
    stack[0] = 0
    n = 1
    while n > 0:
        n -= 1
        i = stack[n]
        nx = nodes[i, 0]
        ny = nodes[i, 1]
        size = nodes[i, 2]
        if not segment_near_box(x0, y0, x1, y1, nx - 0.5, ny - 0.5, nx + size - 0.5,
                                ny + size - 0.5, clearance):
            continue
        colour = nodes[i, 3]
        if colour == 0:
            continue
        if colour == 1 or children[i, 0] < 0 and children[i, 1] < 0 \
                and children[i, 2] < 0 and children[i, 3] < 0:
            return False  # black, or a grey leaf at the finest size (not routable)
        for q in range(4):
            c = children[i, q]
            if c >= 0:
                stack[n] = c
                n += 1
    return True


@njit(cache=True)
def point_on_polyline(pts, cum, s):
    """Point at arc length ``s`` (clamped) along the polyline ``pts``."""
    n = pts.shape[0]
    if s <= 0.0 or n == 1:
        return pts[0, 0], pts[0, 1]
    if s >= cum[n - 1]:
        return pts[n - 1, 0], pts[n - 1, 1]
    i = 1
    while cum[i] < s:
        i += 1
    seg = cum[i] - cum[i - 1]
    f = (s - cum[i - 1]) / seg if seg > 0 else 0.0
    return (pts[i - 1, 0] + f * (pts[i, 0] - pts[i - 1, 0]),
            pts[i - 1, 1] + f * (pts[i, 1] - pts[i - 1, 1]))


@njit(cache=True)
def predict_min_separation(pts, cum, motion, obs_pos, obs_vel):
    """The t-second look-ahead of the collision check.

    The AGV moves along its path ahead (``pts``, cumulative lengths ``cum``)
    as :class:`Motion` says; each obstacle keeps the velocity estimated from
    its last two positions. Returns ``(min distance, index of that obstacle,
    step of it)`` over the time from step 1 to step ``motion.steps``,
    continuous in between: during a step both move straight, and the
    closest approach of two straight motions is found in closed form (a
    pass between two samples is not missed). Index -1 when there is no
    obstacle.
    """
    best = np.inf
    best_j = -1
    best_k = -1
    s = 0.0
    v = motion.v0
    dt = motion.dt
    m = obs_pos.shape[0]
    qx = 0.0
    qy = 0.0
    for k in range(1, motion.steps + 1):
        if v < motion.v_target:
            v = min(v + motion.a_max * dt, motion.v_target)
        else:
            v = max(v - motion.a_max * dt, motion.v_target)
        s += v * dt
        px, py = point_on_polyline(pts, cum, s)
        t = k * dt
        for j in range(m):
            dx = px - (obs_pos[j, 0] + obs_vel[j, 0] * t)
            dy = py - (obs_pos[j, 1] + obs_vel[j, 1] * t)
            if k > 1:  # relative motion from the last step's (ex, ey) to (dx, dy)
                ex = qx - (obs_pos[j, 0] + obs_vel[j, 0] * (t - dt))
                ey = qy - (obs_pos[j, 1] + obs_vel[j, 1] * (t - dt))
                d = math.sqrt(_point_segment_dist2(0.0, 0.0, ex, ey, dx, dy))
            else:
                d = math.sqrt(dx * dx + dy * dy)
            if d < best:
                best = d
                best_j = j
                best_k = k
        qx = px
        qy = py
    return best, best_j, best_k

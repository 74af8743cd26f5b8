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
cell centres.
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
def tree_segment_free(nodes, children, width, height, x0, y0, x1, y1):
    """Whether a segment touches only white quadtree leaves.

    ``nodes`` (n, 5): x0, y0, size, colour (0 white, 1 black, 2 grey), depth;
    ``children`` (n, 4): child indices, -1 where none (a leaf, or a quarter
    wholly outside the grid). A segment reaching the grid's border line or
    beyond is blocked, as the cells outside count as blocked.
    """
    lo = -0.5
    if min(x0, x1) <= lo or min(y0, y1) <= lo or max(x0, x1) >= width - 0.5 \
            or max(y0, y1) >= height - 0.5:
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
        if not segment_meets_box(x0, y0, x1, y1, nx - 0.5, ny - 0.5, nx + size - 0.5,
                                 ny + size - 0.5):
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
    step of it)`` over steps 1..``motion.steps`` (index -1 when there is no
    obstacle).
    """
    best = np.inf
    best_j = -1
    best_k = -1
    s = 0.0
    v = motion.v0
    dt = motion.dt
    m = obs_pos.shape[0]
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
            d = math.sqrt(dx * dx + dy * dy)
            if d < best:
                best = d
                best_j = j
                best_k = k
    return best, best_j, best_k

"""Numba kernels of the AGV simulation and the quadtree planner.

Cells follow the grid convention: ``occ[y, x]`` (``True`` = blocked), the
centre of cell ``(x, y)`` at the point ``(x, y)``, the cell covering the closed
square ``[x - 0.5, x + 0.5] x [y - 0.5, y + 0.5]``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def segment_free(occ, x0, y0, x1, y1):
    """Whether the segment (x0, y0)-(x1, y1) touches no blocked cell.

    Conservative: a cell counts as touched when its closed square meets the
    segment, so grazing the corner of a blocked cell is not free. Points
    outside the grid count as blocked.
    """
    h, w = occ.shape
    if x0 > x1:
        x0, y0, x1, y1 = x1, y1, x0, y0
    i_lo = int(math.ceil(x0 - 0.5))
    i_hi = int(math.floor(x1 + 0.5))
    for i in range(i_lo, i_hi + 1):
        if x1 == x0:
            ya, yb = y0, y1
        else:
            xa = max(x0, i - 0.5)
            xb = min(x1, i + 0.5)
            ya = y0 + (xa - x0) * (y1 - y0) / (x1 - x0)
            yb = y0 + (xb - x0) * (y1 - y0) / (x1 - x0)
        if ya > yb:
            ya, yb = yb, ya
        j_lo = int(math.ceil(ya - 0.5))
        j_hi = int(math.floor(yb + 0.5))
        for j in range(j_lo, j_hi + 1):
            if i < 0 or i >= w or j < 0 or j >= h:
                return False
            if occ[j, i]:
                return False
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
def predict_min_separation(pts, cum, v0, v_target, a_max, dt, steps, obs_pos, obs_vel):
    """The t-second look-ahead of the collision check.

    The AGV moves along its path ahead (``pts``, cumulative lengths ``cum``)
    from speed ``v0`` towards ``v_target`` with acceleration ``a_max``; each
    obstacle keeps the velocity estimated from its last two positions. Returns
    ``(min distance, index of that obstacle, step of it)`` over steps
    1..``steps`` of ``dt`` (index -1 when there is no obstacle).
    """
    best = np.inf
    best_j = -1
    best_k = -1
    s = 0.0
    v = v0
    m = obs_pos.shape[0]
    for k in range(1, steps + 1):
        if v < v_target:
            v = min(v + a_max * dt, v_target)
        else:
            v = max(v - a_max * dt, v_target)
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

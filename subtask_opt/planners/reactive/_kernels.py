"""Numba kernels of the reactive navigators: unicycle arcs, ray casting, scan prediction.

Arrays and scalars in, arrays out; the Python wrappers in :mod:`.sonar`,
:mod:`.fuzzy_nav` and :mod:`.reactive_sim` validate and unpack.
Edges are ``(m, 4)`` rows ``x1, y1, x2, y2``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from subtask_opt.planners.polygon._kernels import point_segment_distance as _point_segment


@njit(cache=True)
def _ray_segment(ox, oy, dx, dy, x1, y1, x2, y2):
    """Distance along the unit ray (o, d) to segment (x1,y1)-(x2,y2), or inf."""
    ex = x2 - x1
    ey = y2 - y1
    den = dx * ey - dy * ex
    if abs(den) < 1e-15:
        return np.inf
    wx = x1 - ox
    wy = y1 - oy
    t = (wx * ey - wy * ex) / den      # along the ray
    s = (wx * dy - wy * dx) / den      # along the segment
    if t >= 0.0 and -1e-12 <= s <= 1.0 + 1e-12:
        return t
    return np.inf


@njit(cache=True)
def cast_rays(edges, ox, oy, angles, max_range):
    """Range along each world-frame direction in ``angles`` from (ox, oy), capped at max_range."""
    n = angles.shape[0]
    out = np.empty(n)
    for k in range(n):
        dx = math.cos(angles[k])
        dy = math.sin(angles[k])
        best = max_range
        for e in range(edges.shape[0]):
            t = _ray_segment(ox, oy, dx, dy, edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3])
            if t < best:
                best = t
        out[k] = best
    return out


@njit(cache=True)
def predict_scans(ranges, beam_angles, spacing, max_range, overlap, cand, mid):
    """Scans predicted at candidate poses by a rigid transform of the current scan.

    Every echo ``k`` (range < max_range) becomes a wall perpendicular to beam k,
    centred on the echo and as wide as the beam's angular sector (times
    ``overlap``); everything else is open space. All coordinates are in the
    current robot frame.

    Args:
        ranges: (n,) current readings; beam_angles: (n,) sensor angles (robot frame);
            spacing: angular width of one beam's sector (rad).
        cand: (c, 3) candidate poses x, y, heading; mid: (c, 2) arc midpoints.

    Returns:
        pred: (c, n) predicted readings; clearance: (c,) smallest distance from the
        candidate or its arc midpoint to any predicted wall (inf if none).
    """
    n = ranges.shape[0]
    c = cand.shape[0]
    half = math.tan(0.5 * min(spacing, 2.0)) * overlap
    walls = np.empty((n, 4))
    m = 0
    for k in range(n):
        r = ranges[k]
        if r < max_range:
            ca = math.cos(beam_angles[k])
            sa = math.sin(beam_angles[k])
            w = r * half
            cx = r * ca
            cy = r * sa
            walls[m, 0] = cx + w * sa
            walls[m, 1] = cy - w * ca
            walls[m, 2] = cx - w * sa
            walls[m, 3] = cy + w * ca
            m += 1
    pred = np.full((c, n), max_range)
    clearance = np.full(c, np.inf)
    for i in range(c):
        ox = cand[i, 0]
        oy = cand[i, 1]
        for j in range(n):
            a = cand[i, 2] + beam_angles[j]
            dx = math.cos(a)
            dy = math.sin(a)
            best = max_range
            for e in range(m):
                t = _ray_segment(ox, oy, dx, dy, walls[e, 0], walls[e, 1], walls[e, 2], walls[e, 3])
                if t < best:
                    best = t
            pred[i, j] = best
        best = np.inf
        for e in range(m):
            d1 = _point_segment(ox, oy, walls[e, 0], walls[e, 1], walls[e, 2], walls[e, 3])
            d2 = _point_segment(mid[i, 0], mid[i, 1], walls[e, 0], walls[e, 1], walls[e, 2],
                                walls[e, 3])
            best = min(best, d1, d2)
        clearance[i] = best
    return pred, clearance


@njit(cache=True)
def arc(x, y, th, v, omega, dt):
    """Unicycle pose after dt from (x, y, th) with speed v and turn rate omega (exact arc)."""
    half = 0.5 * omega * dt
    # sin(h)/h is the chord factor of the arc; its limit at 0 is 1
    chord = v * dt * (math.sin(half) / half if abs(half) > 1e-12 else 1.0)
    mid = th + half
    heading = (th + 2.0 * half + math.pi) % (2.0 * math.pi) - math.pi
    return x + chord * math.cos(mid), y + chord * math.sin(mid), heading


@njit(cache=True)
def arc_poses(x, y, th, v, omega, dt):
    """Poses (n, 3) reached from (x, y, th) with each command (v[i], omega[i]) over dt."""
    out = np.empty((v.shape[0], 3))
    for i in range(v.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = arc(x, y, th, v[i], omega[i], dt)
    return out

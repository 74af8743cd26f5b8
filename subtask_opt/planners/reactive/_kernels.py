"""Numba kernels of the reactive navigators: unicycle arcs, ray casting, scan prediction.

Arrays and scalars in, arrays out; the Python wrappers in :mod:`.sonar`,
:mod:`.fuzzy`, :mod:`.unicycle` and :mod:`.simulation` validate and unpack.
Edges are ``(m, 4)`` rows ``x1, y1, x2, y2``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.planners.polygon._kernels import distance_to_edges
from subtask_opt.planners.polygon._kernels import point_segment_distance as _point_segment


class RingParams(NamedTuple):
    """The sonar ring as :func:`predict_scans` takes it."""

    spacing: float      # angular width of one beam's sector (rad)
    max_range: float    # sensing range
    overlap: float      # predicted wall width relative to the sector


class SweepParams(NamedTuple):
    """How :func:`swept_clearance` checks a step."""

    radius: float       # body radius
    n_samples: int      # evenly spaced pieces to start from (>= 1)
    tol: float          # shortest piece that is still split (> 0)


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
def predict_scans(ranges, beam_angles, ring, cand, mid):
    """Scans predicted at candidate poses by a rigid transform of the current scan.

    Every echo ``k`` (range < max_range) becomes a wall perpendicular to beam k,
    centred on the echo and as wide as the beam's angular sector (times
    ``overlap``); everything else is open space. All coordinates are in the
    current robot frame.

    Args:
        ranges: (n,) current readings; beam_angles: (n,) sensor angles (robot frame);
        ring: :class:`RingParams`.
        cand: (c, 3) candidate poses x, y, heading; mid: (c, 2) arc midpoints.

    Returns:
        pred: (c, n) predicted readings; clearance: (c,) smallest distance from the
        candidate or its arc midpoint to any predicted wall (inf if none).
    """
    max_range = ring.max_range
    n = ranges.shape[0]
    c = cand.shape[0]
    half = math.tan(0.5 * min(ring.spacing, 2.0)) * ring.overlap
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


@njit(cache=True)
def _clearance_at(x, y, th, v, omega, dt, f, edges):
    """Distance from the centre at fraction ``f`` of the step to the nearest edge."""
    px, py, _ = arc(x, y, th, v, omega, f * dt)
    return distance_to_edges(px, py, edges)


@njit(cache=True)
def _contact(x, y, th, v, omega, dt, edges, radius, a, b, tol):
    """Bisect [a, b] (free at a, inside at b) down to ``tol`` of arc length; the
    fraction returned is inside the body's reach (at most ``tol`` past the contact)."""
    length = abs(v) * dt
    for _ in range(200):
        if length * (b - a) <= tol:
            break
        m = 0.5 * (a + b)
        if _clearance_at(x, y, th, v, omega, dt, m, edges) < radius:
            b = m
        else:
            a = m
    return b


@njit(cache=True)
def swept_clearance(x, y, th, v, omega, dt, edges, sweep):
    """Certified collision test of the body circle swept along one unicycle arc.

    The centre's distance to the walls is 1-Lipschitz in arc length, so on a
    piece of arc of length L whose ends are at distances a and b no point is
    nearer than ``(a + b - L) / 2``. Pieces whose bound stays at or above
    ``radius`` are certified free; the others are halved (earliest first) until
    a sample lies inside the body (a collision, located by bisection) or the
    piece is shorter than ``tol`` (a graze of at most ``tol / 2``, counted as free).

    Args:
        x, y, th: start pose; v, omega: command held for ``dt``.
        edges: (m, 4) walls.
        sweep: :class:`SweepParams` (body radius, initial pieces, tolerance).

    Returns:
        ``(min_clearance, hit, fraction)``: the smallest sampled clearance
        (distance minus radius), whether the body meets a wall, and the
        fraction of the step at which it first touches (to ``tol``; 1.0 if never).
    """
    radius = sweep.radius
    n_samples = sweep.n_samples
    tol = sweep.tol
    length = abs(v) * dt
    d0 = _clearance_at(x, y, th, v, omega, dt, 0.0, edges)
    min_clear = d0 - radius
    if d0 < radius:
        return min_clear, True, 0.0
    cap = 64 + 2 * n_samples
    sa = np.empty(cap)
    sb = np.empty(cap)
    da = np.empty(cap)
    db = np.empty(cap)
    top = 0
    # the initial pieces, pushed last-first so that the earliest is popped first
    d_next = _clearance_at(x, y, th, v, omega, dt, 1.0, edges)
    for i in range(n_samples, 0, -1):
        a = (i - 1) / n_samples
        d_a = d0 if i == 1 else _clearance_at(x, y, th, v, omega, dt, a, edges)
        sa[top], sb[top], da[top], db[top] = a, i / n_samples, d_a, d_next
        top += 1
        d_next = d_a
    for i in range(top):
        min_clear = min(min_clear, db[i] - radius)
    while top > 0:
        top -= 1
        a = sa[top]
        b = sb[top]
        d_a = da[top]
        d_b = db[top]
        if d_b < radius:  # every piece before this one is free: the first contact is here
            return min_clear, True, _contact(x, y, th, v, omega, dt, edges, radius, a, b, tol)
        piece = length * (b - a)
        if 0.5 * (d_a + d_b - piece) >= radius or piece < tol:
            continue
        m = 0.5 * (a + b)
        d_m = _clearance_at(x, y, th, v, omega, dt, m, edges)
        min_clear = min(min_clear, d_m - radius)
        if top + 2 > cap:  # depth-first: the stack holds about log2(length / tol) pieces
            cap *= 2
            sa2 = np.empty(cap)
            sb2 = np.empty(cap)
            da2 = np.empty(cap)
            db2 = np.empty(cap)
            sa2[:top] = sa[:top]
            sb2[:top] = sb[:top]
            da2[:top] = da[:top]
            db2[:top] = db[:top]
            sa, sb, da, db = sa2, sb2, da2, db2
        sa[top], sb[top], da[top], db[top] = m, b, d_m, d_b
        top += 1
        sa[top], sb[top], da[top], db[top] = a, m, d_a, d_m
        top += 1
    return min_clear, False, 1.0

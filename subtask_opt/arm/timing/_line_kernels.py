"""Numba kernels of the ``line`` time model: time-optimal traversal of a straight line.

The tip moves from ``p0`` to ``p1`` along ``p(s) = p0 + s u`` (``u`` the unit
direction, ``0 <= s <= d``) on one elbow branch. With the path velocity
``x = s_dot**2`` and the path acceleration ``w = s_ddot``, every limit is linear
in ``(w, x)`` at a point of the path:

* joint k:       ``|q_k'(s) s_dot| <= v_k``  and  ``|q_k'(s) w + q_k''(s) x| <= a_k``
* translation:   ``s_dot <= Kv``  and  ``|w| <= Ka`` (a straight line has no
  normal acceleration)
* tool rotation: ``|phi'(s) s_dot| <= Kw``  and  ``|phi'(s) w + phi''(s) x| <= Kw_dot``

(``'`` is d/ds; ``q'`` and ``q''`` come from the analytic Jacobian of the arm.)
The path is cut into M intervals (``delta_i`` long, denser near the ends, see
:func:`path_grid`) with a constant ``w`` on each, so that
``x_{i+1} = x_i + 2 delta_i w_i``. Each interval's limits are enforced at both of
its ends (the "interpolation" scheme of TOPP-RA), which keeps the executed
trajectory within the limits between the grid points up to O(delta^2).
The time-optimal profile then follows from two passes (Pham & Pham's TOPP-RA
reachability analysis, in closed form because there is one path coordinate):

1. backward: the largest controllable ``x`` at each grid point, from ``x_M = 0``;
2. forward: from ``x_0 = 0``, the largest ``w`` that stays controllable.

``status`` codes: 0 feasible, 1 the line leaves the reachable annulus (inner
disc or beyond the reach), 2 it passes a joint limit (or arrives at another
representative of the goal configuration), 3 it passes a singularity where the
limits force the arm to stop.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from subtask_opt.arm._kinematics_kernels import (
    K_A1,
    K_A2,
    K_BX,
    K_BY,
    K_L1,
    K_L2,
    K_LO1,
    K_LO2,
    K_S1,
    K_S2,
    K_UP1,
    K_UP2,
    TWO_PI,
    ik_point,
)

LINE_OK, LINE_ANNULUS, LINE_JOINT_LIMIT, LINE_SINGULAR = 0, 1, 2, 3
# |sin(elbow angle)| below this is a singular configuration (the rim or the inner disc).
_SINGULAR = 1e-9
# Slack on joint limits and on matching the goal configuration (rad).
_QTOL = 1e-7


# Share of the grid spaced uniformly; the rest is spaced as a cosine, densest at the
# ends, where the arm starts from rest and where a subtask near the rim makes the
# joint speeds change fastest (the distance to the base is largest at an end).
_UNIFORM_SHARE = 0.5


@njit(cache=True)
def path_grid(d, m):
    """M + 1 path coordinates from 0 to d, uniform blended with cosine clustering."""
    sg = np.empty(m + 1)
    for g in range(m + 1):
        u = g / m
        clustered = 0.5 * (1.0 - math.cos(math.pi * u))
        sg[g] = d * (_UNIFORM_SHARE * u + (1.0 - _UNIFORM_SHARE) * clustered)
    sg[0] = 0.0
    sg[m] = d
    return sg


@njit(cache=True)
def path_derivatives(kin, q1, q2, ux, uy, out):
    """d/ds and d2/ds2 of the joints and of the tool angle along direction (ux, uy).

    Writes ``out[0:2] = q'``, ``out[2:4] = q''``, ``out[4] = phi'``,
    ``out[5] = phi''``; returns False at a singular configuration.
    """
    l1 = kin[K_L1]
    l2 = kin[K_L2]
    th1 = kin[K_A1] + kin[K_S1] * q1
    th12 = th1 + kin[K_A2] + kin[K_S2] * q2
    s1 = math.sin(th1)
    c1 = math.cos(th1)
    s12 = math.sin(th12)
    c12 = math.cos(th12)
    # p' = A (th1', th12')  with  A = [[-l1 s1, -l2 s12], [l1 c1, l2 c12]]
    det = l1 * l2 * math.sin(th12 - th1)
    if abs(math.sin(th12 - th1)) < _SINGULAR:
        return False
    d1 = (l2 * c12 * ux + l2 * s12 * uy) / det
    d12 = (-l1 * c1 * ux - l1 * s1 * uy) / det
    # p'' = 0 = A (th1'', th12'') + c
    cx = -l1 * c1 * d1 * d1 - l2 * c12 * d12 * d12
    cy = -l1 * s1 * d1 * d1 - l2 * s12 * d12 * d12
    dd1 = -(l2 * c12 * cx + l2 * s12 * cy) / det
    dd12 = -(-l1 * c1 * cx - l1 * s1 * cy) / det
    out[0] = kin[K_S1] * d1
    out[1] = kin[K_S2] * (d12 - d1)
    out[2] = kin[K_S1] * dd1
    out[3] = kin[K_S2] * (dd12 - dd1)
    out[4] = d12
    out[5] = dd12
    return True


@njit(cache=True)
def _follow(kin, x, y, branch, prev0, prev1, out):
    """IK on ``branch`` continued from (prev0, prev1): no 2 pi jumps. Returns a status."""
    st = ik_point(kin, x, y, branch, out)
    if st == 1:
        return LINE_ANNULUS
    out[0] += TWO_PI * round((prev0 - out[0]) / TWO_PI)
    out[1] += TWO_PI * round((prev1 - out[1]) / TWO_PI)
    if not (kin[K_LO1] - _QTOL <= out[0] <= kin[K_UP1] + _QTOL
            and kin[K_LO2] - _QTOL <= out[1] <= kin[K_UP2] + _QTOL):
        return LINE_JOINT_LIMIT
    return LINE_OK


@njit(cache=True)
def line_geometry(kin, p0, p1, branch, q_start, q_end, m):
    """Joint path and its derivatives at the M + 1 grid points of the line p0 -> p1.

    Returns ``(status, sg (M+1,), qs (M+1, 2), der (M+1, 6))``: the grid of
    :func:`path_grid`, the joints and ``der`` as in :func:`path_derivatives`.
    The joints start at ``q_start`` and must arrive at ``q_end`` (both on ``branch``).
    """
    qs = np.zeros((m + 1, 2))
    der = np.zeros((m + 1, 6))
    dx = p1[0] - p0[0]
    dy = p1[1] - p0[1]
    d = math.sqrt(dx * dx + dy * dy)
    ux = dx / d
    uy = dy / d
    sg = path_grid(d, m)
    tmp = np.empty(2)
    # The distance to the base is convex along a line: its closest point decides
    # the inner disc, which sampling could step over.
    s_c = (kin[K_BX] - p0[0]) * ux + (kin[K_BY] - p0[1]) * uy
    if 0.0 < s_c < d:
        if ik_point(kin, p0[0] + s_c * ux, p0[1] + s_c * uy, branch, tmp) == 1:
            return LINE_ANNULUS, sg, qs, der
    qs[0, 0] = q_start[0]
    qs[0, 1] = q_start[1]
    for g in range(1, m + 1):
        s = sg[g]
        st = _follow(kin, p0[0] + s * ux, p0[1] + s * uy, branch, qs[g - 1, 0], qs[g - 1, 1],
                     tmp)
        if st != LINE_OK:
            return st, sg, qs, der
        qs[g, 0] = tmp[0]
        qs[g, 1] = tmp[1]
    if abs(qs[m, 0] - q_end[0]) > 1e-6 or abs(qs[m, 1] - q_end[1]) > 1e-6:
        return LINE_JOINT_LIMIT, sg, qs, der
    qs[m, 0] = q_end[0]
    qs[m, 1] = q_end[1]
    for g in range(m + 1):
        if not path_derivatives(kin, qs[g, 0], qs[g, 1], ux, uy, der[g]):
            return LINE_SINGULAR, sg, qs, der
    return LINE_OK, sg, qs, der


@njit(cache=True)
def _interval_constraints(der, i, delta, acc, ka, kw_dot, ca, cb, cl):
    """Limits of interval i as ``|ca w + cb x_i| <= cl`` (7 rows), both ends enforced."""
    r = 0
    for g in range(i, i + 2):
        far = 2.0 * delta if g == i + 1 else 0.0  # x_{i+1} = x_i + 2 delta w
        for k in range(2):
            ca[r] = der[g, k] + far * der[g, 2 + k]
            cb[r] = der[g, 2 + k]
            cl[r] = acc[k]
            r += 1
        ca[r] = der[g, 4] + far * der[g, 5]
        cb[r] = der[g, 5]
        cl[r] = kw_dot
        r += 1
    ca[r] = 1.0
    cb[r] = 0.0
    cl[r] = ka


@njit(cache=True)
def topp_profile(der, sg, vel, acc, kv, ka, kw, kw_dot):
    """Time-optimal squared path speeds ``x`` (M+1,) and accelerations ``w`` (M,).

    Returns ``(ok, x, w, duration)``; ok is False when the limits force the
    path speed to zero at an interior point over a whole interval.
    """
    m = der.shape[0] - 1
    n_c = 7
    ca = np.empty(n_c)
    cb = np.empty(n_c)
    cl = np.empty(n_c)
    # Velocity limits at the grid points.
    xv = np.empty(m + 1)
    for g in range(m + 1):
        b = kv * kv
        for k in range(2):
            if der[g, k] != 0.0:
                b = min(b, (vel[k] / der[g, k]) ** 2)
        if der[g, 4] != 0.0:
            b = min(b, (kw / der[g, 4]) ** 2)
        xv[g] = b
    # Backward pass: k[i] = largest x_i from which x_M = 0 stays reachable.
    kmax = np.zeros(m + 1)
    lo_a = np.empty(n_c)
    hi_a = np.empty(n_c)
    beta = np.empty(n_c)
    active = np.empty(n_c, dtype=np.bool_)
    x = np.zeros(m + 1)
    w = np.zeros(m)
    for i in range(m - 1, -1, -1):
        delta = sg[i + 1] - sg[i]
        _interval_constraints(der, i, delta, acc, ka, kw_dot, ca, cb, cl)
        bound = xv[i]
        for c in range(n_c):
            if abs(ca[c]) < 1e-12:
                active[c] = False
                if abs(cb[c]) > 0.0:
                    bound = min(bound, cl[c] / abs(cb[c]))
                continue
            active[c] = True
            beta[c] = -cb[c] / ca[c]  # w bounds: lo/hi_a[c] + beta[c] x
            lo_a[c] = -cl[c] / abs(ca[c])
            hi_a[c] = cl[c] / abs(ca[c])
        for c1 in range(n_c):
            if not active[c1]:
                continue
            # some w must exist: max of the lower bounds <= min of the upper ones
            for c2 in range(n_c):
                if active[c2] and beta[c1] > beta[c2]:
                    bound = min(bound, (hi_a[c2] - lo_a[c1]) / (beta[c1] - beta[c2]))
            # the smallest w must not overshoot k[i+1] ...
            coef = 1.0 + 2.0 * delta * beta[c1]
            if coef > 0.0:
                bound = min(bound, (kmax[i + 1] - 2.0 * delta * lo_a[c1]) / coef)
            # ... and the largest must not undershoot x = 0
            coef = beta[c1] + 0.5 / delta
            if coef < 0.0:
                bound = min(bound, hi_a[c1] / -coef)
        kmax[i] = max(bound, 0.0)
    # Forward pass: the largest admissible w that keeps x_{i+1} controllable.
    duration = 0.0
    for i in range(m):
        delta = sg[i + 1] - sg[i]
        _interval_constraints(der, i, delta, acc, ka, kw_dot, ca, cb, cl)
        best = (kmax[i + 1] - x[i]) / (2.0 * delta)
        for c in range(n_c):
            if abs(ca[c]) >= 1e-12:  # upper bound of w from |ca w + cb x| <= cl
                best = min(best, cl[c] / abs(ca[c]) - cb[c] * x[i] / ca[c])
        x[i + 1] = max(x[i] + 2.0 * delta * best, 0.0)
        w[i] = (x[i + 1] - x[i]) / (2.0 * delta)
        speed = math.sqrt(x[i]) + math.sqrt(x[i + 1])
        if speed <= 0.0:
            return False, x, w, np.inf
        duration += 2.0 * delta / speed
    return True, x, w, duration


@njit(cache=True)
def line_time(kin, p0, p1, branch, q_start, q_end, vel, acc, kv, ka, kw, kw_dot, m):
    """``(status, duration)`` of the time-optimal straight move p0 -> p1 on ``branch``."""
    st, sg, qs, der = line_geometry(kin, p0, p1, branch, q_start, q_end, m)
    if st != LINE_OK:
        return st, np.inf
    ok, x, w, duration = topp_profile(der, sg, vel, acc, kv, ka, kw, kw_dot)
    if not ok:
        return LINE_SINGULAR, np.inf
    return LINE_OK, duration


@njit(cache=True)
def line_tensor(points, q_both, kin, vel, acc, kv, ka, kw, kw_dot, m):
    """Straight-line times for every pair and branch.

    Returns ``(times (N, N, 2), status (N, N, 2))``: the time-optimal line from
    i to j with both ends on branch c (inf where infeasible, with the reason in
    ``status``). A branch that does not reach an endpoint has status 2.
    """
    n = points.shape[0]
    times = np.zeros((n, n, 2))
    status = np.zeros((n, n, 2), dtype=np.int64)
    for i in range(n):
        for j in range(i + 1, n):
            for c in range(2):
                if not (np.isfinite(q_both[i, c, 0]) and np.isfinite(q_both[j, c, 0])):
                    st = LINE_JOINT_LIMIT
                    t = np.inf
                else:
                    st, t = line_time(kin, points[i], points[j], c, q_both[i, c], q_both[j, c],
                                      vel, acc, kv, ka, kw, kw_dot, m)
                times[i, j, c] = t
                times[j, i, c] = t
                status[i, j, c] = st
                status[j, i, c] = st
    return times, status


@njit(cache=True)
def line_states(kin, p0, p1, branch, sg, qs, x, w, t):
    """Joint positions, velocities and accelerations (each (T, 2)) at times t of a profile.

    ``sg`` and ``qs`` are the grid and its joint positions (to pick the representative of each
    IK solution), ``x``/``w`` the profile of :func:`topp_profile`; t is clamped
    to [0, duration].
    """
    m = w.shape[0]
    dx = p1[0] - p0[0]
    dy = p1[1] - p0[1]
    d = math.sqrt(dx * dx + dy * dy)
    ux = dx / d
    uy = dy / d
    starts = np.zeros(m + 1)
    for i in range(m):
        starts[i + 1] = starts[i] + 2.0 * (sg[i + 1] - sg[i]) / (math.sqrt(x[i])
                                                                  + math.sqrt(x[i + 1]))
    n_t = t.shape[0]
    q = np.empty((n_t, 2))
    qd = np.empty((n_t, 2))
    qdd = np.empty((n_t, 2))
    der = np.empty(6)
    tmp = np.empty(2)
    i = 0
    for k in range(n_t):
        tk = min(max(t[k], 0.0), starts[m])
        # times are usually sorted: walk forward, else search
        if tk < starts[i]:
            i = 0
        while i < m - 1 and tk >= starts[i + 1]:
            i += 1
        tau = tk - starts[i]
        v0 = math.sqrt(x[i])
        sdot = max(v0 + w[i] * tau, 0.0)
        s = min(sg[i] + v0 * tau + 0.5 * w[i] * tau * tau, d)
        # the grid's joints, interpolated, select the representative of the IK solution
        f = min(max((s - sg[i]) / (sg[i + 1] - sg[i]), 0.0), 1.0)
        ref0 = qs[i, 0] + f * (qs[i + 1, 0] - qs[i, 0])
        ref1 = qs[i, 1] + f * (qs[i + 1, 1] - qs[i, 1])
        ik_point(kin, p0[0] + s * ux, p0[1] + s * uy, branch, tmp)
        q0 = tmp[0] + TWO_PI * round((ref0 - tmp[0]) / TWO_PI)
        q1 = tmp[1] + TWO_PI * round((ref1 - tmp[1]) / TWO_PI)
        q[k, 0] = q0
        q[k, 1] = q1
        path_derivatives(kin, q0, q1, ux, uy, der)
        for a in range(2):
            qd[k, a] = der[a] * sdot
            qdd[k, a] = der[a] * w[i] + der[2 + a] * sdot * sdot
    return q, qd, qdd

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

With joint jerk limits (:class:`LineLimits` ``has_jerk``) that profile has
acceleration steps, so :func:`line_profile` drives instead its moving average
over a window tau, ``f(t) = (1/tau) * integral of s over [t - tau, t]``: still
rest to rest and on the line, now with continuous acceleration and bounded
jerk ``f3 = (s_ddot(t) - s_ddot(t - tau)) / tau``; the joint jerk is
``q' f3 + 3 q'' f1 f2 + q3 f1**3`` (f1, f2 the path speed and acceleration,
q3 the third path derivative of the joints). Stretching time by lambda divides
velocities, accelerations and jerks by lambda, lambda**2 and lambda**3, so the
smallest lambda that meets every limit follows from the largest ratios; tau is
searched to minimise the duration lambda (T + tau) (:func:`_smoothing`), and the
lambda of the width chosen is measured at every breakpoint of the averaged profile
(:func:`_slowdown`).

The loops that run per grid point or per checked instant read the arrays themselves and
call helpers that take and return scalars only (:func:`point_values`, :func:`_raw_values`,
:func:`_ratios`): numba counts array references atomically, and helpers handed arrays in
these loops made a line cost 30 times the acceleration-limited one.

``status`` codes: 0 feasible, 1 the line leaves the reachable annulus (inner
disc or beyond the reach), 2 it passes a joint limit (or arrives at another
representative of the goal configuration), 3 it passes a singularity where the
limits force the arm to stop.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.kinematics._kernels import TWO_PI, ik_point, ik_values, unit_direction

LINE_OK, LINE_ANNULUS, LINE_JOINT_LIMIT, LINE_SINGULAR = 0, 1, 2, 3
# |sin(elbow angle)| below this is a singular configuration (the rim or the inner disc).
_SINGULAR = 1e-9
# Slack on |cos(elbow angle)| <= 1, as in the IK: points on the rim up to rounding count.
_RIM = 1e-9
# Entries of a path-derivative row (see :func:`path_derivatives`).
N_DER = 9
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
    """d/ds, d2/ds2 and d3/ds3 of the joints and the tool angle along direction (ux, uy).

    Writes ``out[0:2] = q'``, ``out[2:4] = q''``, ``out[4] = phi'``,
    ``out[5] = phi''``, ``out[6:8] = q'''``, ``out[8] = phi'''`` (:data:`N_DER`
    values); returns False at a singular configuration.
    """
    th1 = kin.a1 + kin.s1 * q1
    th12 = th1 + kin.a2 + kin.s2 * q2
    ok, d = _frame_values(kin, math.cos(th1), math.sin(th1), math.cos(th12), math.sin(th12),
                          math.sin(th12 - th1), ux, uy)
    if ok:
        for k in range(N_DER):
            out[k] = d[k]
    return ok


@njit(cache=True)
def point_derivatives(kin, px, py, branch, ux, uy, out):
    """:func:`path_derivatives` at the tip point (px, py) on ``branch`` (see
    :func:`point_values`); False outside the annulus or at a singular configuration."""
    ok, d = point_values(kin, px, py, branch, ux, uy)
    if ok:
        for k in range(N_DER):
            out[k] = d[k]
    return ok


@njit(cache=True, inline="always")
def point_values(kin, px, py, branch, ux, uy):
    """``(ok, (q1', q2', q1'', q2'', phi', phi'', q1''', q2''', phi'''))``: the path
    derivatives of :func:`path_derivatives` at the tip point (px, py) on ``branch``,
    without a trigonometric call (the elbow's cosine follows from the point's distance to
    the base, the links' directions from turning the point's direction by the angle of
    ``(l1 + l2 cos b, l2 sin b)``), as scalars (a loop calling it moves no array
    reference, which numba would count atomically). ok is False outside the annulus or
    at a singular configuration. The derivatives depend on the configuration only, not
    on which representative of its joint angles a path holds."""
    dx = px - kin.base_x
    dy = py - kin.base_y
    l1 = kin.l1
    l2 = kin.l2
    r2 = dx * dx + dy * dy
    c = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    inside = -1.0 - _RIM <= c <= 1.0 + _RIM
    c = min(1.0, max(-1.0, c))
    sb = math.sqrt(1.0 - c * c) * (-1.0 if branch == 1 else 1.0)
    # th1 = atan2(dy, dx) - atan2(l2 sb, l1 + l2 c), a vector of length r; th12 = th1 + b
    inv_r2 = 1.0 / r2 if r2 > 0.0 else 0.0
    bx = l1 + l2 * c
    by = l2 * sb
    c1 = (dx * bx + dy * by) * inv_r2
    s1 = (dy * bx - dx * by) * inv_r2
    ok, d = _frame_values(kin, c1, s1, c1 * c - s1 * sb, s1 * c + c1 * sb, sb, ux, uy)
    return ok and inside, d


@njit(cache=True, inline="always")
def _frame_values(kin, c1, s1, c12, s12, sb, ux, uy):
    """``(ok, derivatives)`` of :func:`point_values` from the cosines and sines of the links'
    absolute angles th1 and th12 and ``sb = sin(th12 - th1)`` (ok False at a singular
    configuration, the values then meaningless)."""
    ok = abs(sb) >= _SINGULAR
    l1 = kin.l1
    l2 = kin.l2
    # p' = A (th1', th12')  with  A = [[-l1 s1, -l2 s12], [l1 c1, l2 c12]]
    inv_det = 1.0 / (l1 * l2 * (sb if ok else _SINGULAR))
    d1 = (l2 * c12 * ux + l2 * s12 * uy) * inv_det
    d12 = (-l1 * c1 * ux - l1 * s1 * uy) * inv_det
    # p'' = 0 = A (th1'', th12'') + c
    cx = -l1 * c1 * d1 * d1 - l2 * c12 * d12 * d12
    cy = -l1 * s1 * d1 * d1 - l2 * s12 * d12 * d12
    dd1 = -(l2 * c12 * cx + l2 * s12 * cy) * inv_det
    dd12 = -(-l1 * c1 * cx - l1 * s1 * cy) * inv_det
    # p''' = 0 = A (th1''', th12''') + c3
    cx3 = (l1 * s1 * d1 * d1 * d1 - 3.0 * l1 * c1 * d1 * dd1
           + l2 * s12 * d12 * d12 * d12 - 3.0 * l2 * c12 * d12 * dd12)
    cy3 = (-l1 * c1 * d1 * d1 * d1 - 3.0 * l1 * s1 * d1 * dd1
           - l2 * c12 * d12 * d12 * d12 - 3.0 * l2 * s12 * d12 * dd12)
    ddd1 = -(l2 * c12 * cx3 + l2 * s12 * cy3) * inv_det
    ddd12 = -(-l1 * c1 * cx3 - l1 * s1 * cy3) * inv_det
    return ok, (kin.s1 * d1, kin.s2 * (d12 - d1), kin.s1 * dd1, kin.s2 * (dd12 - dd1), d12,
                dd12, kin.s1 * ddd1, kin.s2 * (ddd12 - ddd1), ddd12)


@njit(cache=True)
def line_geometry(kin, p0, p1, branch, q_start, q_end, m):
    """Joint path and its derivatives at the M + 1 grid points of the line p0 -> p1.

    Returns ``(status, sg (M+1,), qs (M+1, 2), der (M+1, 6))``: the grid of
    :func:`path_grid`, the joints and ``der`` as in :func:`path_derivatives`.
    The joints start at ``q_start`` and must arrive at ``q_end`` (both on ``branch``).
    """
    return _line_geometry(kin, p0, p1, branch, q_start, q_end, unit_grid(m))


@njit(cache=True)
def unit_grid(m):
    """:func:`path_grid` of a unit line: the grid of a line of length d is d times it."""
    return path_grid(1.0, m)


@njit(cache=True)
def _follow_point(kin, x, y, sign, prev0, prev1, ux, uy):
    """``(status, q1, q2, ok, derivatives)`` at the tip point (x, y) of a line on the
    elbow branch of ``sign`` (+1 down, -1 up): the joints continued from (prev0, prev1)
    (no 2 pi jumps) with :data:`LINE_OK`, :data:`LINE_ANNULUS` or
    :data:`LINE_JOINT_LIMIT`, and the path derivatives of :func:`point_values` (ok
    False at a singular configuration), from one set of intermediate values: two
    arctangents, one square root. The IK of :func:`ik_values` up to rounding (its first
    link angle is the arctangent of the point's direction turned by the elbow's angle,
    rather than a difference of two), without its choice of representative, which the
    continuation replaces."""
    dx = x - kin.base_x
    dy = y - kin.base_y
    l1 = kin.l1
    l2 = kin.l2
    r2 = dx * dx + dy * dy
    c = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    inside = -1.0 - _RIM <= c <= 1.0 + _RIM
    c = min(1.0, max(-1.0, c))
    sb = math.sqrt(1.0 - c * c) * sign
    bx = l1 + l2 * c
    by = l2 * sb
    cross = dy * bx - dx * by
    dot = dx * bx + dy * by
    q0 = kin.s1 * (math.atan2(cross, dot) - kin.a1)
    q1 = kin.s2 * (math.atan2(sb, c) - kin.a2)
    q0 += TWO_PI * round((prev0 - q0) / TWO_PI)
    q1 += TWO_PI * round((prev1 - q1) / TWO_PI)
    within = (kin.lower1 - _QTOL <= q0 <= kin.upper1 + _QTOL
              and kin.lower2 - _QTOL <= q1 <= kin.upper2 + _QTOL)
    status = LINE_ANNULUS if not inside else (LINE_OK if within else LINE_JOINT_LIMIT)
    inv_r2 = 1.0 / r2 if r2 > 0.0 else 0.0
    c1 = dot * inv_r2
    s1 = cross * inv_r2
    ok, d = _frame_values(kin, c1, s1, c1 * c - s1 * sb, s1 * c + c1 * sb, sb, ux, uy)
    return status, q0, q1, ok, d


@njit(cache=True)
def _line_geometry(kin, p0, p1, branch, q_start, q_end, unit):
    """:func:`line_geometry` on ``unit`` (:func:`unit_grid`) scaled to the line's length."""
    m = unit.shape[0] - 1
    qs = np.zeros((m + 1, 2))
    der = np.zeros((m + 1, N_DER))
    d, ux, uy = unit_direction(p0[0], p0[1], p1[0], p1[1])
    sg = np.empty(m + 1)
    for g in range(m + 1):
        sg[g] = d * unit[g]
    sg[m] = d
    # The distance to the base is convex along a line: its closest point decides
    # the inner disc, which sampling could step over.
    s_c = (kin.base_x - p0[0]) * ux + (kin.base_y - p0[1]) * uy
    if 0.0 < s_c < d:
        if ik_values(kin, p0[0] + s_c * ux, p0[1] + s_c * uy, branch)[0] == 1:
            return LINE_ANNULUS, sg, qs, der
    x0 = p0[0]
    y0 = p0[1]
    sign = -1.0 if branch == 1 else 1.0
    prev0 = q_start[0]
    prev1 = q_start[1]
    qs[0, 0] = prev0
    qs[0, 1] = prev1
    singular = False  # reported only if the joints follow the whole line
    for g in range(m + 1):
        s = sg[g]
        st, q0, q1, ok, dr = _follow_point(kin, x0 + s * ux, y0 + s * uy, sign, prev0, prev1,
                                           ux, uy)
        if g > 0:
            if st != LINE_OK:
                return st, sg, qs, der
            qs[g, 0] = q0
            qs[g, 1] = q1
            prev0 = q0
            prev1 = q1
        singular = singular or not ok
        for k in range(N_DER):
            der[g, k] = dr[k]
    if abs(qs[m, 0] - q_end[0]) > 1e-6 or abs(qs[m, 1] - q_end[1]) > 1e-6:
        return LINE_JOINT_LIMIT, sg, qs, der
    qs[m, 0] = q_end[0]
    qs[m, 1] = q_end[1]
    if singular:
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

    Each limit of an interval (:func:`_interval_constraints`, written out here so that
    the loop passes no arrays to a helper) is the band ``|w - beta x| <= r`` with
    ``beta = -cb / ca`` and ``r = cl / |ca|``; a candidate bound is divided out only
    when it can improve the current one.
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
    rad = np.empty(n_c)
    beta = np.empty(n_c)
    active = np.empty(n_c, dtype=np.bool_)
    x = np.zeros(m + 1)
    w = np.zeros(m)
    for i in range(m - 1, -1, -1):
        delta = sg[i + 1] - sg[i]
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
        bound = xv[i]
        for c in range(n_c):
            active[c] = abs(ca[c]) >= 1e-12
            if not active[c]:
                if abs(cb[c]) > 0.0:
                    bound = min(bound, cl[c] / abs(cb[c]))
                continue
            inv = 1.0 / ca[c]
            beta[c] = -cb[c] * inv  # w bounds: beta[c] x -+ rad[c]
            rad[c] = cl[c] * abs(inv)
        half = 0.5 / delta
        for c1 in range(n_c):
            if not active[c1]:
                continue
            # some w must exist: max of the lower bounds <= min of the upper ones
            for c2 in range(n_c):
                gap = beta[c1] - beta[c2]
                if active[c2] and gap > 0.0 and rad[c2] + rad[c1] < bound * gap:
                    bound = (rad[c2] + rad[c1]) / gap
            # the smallest w must not overshoot k[i+1] ...
            coef = 1.0 + 2.0 * delta * beta[c1]
            top = kmax[i + 1] + 2.0 * delta * rad[c1]
            if coef > 0.0 and top < bound * coef:
                bound = top / coef
            # ... and the largest must not undershoot x = 0
            coef = -(beta[c1] + half)
            if coef > 0.0 and rad[c1] < bound * coef:
                bound = rad[c1] / coef
        kmax[i] = max(bound, 0.0)
    # Forward pass: the largest admissible w that keeps x_{i+1} controllable.
    duration = 0.0
    v0 = 0.0
    for i in range(m):
        delta = sg[i + 1] - sg[i]
        best = (kmax[i + 1] - x[i]) / (2.0 * delta)
        for g in range(i, i + 2):  # upper bound of w from |ca w + cb x| <= cl
            far = 2.0 * delta if g == i + 1 else 0.0
            for k in range(3):
                col = k if k < 2 else 4
                a = der[g, col] + far * der[g, col + 2 if k < 2 else 5]
                if abs(a) >= 1e-12:
                    lim = acc[k] if k < 2 else kw_dot
                    best = min(best, lim / abs(a) - der[g, col + 2 if k < 2 else 5] * x[i] / a)
        best = min(best, ka)
        x[i + 1] = max(x[i] + 2.0 * delta * best, 0.0)
        w[i] = (x[i + 1] - x[i]) / (2.0 * delta)
        v1 = math.sqrt(x[i + 1])
        speed = v0 + v1
        if speed <= 0.0:
            return False, x, w, np.inf
        duration += 2.0 * delta / speed
        v0 = v1
    return True, x, w, duration


class LineLimits(NamedTuple):
    """Kernel parameters of a straight-line move: the limits and the search settings.

    ``vel``, ``acc``, ``jerk`` are the (2,) joint limits (``jerk`` is ignored
    unless ``has_jerk``); ``kv``, ``ka``, ``kw``, ``kw_dot`` the Cartesian
    ones; ``grid`` the number M of path intervals. With jerk limits the
    acceleration-limited profile is smoothed by a moving average of width tau
    and slowed down uniformly until every limit holds (:func:`line_profile`);
    tau is searched on ``n_tau`` log-spaced values in
    [``tau_min``, ``tau_max``] x (unsmoothed duration) and beside the gaps between the
    largest acceleration jumps, refined by ``n_golden`` golden-section steps, each
    candidate judged at ``n_search`` evenly spaced instants and in the pieces those
    jumps make (:func:`_estimate`); the chosen profile is then measured at every
    breakpoint (:func:`_slowdown`). ``margin`` is the relative slack added to the
    slow-down factor (covers the limits between the checked instants).
    """

    vel: np.ndarray
    acc: np.ndarray
    jerk: np.ndarray
    kv: float
    ka: float
    kw: float
    kw_dot: float
    has_jerk: bool
    grid: int
    n_tau: int
    n_golden: int
    n_search: int
    tau_min: float
    tau_max: float
    margin: float


@njit(cache=True)
def profile_knots(sg, x, w):
    """Times ``tk`` (M+1,) at the grid points and integrals ``sk`` of s(t) up to them."""
    m = w.shape[0]
    tk = np.zeros(m + 1)
    sk = np.zeros(m + 1)
    for i in range(m):
        v0 = math.sqrt(x[i])
        h = 2.0 * (sg[i + 1] - sg[i]) / (v0 + math.sqrt(x[i + 1]))
        tk[i + 1] = tk[i] + h
        sk[i + 1] = sk[i] + sg[i] * h + 0.5 * v0 * h * h + w[i] * h * h * h / 6.0
    return tk, sk


@njit(cache=True, inline="always")
def _locate(tk, t, i):
    """Index of the interval of ``tk`` holding t, searched from the guess i."""
    m = tk.shape[0] - 1
    while i < m - 1 and t >= tk[i + 1]:
        i += 1
    while i > 0 and t < tk[i]:
        i -= 1
    return i


@njit(cache=True, inline="always")
def _raw_values(t, h, s0, v0, a0, k0, t_end, s_end, k_end):
    """s, s_dot, s_ddot and the integral of s at time t of the unsmoothed profile, from
    its interval's start position s0, speed v0, acceleration a0, integral k0, h = t minus
    the interval's start time, and the profile's end time, position and integral.

    At rest at s = 0 before t = 0 and at s = s_end after t_end. Scalars in, and no
    branches (each value selected): numba's code for the same with if/elif blocks and
    the arrays passed in took ten times as long, and this runs at every instant a
    smoothed profile is checked.
    """
    s = min(s0 + v0 * h + 0.5 * a0 * h * h, s_end)
    integral = k0 + s0 * h + 0.5 * v0 * h * h + a0 * h * h * h / 6.0
    speed = max(v0 + a0 * h, 0.0)
    after = t >= t_end
    inside = t > 0.0 and not after
    return (s_end if after else (s if inside else 0.0),
            speed if inside else 0.0,
            a0 if inside else 0.0,
            k_end + s_end * (t - t_end) if after else (integral if inside else 0.0))


@njit(cache=True, inline="always")
def _window(tau, inv_tau, now, before, s_end):
    """(f, f', f'', f'''): the profile averaged over [t - tau, t] from the raw states
    ``now`` at t and ``before`` at t - tau (:func:`_raw_values`), ``inv_tau`` = 1 / tau;
    tau = 0: ``now`` itself.

    Averaging a rest-to-rest profile keeps it rest to rest with zero end
    accelerations and makes its acceleration continuous: f''' is the
    difference of the accelerations at t and t - tau over tau.
    """
    smooth = tau > 0.0
    inv = inv_tau if smooth else 0.0
    f = min(max((now[3] - before[3]) * inv, 0.0), s_end)
    return (f if smooth else now[0], max((now[0] - before[0]) * inv, 0.0) if smooth else now[1],
            (now[1] - before[1]) * inv if smooth else now[2], (now[2] - before[2]) * inv)


@njit(cache=True)
def _smoothed(t, tau, ia, ib, sg, v, w, tk, sk):
    """(f, f', f'', f''', ia, ib): the profile averaged over [t - tau, t] (tau = 0: itself),
    ``ia``, ``ib`` the intervals of t and t - tau, searched from the guesses given;
    ``v``: the path speeds at the grid points (the square roots of ``x``).
    """
    m = w.shape[0]
    ia = _locate(tk, t, ia)
    ib = _locate(tk, t - tau, ib)
    now = _raw_values(t, t - tk[ia], sg[ia], v[ia], w[ia], sk[ia], tk[m], sg[m], sk[m])
    before = _raw_values(t - tau, t - tau - tk[ib], sg[ib], v[ib], w[ib], sk[ib], tk[m], sg[m],
                         sk[m])
    f, f1, f2, f3 = _window(tau, 1.0 / tau if tau > 0.0 else 0.0, now, before, sg[m])
    return f, f1, f2, f3, ia, ib


@njit(cache=True)
def _exact_derivatives(kin, p0, ux, uy, branch, sg, qs, s, g, der_out, tmp):
    """Path derivatives at s by IK (the grid's joints pick the representative)."""
    f = min(max((s - sg[g]) / (sg[g + 1] - sg[g]), 0.0), 1.0)
    ref0 = qs[g, 0] + f * (qs[g + 1, 0] - qs[g, 0])
    ref1 = qs[g, 1] + f * (qs[g + 1, 1] - qs[g, 1])
    ik_point(kin, p0[0] + s * ux, p0[1] + s * uy, branch, tmp)
    q0 = tmp[0] + TWO_PI * round((ref0 - tmp[0]) / TWO_PI)
    q1 = tmp[1] + TWO_PI * round((ref1 - tmp[1]) / TWO_PI)
    path_derivatives(kin, q0, q1, ux, uy, der_out)
    return q0, q1


@njit(cache=True, inline="always")
def _inverse_limits(lim):
    """1 / (kv, kw, ka, kw_dot, vel[0], vel[1], acc[0], acc[1], jerk[0], jerk[1])."""
    return (1.0 / lim.kv, 1.0 / lim.kw, 1.0 / lim.ka, 1.0 / lim.kw_dot, 1.0 / lim.vel[0],
            1.0 / lim.vel[1], 1.0 / lim.acc[0], 1.0 / lim.acc[1], 1.0 / lim.jerk[0],
            1.0 / lim.jerk[1])


@njit(cache=True, inline="always")
def _ratios(dr, f1, f2, f3a, f3b, inv, has_jerk, rv, ra, rj):
    """(velocity, acceleration, jerk) ratios to the limits, raised from (rv, ra, rj) by one
    instant of the smoothed profile: path derivatives ``dr`` (:func:`point_values`), path
    speed f1 and acceleration f2, and the path jerk f3a, f3b on either side of the instant
    (the jerk may jump there); ``inv``: :func:`_inverse_limits`."""
    rv = max(rv, f1 * inv[0], abs(dr[4]) * f1 * inv[1], abs(dr[0]) * f1 * inv[4],
             abs(dr[1]) * f1 * inv[5])
    ra = max(ra, abs(f2) * inv[2], abs(dr[4] * f2 + dr[5] * f1 * f1) * inv[3],
             abs(dr[0] * f2 + dr[2] * f1 * f1) * inv[6],
             abs(dr[1] * f2 + dr[3] * f1 * f1) * inv[7])
    rest0 = 3.0 * dr[2] * f1 * f2 + dr[6] * f1 * f1 * f1
    rest1 = 3.0 * dr[3] * f1 * f2 + dr[7] * f1 * f1 * f1
    jerk = max(abs(dr[0] * f3a + rest0) * inv[8], abs(dr[0] * f3b + rest0) * inv[8],
               abs(dr[1] * f3a + rest1) * inv[9], abs(dr[1] * f3b + rest1) * inv[9])
    return rv, ra, max(rj, jerk) if has_jerk else rj


SPIKES = 8
"""The unsmoothed profile's largest acceleration jumps that a width's estimate follows
(:func:`_estimate`)."""
GAPS = 4
"""Of those, the largest whose gaps are candidate widths (:func:`_smoothing`)."""
MISSED = 0.03
"""An exact measure this share above its width's estimate sends :func:`_smoothing` to the
best candidates of the grid too (1%: the same lines 5-10% slower, their times 0.03-0.08%
shorter at the median)."""
_MIN_GAP = 0.03
"""Gaps below this share of T are not candidates (the jerk of so narrow a window costs more
than any gain; the log grid still covers them)."""
_SAME_GAP = 0.02
"""Gaps within this share of one already taken are the same candidate."""
_NEAR_GAP = 2e-3
"""Candidate widths this share below and above each gap between two of the largest jumps:
the cost jumps there (up or down), so its lowest value is often just beside one."""


@njit(cache=True)
def _jump_times(tk, w):
    """Times of the :data:`SPIKES` largest jumps of the unsmoothed path acceleration (from
    and to rest included), the largest first: the smoothed jerk (a(t) - a(t - tau)) / tau
    changes by a jump's size over tau at the jump and again tau after it."""
    m = w.shape[0]
    times = np.zeros(SPIKES)
    sizes = np.full(SPIKES, -1.0)
    for k in range(m + 1):
        jump = abs((w[k] if k < m else 0.0) - (w[k - 1] if k > 0 else 0.0))
        low = 0
        for j in range(1, SPIKES):
            if sizes[j] < sizes[low]:
                low = j
        if jump > sizes[low]:
            sizes[low] = jump
            times[low] = tk[k]
    for i in range(1, SPIKES):  # the largest first
        j = i
        while j > 0 and sizes[j - 1] < sizes[j]:
            sizes[j - 1], sizes[j] = sizes[j], sizes[j - 1]
            times[j - 1], times[j] = times[j], times[j - 1]
            j -= 1
    return times


@njit(cache=True)
def _jump_pieces(jumps, tau):
    """The middles of the pieces between the largest jumps and the same shifted by tau,
    sorted: where the jerk the jumps make is constant, whatever combination of them the
    window holds (a width just above the gap between two jumps makes a narrow peak)."""
    n = jumps.shape[0]
    marks = np.empty(2 * n)
    for k in range(n):
        marks[k] = jumps[k]
        marks[n + k] = jumps[k] + tau
    for i in range(1, 2 * n):  # insertion sort: 16 values
        x = marks[i]
        j = i
        while j > 0 and marks[j - 1] > x:
            marks[j] = marks[j - 1]
            j -= 1
        marks[j] = x
    mids = np.empty(2 * n - 1)
    for k in range(2 * n - 1):
        mids[k] = 0.5 * (marks[k] + marks[k + 1])
    return mids


_CLEARLY = 1.0 + 1e-12
"""A running ratio this share above a bound stops a judgement early: far above rounding, so
the full value would be above the bound as well."""
FIRST_WIDTH = 0.15
"""The width, as a share of the unsmoothed duration T, whose nearest candidate
:func:`_smoothing` judges first: the median best width (planar_2r, 600 random lines:
quartiles 0.13 and 0.26). Only the work depends on it, not the width chosen."""

TIME_BUCKETS = 128
"""Buckets of :func:`_time_index` (a few grid intervals each)."""


@njit(cache=True)
def _time_index(tk, nb):
    """``index[j]``: the interval of ``tk`` holding the time j T / nb (T = tk[-1]), so that
    a search for any time starts a step or two before it."""
    m = tk.shape[0] - 1
    index = np.empty(nb + 1, dtype=np.int64)
    i = 0
    for j in range(nb + 1):
        t = j * tk[m] / nb
        while i < m - 1 and t >= tk[i + 1]:
            i += 1
        index[j] = i
    return index


@njit(cache=True)
def _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, tau, lim, jumps, index, bound):
    """The duration of width tau, its time stretch judged at ``lim.n_search`` evenly spaced
    instants and
    in each piece of the jerk the largest acceleration ``jumps`` make
    (:func:`_jump_pieces`: features narrower than the spacing); to compare widths quickly.
    ``index``: :func:`_time_index` of ``tk``. The loop reads the arrays itself and calls
    scalar helpers only (see :func:`point_values`).

    Returns ``(cost, complete)``, the cost being the stretch times the duration
    ``T + tau``. The stretch is a maximum over the instants, so once its running value makes
    a cost above ``bound`` the width cannot beat a width whose cost is ``bound``: the loop
    stops there and returns that running cost, raised if rounding put it at the bound, so
    that it is strictly above (``complete`` False; a tie is judged in full). The jump
    pieces, where the jerk peaks, come first, so that such a width is seen to lose early
    (``bound = inf``: every instant).
    """
    m = w.shape[0]
    t_end = tk[m]
    s_end = sg[m]
    k_end = sk[m]
    end = t_end + tau
    inv = _inverse_limits(lim)
    has_jerk = lim.has_jerk  # (the loops read no field of lim: it holds arrays)
    x0 = p0[0]
    y0 = p0[1]
    dr = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    rv = 0.0
    ra = 0.0
    rj = 0.0
    nb = index.shape[0] - 1
    scale = nb / t_end
    n = lim.n_search
    mids = _jump_pieces(jumps, tau)
    step = end / n
    inv_tau = 1.0 / tau
    n_mids = mids.shape[0]
    # the running ratios that put the stretch clearly above B = bound / (T + tau): v > B,
    # a > B^2, j > B^3 with a margin over rounding, so that the full cost is above too
    b1 = bound / (t_end + tau) * _CLEARLY
    b2 = b1 * b1
    b3 = b2 * b1
    for k in range(n + n_mids):
        if rv > b1 or ra > b2 or rj > b3:
            cost = max(rv, math.sqrt(ra), rj ** (1.0 / 3.0)) * (t_end + tau)
            return max(cost, np.nextafter(bound, np.inf)), False
        t = mids[k] if k < n_mids else (k - n_mids + 0.5) * step
        tb = t - tau
        # each search starts from the interval of the bucket's start (:func:`_time_index`)
        ia = index[int(min(max(t, 0.0) * scale, nb))]
        while ia < m - 1 and t >= tk[ia + 1]:
            ia += 1
        while ia > 0 and t < tk[ia]:
            ia -= 1
        ib = index[int(min(max(tb, 0.0) * scale, nb))]
        while ib < m - 1 and tb >= tk[ib + 1]:
            ib += 1
        while ib > 0 and tb < tk[ib]:
            ib -= 1
        now = _raw_values(t, t - tk[ia], sg[ia], v[ia], w[ia], sk[ia], t_end, s_end, k_end)
        before = _raw_values(tb, tb - tk[ib], sg[ib], v[ib], w[ib], sk[ib], t_end, s_end,
                             k_end)
        f, f1, f2, f3 = _window(tau, inv_tau, now, before, s_end)
        ok, d = point_values(kin, x0 + f * ux, y0 + f * uy, branch, ux, uy)
        dr = d if ok else dr
        rv, ra, rj = _ratios(dr, f1, f2, f3, f3, inv, has_jerk, rv, ra, rj)
    return max(rv, math.sqrt(ra), rj ** (1.0 / 3.0)) * (t_end + tau), True


@njit(cache=True)
def _slowdown(kin, p0, ux, uy, branch, sg, v, w, tk, sk, tau, lim, bound):
    """Uniform time-stretch factor that brings the smoothed profile within every limit.

    Stretching time by lambda divides velocities by lambda, accelerations by
    lambda^2 and jerks by lambda^3, so the factor is the max over the checked
    instants of (velocity ratio, sqrt(acceleration ratio), cbrt(jerk ratio)). The
    instants are the profile's breakpoints, the grid times and the same shifted by tau:
    its jerk is constant between them and jumps there, so each is checked with the
    jerk of the piece before and of the piece after it; path derivatives are exact
    (:func:`point_values`) at the path position of each. (The loop reads the arrays
    itself and calls scalar helpers only, see :func:`point_values`.)

    A factor above ``bound`` is returned as inf, and the loop stops as soon as the running
    factor is above it: that it is above is all a caller giving a bound asks
    (``bound = inf``: the factor itself).
    """
    n = tk.shape[0]
    m = n - 1
    t_end = tk[m]
    s_end = sg[m]
    k_end = sk[m]
    inv = _inverse_limits(lim)
    has_jerk = lim.has_jerk  # (the loops read no field of lim: it holds arrays)
    x0 = p0[0]
    y0 = p0[1]
    dr = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    rv = 0.0
    ra = 0.0
    rj = 0.0
    a = 0  # the next grid time, and the next one shifted by tau
    b = 0
    ia = 0
    ib = 0
    inv_tau = 1.0 / tau
    before_jerk = 0.0  # of the piece before the breakpoint (at rest before t = 0)
    b1 = bound * _CLEARLY  # clearly above (see :func:`_estimate`); the end decides exactly
    b2 = b1 * b1
    b3 = b2 * b1
    for _ in range(2 * n):
        if rv > b1 or ra > b2 or rj > b3:
            return np.inf
        if b >= n or (a < n and tk[a] <= tk[b] + tau):
            t = tk[a]
            tb = t - tau
            a += 1
            while ib < m - 1 and tb >= tk[ib + 1]:
                ib += 1
        else:  # t - tau is grid time b itself (not its sum with tau less tau, rounded)
            tb = tk[b]
            t = tb + tau
            ib = min(b, m - 1)
            b += 1
        while ia < m - 1 and t >= tk[ia + 1]:
            ia += 1
        # the jerk of the piece after t: the raw accelerations just after t and t - tau
        # (the intervals found hold their start; at rest outside [0, T))
        after_jerk = ((w[ia] if 0.0 <= t < t_end else 0.0)
                      - (w[ib] if 0.0 <= tb < t_end else 0.0)) * inv_tau
        now = _raw_values(t, t - tk[ia], sg[ia], v[ia], w[ia], sk[ia], t_end, s_end, k_end)
        before = _raw_values(tb, tb - tk[ib], sg[ib], v[ib], w[ib], sk[ib], t_end, s_end,
                             k_end)
        f, f1, f2, _ = _window(tau, inv_tau, now, before, s_end)
        ok, d = point_values(kin, x0 + f * ux, y0 + f * uy, branch, ux, uy)
        dr = d if ok else dr
        rv, ra, rj = _ratios(dr, f1, f2, before_jerk, after_jerk, inv, has_jerk, rv, ra,
                             rj)
        before_jerk = after_jerk
    factor = max(rv, math.sqrt(ra), rj ** (1.0 / 3.0))
    return np.inf if factor > bound else factor


@njit(cache=True)
def _smoothing(kin, p0, ux, uy, branch, sg, x, w, lim):
    """(tau, lambda): the averaging width and time stretch of the fastest smoothed profile.

    The duration lambda (T + tau) is minimised over tau on a log grid plus the widths
    just beside the gaps between the largest acceleration jumps (:data:`GAPS`) and
    beside T, refined by a golden-section search on log tau around the best, each
    width judged by :func:`_estimate`; lambda of the width chosen is then measured at
    every breakpoint (:func:`_slowdown`). When that is :data:`MISSED` above its estimate
    (a feature the estimate missed), the best and the next best candidates are measured
    too and the fastest kept.
    """
    tk, sk = profile_knots(sg, x, w)
    v = np.sqrt(x)
    t1 = tk[tk.shape[0] - 1]
    jumps = _jump_times(tk, w)
    index = _time_index(tk, TIME_BUCKETS)
    lo = math.log(lim.tau_min * t1)
    hi = math.log(lim.tau_max * t1)
    # log-spaced widths, plus one just below and one just above each gap between two of
    # the largest jumps and the duration T: a window wider than a gap holds both jumps,
    # and the jerk (so the cost) jumps there
    logs = np.empty(lim.n_tau + GAPS * (GAPS - 1) + 2)
    for k in range(lim.n_tau):
        logs[k] = lo + (hi - lo) * k / (lim.n_tau - 1)
    n_all = lim.n_tau
    gaps = np.empty(GAPS * (GAPS - 1) // 2 + 1)
    gaps[0] = t1
    n_gaps = 1
    for i in range(GAPS):
        for j in range(i + 1, GAPS):
            gap = abs(jumps[j] - jumps[i])
            seen = gap < _MIN_GAP * t1  # a narrower window is never the fastest
            for k in range(n_gaps):
                seen = seen or abs(gap - gaps[k]) <= _SAME_GAP * gaps[k]
            if not seen:
                gaps[n_gaps] = gap
                n_gaps += 1
    for k in range(n_gaps):
        for side in (-1.0, 1.0):
            tau = gaps[k] * (1.0 + side * _NEAR_GAP)
            if lim.tau_min * t1 <= tau <= lim.tau_max * t1:
                logs[n_all] = math.log(tau)
                n_all += 1
    logs = np.sort(logs[:n_all])
    # each width is judged only until it is seen to lose to the best so far (its cost
    # then a lower bound, ``complete`` False; a width that wins or ties is judged in
    # full), the one nearest the usual best first, so that most lose early; ties go to
    # the narrower width, as in a scan from the narrowest
    costs = np.empty(n_all)
    complete = np.ones(n_all, dtype=np.bool_)
    best = np.argmin(np.abs(logs - math.log(FIRST_WIDTH * t1)))
    for i in range(n_all + 1):
        k = best if i == 0 else i - 1
        if i > 0 and k == best:
            continue
        tau = math.exp(logs[k])
        costs[k], complete[k] = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, tau,
                                          lim, jumps, index,
                                          costs[best] if i > 0 else np.inf)
        if costs[k] < costs[best] or (costs[k] == costs[best] and k < best):
            best = k
    a = logs[max(best - 1, 0)]
    b = logs[min(best + 1, n_all - 1)]
    best_log = logs[best]
    best_cost = costs[best]
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    c = b - ratio * (b - a)
    e = a + ratio * (b - a)
    # each new point is judged until it is seen to lose to the other inner point: the
    # step then discards it, and a point that loses never lowers best_cost below the
    # other's (a tie is judged in full), so the search is the same as with every point
    # judged in full
    fc = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, math.exp(c), lim,
                   jumps, index, np.inf)[0]
    fe = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, math.exp(e), lim,
                   jumps, index, fc)[0]
    for step in range(lim.n_golden + 1):
        if fc < best_cost:
            best_cost = fc
            best_log = c
        if fe < best_cost:
            best_cost = fe
            best_log = e
        if step == lim.n_golden:
            break
        if fc < fe:  # the minimum is in [a, e]: the old c is the new e
            b = e
            e = c
            fe = fc
            c = b - ratio * (b - a)
            fc = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, math.exp(c), lim,
                           jumps, index, fe)[0]
        else:  # in [c, b]: the old e is the new c
            a = c
            c = e
            fc = fe
            e = a + ratio * (b - a)
            fe = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, math.exp(e), lim,
                           jumps, index, fc)[0]
    # the width chosen, measured; an estimate that missed a narrow feature (the cost can
    # jump at a width where two phases of the profile start to overlap in the window) is
    # more than MISSED below: then the best and the next best widths of the grid are measured
    # too, until one meets its estimate, and the fastest is kept
    tau = math.exp(best_log)
    lam = _slowdown(kin, p0, ux, uy, branch, sg, v, w, tk, sk, tau, lim, np.inf)
    missed = lam * (t1 + tau) > (1.0 + MISSED) * best_cost
    for _ in range(2):
        if not missed:
            break
        k = np.argmin(costs)
        if logs[k] == best_log:  # the width measured already: it missed its estimate
            costs[k] = np.inf
            continue
        while not complete[k]:  # a lower bound first: judged in full, then compared again
            tau_k = math.exp(logs[k])
            costs[k] = _estimate(kin, p0, ux, uy, branch, sg, v, w, tk, sk, tau_k, lim,
                                 jumps, index, np.inf)[0]
            complete[k] = True
            k = np.argmin(costs)
        other = math.exp(logs[k])
        # measured only as far as needed to know it neither beats the width kept nor
        # meets its estimate (inf then: both decisions follow)
        enough = max(lam * (t1 + tau), (1.0 + MISSED) * costs[k]) / (t1 + other)
        lo_lam = _slowdown(kin, p0, ux, uy, branch, sg, v, w, tk, sk, other, lim, enough)
        missed = lo_lam * (t1 + other) > (1.0 + MISSED) * costs[k]
        costs[k] = np.inf
        if lo_lam * (t1 + other) < lam * (t1 + tau):
            tau = other
            lam = lo_lam
    return tau, lam * (1.0 + lim.margin)


@njit(cache=True)
def line_profile(kin, p0, p1, branch, q_start, q_end, lim):
    """The executed straight move p0 -> p1 on ``branch``.

    Returns ``(status, sg, qs, x, w, tau, lam, duration)``: the grid, its
    joints, the acceleration-limited time-optimal profile ``x``/``w``
    (:func:`topp_profile`), and, with jerk limits, the averaging width ``tau``
    and the time stretch ``lam`` of the jerk-limited profile executed instead
    (tau = 0, lam = 1 without jerk limits). duration = lam (T + tau), T the
    duration of the acceleration-limited profile; inf if status != 0.
    """
    return _line_profile(kin, p0, p1, branch, q_start, q_end, lim, unit_grid(lim.grid))


@njit(cache=True)
def _line_profile(kin, p0, p1, branch, q_start, q_end, lim, unit):
    """:func:`line_profile` on the path grid ``unit`` (:func:`unit_grid`), which a caller
    timing many lines computes once."""
    st, sg, qs, der = _line_geometry(kin, p0, p1, branch, q_start, q_end, unit)
    x = np.zeros(lim.grid + 1)
    w = np.zeros(lim.grid)
    if st != LINE_OK:
        return st, sg, qs, x, w, 0.0, 1.0, np.inf
    ok, x, w, duration = topp_profile(der, sg, lim.vel, lim.acc, lim.kv, lim.ka, lim.kw,
                                      lim.kw_dot)
    if not ok:
        return LINE_SINGULAR, sg, qs, x, w, 0.0, 1.0, np.inf
    if not lim.has_jerk:
        return LINE_OK, sg, qs, x, w, 0.0, 1.0, duration
    _, ux, uy = unit_direction(p0[0], p0[1], p1[0], p1[1])
    tau, lam = _smoothing(kin, p0, ux, uy, branch, sg, x, w, lim)
    return LINE_OK, sg, qs, x, w, tau, lam, lam * (duration + tau)


@njit(cache=True)
def line_time(kin, p0, p1, branch, q_start, q_end, lim):
    """``(status, duration)`` of the executed straight move p0 -> p1 on ``branch``."""
    out = line_profile(kin, p0, p1, branch, q_start, q_end, lim)
    return out[0], out[7]


@njit(cache=True)
def line_tensor(points, q_both, kin, lim):
    """Straight-line times for every pair and branch.

    Returns ``(times (N, N, 2), status (N, N, 2))``: the executed line from
    i to j with both ends on branch c (inf where infeasible, with the reason in
    ``status``). A branch that does not reach an endpoint has status 2.
    """
    n = points.shape[0]
    times = np.zeros((n, n, 2))
    status = np.zeros((n, n, 2), dtype=np.int64)
    unit = unit_grid(lim.grid)
    for i in range(n):
        for j in range(i + 1, n):
            for c in range(2):
                if not (np.isfinite(q_both[i, c, 0]) and np.isfinite(q_both[j, c, 0])):
                    st = LINE_JOINT_LIMIT
                    t = np.inf
                else:
                    out = _line_profile(kin, points[i], points[j], c, q_both[i, c],
                                        q_both[j, c], lim, unit)
                    st = out[0]
                    t = out[7]
                times[i, j, c] = t
                times[j, i, c] = t
                status[i, j, c] = st
                status[j, i, c] = st
    return times, status


@njit(cache=True)
def line_states(kin, p0, p1, branch, sg, qs, x, w, tau, lam, t):
    """Joint positions, velocities, accelerations and jerks (each (T, 2)) at times t.

    ``sg``, ``qs``, ``x``, ``w``, ``tau``, ``lam`` as returned by
    :func:`line_profile`; t is clamped to [0, duration].
    """
    m = w.shape[0]
    d, ux, uy = unit_direction(p0[0], p0[1], p1[0], p1[1])
    tk, sk = profile_knots(sg, x, w)
    v = np.sqrt(x)
    end = tk[m] + tau
    n_t = t.shape[0]
    q = np.empty((n_t, 2))
    qd = np.empty((n_t, 2))
    qdd = np.empty((n_t, 2))
    qddd = np.empty((n_t, 2))
    der = np.empty(N_DER)
    tmp = np.empty(2)
    ia = 0
    ib = 0
    g = 0
    for k in range(n_t):
        tt = min(max(t[k] / lam, 0.0), end)
        f, f1, f2, f3, ia, ib = _smoothed(tt, tau, ia, ib, sg, v, w, tk, sk)
        f1 /= lam
        f2 /= lam * lam
        f3 /= lam * lam * lam
        if f < sg[g]:
            g = 0
        while g < m - 1 and f >= sg[g + 1]:
            g += 1
        q0, q1 = _exact_derivatives(kin, p0, ux, uy, branch, sg, qs, f, g, der, tmp)
        q[k, 0] = q0
        q[k, 1] = q1
        for a in range(2):
            qd[k, a] = der[a] * f1
            qdd[k, a] = der[a] * f2 + der[2 + a] * f1 * f1
            qddd[k, a] = der[a] * f3 + 3.0 * der[2 + a] * f1 * f2 + der[6 + a] * f1 * f1 * f1
    return q, qd, qdd, qddd

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
searched to minimise the duration lambda (T + tau).

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

from subtask_opt.arm._kinematics_kernels import TWO_PI, ik_point, unit_direction

LINE_OK, LINE_ANNULUS, LINE_JOINT_LIMIT, LINE_SINGULAR = 0, 1, 2, 3
# |sin(elbow angle)| below this is a singular configuration (the rim or the inner disc).
_SINGULAR = 1e-9
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
    l1 = kin.l1
    l2 = kin.l2
    th1 = kin.a1 + kin.s1 * q1
    th12 = th1 + kin.a2 + kin.s2 * q2
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
    # p''' = 0 = A (th1''', th12''') + c3
    cx3 = (l1 * s1 * d1 ** 3 - 3.0 * l1 * c1 * d1 * dd1
           + l2 * s12 * d12 ** 3 - 3.0 * l2 * c12 * d12 * dd12)
    cy3 = (-l1 * c1 * d1 ** 3 - 3.0 * l1 * s1 * d1 * dd1
           - l2 * c12 * d12 ** 3 - 3.0 * l2 * s12 * d12 * dd12)
    ddd1 = -(l2 * c12 * cx3 + l2 * s12 * cy3) / det
    ddd12 = -(-l1 * c1 * cx3 - l1 * s1 * cy3) / det
    out[0] = kin.s1 * d1
    out[1] = kin.s2 * (d12 - d1)
    out[2] = kin.s1 * dd1
    out[3] = kin.s2 * (dd12 - dd1)
    out[4] = d12
    out[5] = dd12
    out[6] = kin.s1 * ddd1
    out[7] = kin.s2 * (ddd12 - ddd1)
    out[8] = ddd12
    return True


@njit(cache=True)
def _follow(kin, x, y, branch, prev0, prev1, out):
    """IK on ``branch`` continued from (prev0, prev1): no 2 pi jumps. Returns a status."""
    st = ik_point(kin, x, y, branch, out)
    if st == 1:
        return LINE_ANNULUS
    out[0] += TWO_PI * round((prev0 - out[0]) / TWO_PI)
    out[1] += TWO_PI * round((prev1 - out[1]) / TWO_PI)
    if not (kin.lower1 - _QTOL <= out[0] <= kin.upper1 + _QTOL
            and kin.lower2 - _QTOL <= out[1] <= kin.upper2 + _QTOL):
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
    der = np.zeros((m + 1, N_DER))
    d, ux, uy = unit_direction(p0[0], p0[1], p1[0], p1[1])
    sg = path_grid(d, m)
    tmp = np.empty(2)
    # The distance to the base is convex along a line: its closest point decides
    # the inner disc, which sampling could step over.
    s_c = (kin.base_x - p0[0]) * ux + (kin.base_y - p0[1]) * uy
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


class LineLimits(NamedTuple):
    """Kernel parameters of a straight-line move: the limits and the search settings.

    ``vel``, ``acc``, ``jerk`` are the (2,) joint limits (``jerk`` is ignored
    unless ``has_jerk``); ``kv``, ``ka``, ``kw``, ``kw_dot`` the Cartesian
    ones; ``grid`` the number M of path intervals. With jerk limits the
    acceleration-limited profile is smoothed by a moving average of width tau
    and slowed down uniformly until every limit holds (:func:`line_profile`);
    tau is searched on ``n_tau`` log-spaced values in
    [``tau_min``, ``tau_max``] x (unsmoothed duration), refined by
    ``n_golden`` golden-section steps, each candidate judged at ``n_search``
    evenly spaced instants with interpolated path derivatives; the chosen
    profile is then measured exactly. ``margin`` is the relative slack added
    to the slow-down factor (covers the limits between the checked instants).
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


@njit(cache=True)
def _locate(tk, t, i):
    """Index of the interval of ``tk`` holding t, searched from the guess i."""
    m = tk.shape[0] - 1
    while i < m - 1 and t >= tk[i + 1]:
        i += 1
    while i > 0 and t < tk[i]:
        i -= 1
    return i


@njit(cache=True)
def _raw_state(t, i, sg, x, w, tk, sk):
    """s, s_dot, s_ddot and the integral of s at time t of the unsmoothed profile.

    At rest at s = 0 before t = 0 and at s = d after the end.
    """
    m = w.shape[0]
    if t <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    if t >= tk[m]:
        return sg[m], 0.0, 0.0, sk[m] + sg[m] * (t - tk[m])
    h = t - tk[i]
    v0 = math.sqrt(x[i])
    s = min(sg[i] + v0 * h + 0.5 * w[i] * h * h, sg[m])
    integral = sk[i] + sg[i] * h + 0.5 * v0 * h * h + w[i] * h * h * h / 6.0
    return s, max(v0 + w[i] * h, 0.0), w[i], integral


@njit(cache=True)
def _smoothed(t, tau, ia, ib, sg, x, w, tk, sk):
    """(f, f', f'', f''', ia, ib): the profile averaged over [t - tau, t] (tau = 0: itself).

    Averaging a rest-to-rest profile keeps it rest to rest with zero end
    accelerations and makes its acceleration continuous: f''' is the
    difference of the accelerations at t and t - tau over tau.
    """
    ia = _locate(tk, t, ia)
    sa, va, aa, ia_int = _raw_state(t, ia, sg, x, w, tk, sk)
    if tau <= 0.0:
        return sa, va, aa, 0.0, ia, ib
    ib = _locate(tk, t - tau, ib)
    sb, vb, ab, ib_int = _raw_state(t - tau, ib, sg, x, w, tk, sk)
    f = min(max((ia_int - ib_int) / tau, 0.0), sg[sg.shape[0] - 1])
    return f, max((sa - sb) / tau, 0.0), (va - vb) / tau, (aa - ab) / tau, ia, ib


@njit(cache=True)
def _sample_times(tk, tau, three):
    """Instants where the smoothed profile is checked (sorted).

    The breakpoints of the smoothed profile are the grid times and the same
    shifted by tau; its jerk jumps there. Each piece between two breakpoints
    is checked at its middle and, if ``three``, also just after its start and
    just before its end (both one-sided limits of every jump).
    """
    n = tk.shape[0]
    merged = np.empty(2 * n)
    a = 0
    b = 0
    for k in range(2 * n):
        if b >= n or (a < n and tk[a] <= tk[b] + tau):
            merged[k] = tk[a]
            a += 1
        else:
            merged[k] = tk[b] + tau
            b += 1
    per = 3 if three else 1
    out = np.empty(per * (2 * n - 1))
    for k in range(2 * n - 1):
        lo = merged[k]
        hi = merged[k + 1]
        if three:
            eps = 1e-9 * (hi - lo)
            out[3 * k] = lo + eps
            out[3 * k + 1] = 0.5 * (lo + hi)
            out[3 * k + 2] = hi - eps
        else:
            out[k] = 0.5 * (lo + hi)
    return out


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


@njit(cache=True)
def _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, tau, lim, exact):
    """Uniform time-stretch factor that brings the smoothed profile within every limit.

    Stretching time by lambda divides velocities by lambda, accelerations by
    lambda^2 and jerks by lambda^3, so the factor is the max over the checked
    instants of (velocity ratio, sqrt(acceleration ratio), cbrt(jerk ratio)).
    ``exact``: derivatives by IK at three instants per piece of the profile
    (:func:`_sample_times`), else interpolated on the grid at ``lim.n_search``
    evenly spaced instants (to compare candidate widths quickly) when they are
    at most tau / 3 apart (every feature of the smoothed jerk is at least tau
    wide), at the middle of every piece of the profile otherwise.
    """
    m = w.shape[0]
    end = tk[m] + tau
    if exact:
        times = _sample_times(tk, tau, True)
    elif 3.0 * end > tau * lim.n_search:  # the jerk's features (>= tau wide) need more
        times = _sample_times(tk, tau, False)
    else:
        times = (np.arange(lim.n_search) + 0.5) * (end / lim.n_search)
    dr = np.empty(N_DER)
    tmp = np.empty(2)
    ia = 0
    ib = 0
    g = 0
    rv = 0.0
    ra = 0.0
    rj = 0.0
    for k in range(times.shape[0]):
        f, f1, f2, f3, ia, ib = _smoothed(times[k], tau, ia, ib, sg, x, w, tk, sk)
        while g < m - 1 and f >= sg[g + 1]:
            g += 1
        if exact:
            _exact_derivatives(kin, p0, ux, uy, branch, sg, qs, f, g, dr, tmp)
        else:
            r = min(max((f - sg[g]) / (sg[g + 1] - sg[g]), 0.0), 1.0)
            for c in range(N_DER):
                dr[c] = der[g, c] + r * (der[g + 1, c] - der[g, c])
        rv = max(rv, f1 / lim.kv, abs(dr[4]) * f1 / lim.kw)
        ra = max(ra, abs(f2) / lim.ka, abs(dr[4] * f2 + dr[5] * f1 * f1) / lim.kw_dot)
        for a in range(2):
            rv = max(rv, abs(dr[a]) * f1 / lim.vel[a])
            ra = max(ra, abs(dr[a] * f2 + dr[2 + a] * f1 * f1) / lim.acc[a])
            if lim.has_jerk:
                rj = max(rj, abs(dr[a] * f3 + 3.0 * dr[2 + a] * f1 * f2
                                 + dr[6 + a] * f1 * f1 * f1) / lim.jerk[a])
    return max(rv, math.sqrt(ra), rj ** (1.0 / 3.0))


@njit(cache=True)
def _smoothing(kin, p0, ux, uy, branch, sg, qs, der, x, w, lim):
    """(tau, lambda): the averaging width and time stretch of the fastest smoothed profile.

    The duration lambda (T + tau) is minimised over tau on a log grid (plus a
    cluster around tau = T), refined by a golden-section search on log tau
    around the best; lambda is then measured with exact derivatives.
    """
    tk, sk = profile_knots(sg, x, w)
    t1 = tk[tk.shape[0] - 1]
    lo = math.log(lim.tau_min * t1)
    hi = math.log(lim.tau_max * t1)
    # log-spaced widths, plus a linear cluster around tau = T, where the cost has a
    # narrow dip (the window then spans the whole acceleration-limited profile)
    n_near = lim.n_tau // 2
    n_all = lim.n_tau + n_near
    logs = np.empty(n_all)
    for k in range(lim.n_tau):
        logs[k] = lo + (hi - lo) * k / (lim.n_tau - 1)
    for k in range(n_near):
        logs[lim.n_tau + k] = math.log(t1 * (0.8 + 0.4 * k / max(n_near - 1, 1)))
    logs = np.sort(logs)
    costs = np.empty(n_all)
    best = 0
    for k in range(n_all):
        tau = math.exp(logs[k])
        costs[k] = _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, tau, lim,
                             False) * (t1 + tau)
        if costs[k] < costs[best]:
            best = k
    a = logs[max(best - 1, 0)]
    b = logs[min(best + 1, n_all - 1)]
    best_log = logs[best]
    best_cost = costs[best]
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    for _ in range(lim.n_golden):
        c = b - ratio * (b - a)
        e = a + ratio * (b - a)
        tc = math.exp(c)
        te = math.exp(e)
        fc = _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, tc, lim,
                       False) * (t1 + tc)
        fe = _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, te, lim,
                       False) * (t1 + te)
        if fc < best_cost:
            best_cost = fc
            best_log = c
        if fe < best_cost:
            best_cost = fe
            best_log = e
        if fc < fe:
            b = e
        else:
            a = c
    # the estimates can be fooled by narrow jerk spikes: measure the refined width and
    # the three best grid widths exactly and keep the fastest
    tau = math.exp(best_log)
    lam = _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, tau, lim, True)
    ranked = np.argsort(costs)
    for r in range(min(3, n_all)):
        cand = math.exp(logs[ranked[r]])
        lc = _slowdown(kin, p0, ux, uy, branch, sg, qs, der, x, w, tk, sk, cand, lim, True)
        if lc * (t1 + cand) < lam * (t1 + tau):
            tau = cand
            lam = lc
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
    st, sg, qs, der = line_geometry(kin, p0, p1, branch, q_start, q_end, lim.grid)
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
    tau, lam = _smoothing(kin, p0, ux, uy, branch, sg, qs, der, x, w, lim)
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
    for i in range(n):
        for j in range(i + 1, n):
            for c in range(2):
                if not (np.isfinite(q_both[i, c, 0]) and np.isfinite(q_both[j, c, 0])):
                    st = LINE_JOINT_LIMIT
                    t = np.inf
                else:
                    st, t = line_time(kin, points[i], points[j], c, q_both[i, c], q_both[j, c],
                                      lim)
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
        f, f1, f2, f3, ia, ib = _smoothed(tt, tau, ia, ib, sg, x, w, tk, sk)
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

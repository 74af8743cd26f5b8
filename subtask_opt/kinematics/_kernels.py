"""Numba kernels of the planar 2R arm: kinematics, 1-DOF profile times, time matrices.

Arrays and scalars in, arrays out; the Python wrappers in :mod:`subtask_opt.kinematics.planar`
and :mod:`subtask_opt.arm.timing.models` validate the inputs and unpack the objects.

The arm enters every kernel as ``kin``, the :class:`ArmKinematics` named tuple
built by :attr:`subtask_opt.kinematics.planar.Arm.kinematics` (numba caches it by its field types).
With the geometric angles ``t1 = a1 + s1*q1`` (upper arm direction) and
``b = a2 + s2*q2`` (elbow angle, upper arm to forearm), the tip is::

    tip = base + L1 (cos t1, sin t1) + L2 (cos(t1 + b), sin(t1 + b))

and the tool angle (yaw of the tip frame) is ``t1 + b + phi_offset``.
Elbow branch 0 ("elbow down") has ``sin b >= 0``: seen from the base looking
at the tip, the elbow lies on the clockwise (right-hand) side; branch 1
("elbow up") has ``sin b <= 0``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class ArmKinematics(NamedTuple):
    """Geometry and joint limits of a planar 2R arm, as the kernels take them (floats)."""

    base_x: float
    """Shoulder position in the plane (m)."""
    base_y: float
    l1: float
    """Upper arm length (m)."""
    l2: float
    """Forearm length (m)."""
    a1: float
    """Geometric angle of the upper arm at q1 = 0 (rad)."""
    a2: float
    """Geometric elbow angle (upper arm to forearm) at q2 = 0 (rad)."""
    s1: float
    """+1 if joint 1 turns counter-clockwise seen from +z, else -1."""
    s2: float
    """The same for joint 2."""
    phi_offset: float
    """Tool angle minus the forearm direction (rad)."""
    lower1: float
    """Joint position limits (rad)."""
    lower2: float
    upper1: float
    upper2: float


TWO_PI = 2.0 * math.pi
# Slack on |cos b| <= 1 and on joint limits, so points exactly on the rim or a
# limit (up to rounding) count as reachable.
_TOL = 1e-9


@njit(cache=True)
def wrap_angle(a: float) -> float:
    """Angle wrapped into [-pi, pi)."""
    return a - TWO_PI * math.floor((a + math.pi) / TWO_PI)


@njit(cache=True)
def trapezoid_time_nb(d: float, vmax: float, amax: float) -> float:
    """Exact minimum rest-to-rest time over distance d >= 0 (trapezoid or triangle)."""
    if d <= 0.0:
        return 0.0
    if d >= vmax * vmax / amax:
        return d / vmax + vmax / amax
    return 2.0 * math.sqrt(d / amax)


@njit(cache=True)
def scurve_time_nb(d: float, vmax: float, amax: float, jmax: float) -> float:
    """Exact minimum rest-to-rest time of the jerk-limited (7-segment) 1-DOF profile.

    Zero velocity and acceleration at both ends; symmetric limits.
    """
    if d <= 0.0:
        return 0.0
    # Time and distance to go from rest to vmax and back.
    if vmax * jmax >= amax * amax:
        t_to_v = vmax / amax + amax / jmax
    else:
        t_to_v = 2.0 * math.sqrt(vmax / jmax)
    if d >= vmax * t_to_v:
        return d / vmax + t_to_v
    # vmax not reached: peak speed vp solves vp * t_to_vp = d.
    if vmax * jmax >= amax * amax:
        # amax reached on the way to vp if vp >= amax^2 / jmax:
        # vp^2 / amax + vp * amax / jmax - d = 0.
        c = amax / jmax
        vp = 0.5 * amax * (-c + math.sqrt(c * c + 4.0 * d / amax))
        if vp >= amax * amax / jmax:
            return 2.0 * (vp / amax + amax / jmax)
    # Pure jerk phases: d = 2 jmax tj^3, T = 4 tj.
    return 4.0 * (d / (2.0 * jmax)) ** (1.0 / 3.0)


@njit(cache=True)
def unit_direction(x0: float, y0: float, x1: float, y1: float):
    """``(d, ux, uy)``: the length of the segment (x0, y0) -> (x1, y1) (> 0) and its
    unit direction."""
    dx = x1 - x0
    dy = y1 - y0
    d = math.sqrt(dx * dx + dy * dy)
    return d, dx / d, dy / d


@njit(cache=True)
def _fit_limits(q: float, lo: float, up: float) -> float:
    """Representative of q (mod 2 pi) inside [lo, up], or the wrapped q if none."""
    q = wrap_angle(q)
    if q < lo - _TOL and q + TWO_PI <= up + _TOL:
        q += TWO_PI
    elif q > up + _TOL and q - TWO_PI >= lo - _TOL:
        q -= TWO_PI
    return q


@njit(cache=True)
def _within(q: float, lo: float, up: float) -> bool:
    return lo - _TOL <= q <= up + _TOL


@njit(cache=True)
def ik_values(kin: ArmKinematics, x: float, y: float, branch: int) -> tuple[int, float, float]:
    """:func:`ik_point` as ``(status, q1, q2)``: scalars only, so a loop that calls it moves
    no array references (numba counts them, atomically, on every call)."""
    dx = x - kin.base_x
    dy = y - kin.base_y
    l1 = kin.l1
    l2 = kin.l2
    c = (dx * dx + dy * dy - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    if c > 1.0 + _TOL or c < -1.0 - _TOL:
        return 1, np.nan, np.nan
    c = min(1.0, max(-1.0, c))
    s = math.sqrt(1.0 - c * c)
    if branch == 1:
        s = -s
    b = math.atan2(s, c)
    t1 = math.atan2(dy, dx) - math.atan2(l2 * s, l1 + l2 * c)
    q1 = _fit_limits(kin.s1 * (t1 - kin.a1), kin.lower1, kin.upper1)
    q2 = _fit_limits(kin.s2 * (b - kin.a2), kin.lower2, kin.upper2)
    if not _within(q1, kin.lower1, kin.upper1):
        return 2, q1, q2
    if not _within(q2, kin.lower2, kin.upper2):
        return 3, q1, q2
    return 0, q1, q2


@njit(cache=True)
def ik_point(kin: ArmKinematics, x: float, y: float, branch: int, out: np.ndarray) -> int:
    """Analytic IK of one point on one branch into ``out`` (2,).

    Returns 0 if feasible, 1 if the point is outside the annulus, 2 if the
    branch breaks joint 1's limit, 3 joint 2's (``out`` still holds the
    closest representatives then).
    """
    status, q1, q2 = ik_values(kin, x, y, branch)
    out[0] = q1
    out[1] = q2
    return status


@njit(cache=True)
def ik_batch(kin: ArmKinematics, xy: np.ndarray, respect_limits: bool):
    """IK of M points on both branches.

    Returns ``(q, status)``: q (M, 2, 2) with q[m, branch] the joint vector
    (NaN where infeasible if ``respect_limits``), status (M, 2) int codes of
    :func:`ik_point`.
    """
    m = xy.shape[0]
    q = np.empty((m, 2, 2))
    status = np.empty((m, 2), dtype=np.int64)
    tmp = np.empty(2)
    for i in range(m):
        for br in range(2):
            st = ik_point(kin, xy[i, 0], xy[i, 1], br, tmp)
            status[i, br] = st
            if st != 0 and respect_limits:
                q[i, br, 0] = np.nan
                q[i, br, 1] = np.nan
            else:
                q[i, br, 0] = tmp[0]
                q[i, br, 1] = tmp[1]
    return q, status


@njit(cache=True)
def fk_batch(kin: ArmKinematics, q: np.ndarray) -> np.ndarray:
    """Analytic FK: q (M, 2) -> (M, 3) rows (x, y, tool angle in [-pi, pi))."""
    m = q.shape[0]
    out = np.empty((m, 3))
    for i in range(m):
        t1 = kin.a1 + kin.s1 * q[i, 0]
        t12 = t1 + kin.a2 + kin.s2 * q[i, 1]
        out[i, 0] = kin.base_x + kin.l1 * math.cos(t1) + kin.l2 * math.cos(t12)
        out[i, 1] = kin.base_y + kin.l1 * math.sin(t1) + kin.l2 * math.sin(t12)
        out[i, 2] = wrap_angle(t12 + kin.phi_offset)
    return out


@njit(cache=True)
def jacobian_point(kin: ArmKinematics, q1: float, q2: float, out: np.ndarray) -> None:
    """Analytic 2x2 position Jacobian d(x, y)/d(q1, q2) into ``out``."""
    t1 = kin.a1 + kin.s1 * q1
    t12 = t1 + kin.a2 + kin.s2 * q2
    l1 = kin.l1
    l2 = kin.l2
    out[0, 0] = kin.s1 * (-l1 * math.sin(t1) - l2 * math.sin(t12))
    out[1, 0] = kin.s1 * (l1 * math.cos(t1) + l2 * math.cos(t12))
    out[0, 1] = kin.s2 * (-l2 * math.sin(t12))
    out[1, 1] = kin.s2 * (l2 * math.cos(t12))


@njit(cache=True)
def jacobian_batch(kin: ArmKinematics, q: np.ndarray) -> np.ndarray:
    """Analytic Jacobians of q (M, 2) -> (M, 2, 2)."""
    out = np.empty((q.shape[0], 2, 2))
    for i in range(q.shape[0]):
        jacobian_point(kin, q[i, 0], q[i, 1], out[i])
    return out


@njit(cache=True)
def _tool_angle(kin: ArmKinematics, q1: float, q2: float) -> float:
    return wrap_angle(kin.a1 + kin.s1 * q1 + kin.a2 + kin.s2 * q2 + kin.phi_offset)


@njit(cache=True)
def cartesian_matrix(points: np.ndarray, phi: np.ndarray, configs: np.ndarray,
                     kin: ArmKinematics, kv: float, ka: float, kw: float, kw_dot: float,
                     paper: bool, k: float, interpolate_phi: bool) -> np.ndarray:
    """N x N rest-to-rest times of the Cartesian models.

    ``paper=False``: exact trapezoids of the translation |Pj - Pi| (Kv, Ka) and of
    the rotation |wrap(phi_j - phi_i)| (Kw, Kw_dot), synchronised (the max).
    ``paper=True``: eq. (6)-(19) with via-points at fraction k; the tool angles
    at the via-points come from IK on the endpoint's branch (or, with
    ``interpolate_phi``, from the given tool angles interpolated linearly);
    a via-point outside the workspace falls back to its endpoint's angle.
    """
    n = points.shape[0]
    out = np.zeros((n, n))
    tmp = np.empty(2)
    for i in range(n):
        for j in range(i + 1, n):
            dx = points[j, 0] - points[i, 0]
            dy = points[j, 1] - points[i, 1]
            d = math.sqrt(dx * dx + dy * dy)
            dphi = wrap_angle(phi[j] - phi[i])
            if not paper:
                t = max(trapezoid_time_nb(d, kv, ka), trapezoid_time_nb(abs(dphi), kw, kw_dot))
            else:
                if interpolate_phi:
                    phi_a = phi[i] + k * dphi
                    phi_d = phi[j] - k * dphi
                else:
                    phi_a = phi[i]
                    if ik_point(kin, points[i, 0] + k * dx, points[i, 1] + k * dy,
                                configs[i], tmp) == 0:
                        phi_a = _tool_angle(kin, tmp[0], tmp[1])
                    phi_d = phi[j]
                    if ik_point(kin, points[j, 0] - k * dx, points[j, 1] - k * dy,
                                configs[j], tmp) == 0:
                        phi_d = _tool_angle(kin, tmp[0], tmp[1])
                lin = (1.0 - 2.0 * k) * d  # |P_d - P_a|
                theta = abs(wrap_angle(phi_d - phi_a))  # eq. (14) for rotations about z
                t_lin = max(lin / kv, theta / kw)  # eq. (17)
                if t_lin > 0.0:
                    v_lin = lin / t_lin
                    w_lin = theta / t_lin
                    t_acc = max(v_lin / ka, w_lin / kw_dot)  # eq. (18)
                    t = 2.0 * t_acc + t_lin  # eq. (19)
                else:
                    t = 0.0
            out[i, j] = t
            out[j, i] = t
    return out


@njit(cache=True)
def _check_leg(i: int, j: int, points: np.ndarray, q: np.ndarray, phi: np.ndarray,
               configs: np.ndarray, kin: ArmKinematics, vel: np.ndarray, kv: float, ka: float,
               kw: float, kw_dot: float, n_samples: int, qs: np.ndarray,
               jac: np.ndarray) -> tuple[bool, float]:
    """The straight leg i -> j (i < j) driven as in :func:`leg_check`: (the arm
    cannot follow the line, max |q_dot| / velocity limit)."""
    if configs[i] != configs[j]:  # switching branch needs the singular rim
        return True, np.inf
    d, ux, uy = unit_direction(points[i, 0], points[i, 1], points[j, 0], points[j, 1])
    br = configs[i]
    # The radius along a line is convex: the point closest to the base
    # decides the inner disc and the elbow limit exactly.
    s_c = (kin.base_x - points[i, 0]) * ux + (kin.base_y - points[i, 1]) * uy
    if 0.0 < s_c < d:
        if ik_point(kin, points[i, 0] + s_c * ux, points[i, 1] + s_c * uy, br, qs) != 0:
            return True, np.inf
    t_tr = trapezoid_time_nb(d, kv, ka)
    t_rot = trapezoid_time_nb(abs(wrap_angle(phi[j] - phi[i])), kw, kw_dot)
    scale = t_tr / max(t_tr, t_rot)  # uniform time scaling of the slower leg
    worst = 0.0
    prev0 = q[i, 0]
    prev1 = q[i, 1]
    for m in range(1, n_samples):
        s = d * m / n_samples
        if ik_point(kin, points[i, 0] + s * ux, points[i, 1] + s * uy, br, qs) == 1:
            return True, np.inf
        # Follow the branch continuously: the joints may not jump by 2 pi.
        q0 = qs[0] + TWO_PI * round((prev0 - qs[0]) / TWO_PI)
        q1 = qs[1] + TWO_PI * round((prev1 - qs[1]) / TWO_PI)
        if not (_within(q0, kin.lower1, kin.upper1) and _within(q1, kin.lower2, kin.upper2)):
            return True, np.inf
        prev0 = q0
        prev1 = q1
        sdot = scale * min(kv, math.sqrt(2.0 * ka * s), math.sqrt(2.0 * ka * (d - s)))
        jacobian_point(kin, q0, q1, jac)
        det = jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0]
        if det == 0.0:
            worst = np.inf
        else:
            qd0 = (jac[1, 1] * ux - jac[0, 1] * uy) * sdot / det
            qd1 = (-jac[1, 0] * ux + jac[0, 0] * uy) * sdot / det
            worst = max(worst, abs(qd0) / vel[0], abs(qd1) / vel[1])
    # Arriving at q_j (or q_j + 2 pi n if the joint's range allows) within the limits.
    q0 = q[j, 0] + TWO_PI * round((prev0 - q[j, 0]) / TWO_PI)
    q1 = q[j, 1] + TWO_PI * round((prev1 - q[j, 1]) / TWO_PI)
    if not (_within(q0, kin.lower1, kin.upper1) and _within(q1, kin.lower2, kin.upper2)):
        return True, np.inf
    return False, worst


@njit(cache=True)
def leg_check(points: np.ndarray, q: np.ndarray, phi: np.ndarray, configs: np.ndarray,
              kin: ArmKinematics, vel: np.ndarray, kv: float, ka: float, kw: float,
              kw_dot: float, n_samples: int, starts: np.ndarray, ends: np.ndarray):
    """Drive the straight legs starts[k] - ends[k] with the synchronised Cartesian
    trapezoid and check the joints.

    Returns ``(infeasible, ratio)``, both (M,): infeasible where the line
    leaves the workspace of the endpoints' branch (inner disc, a joint limit,
    a change of branch), else ratio = max over interior samples and joints of
    |q_dot| / velocity limit, with q_dot = J^-1 u s_dot (inf where infeasible).
    A leg is driven from its lower index, so i -> j and j -> i agree; i -> i is 0.
    """
    m = starts.shape[0]
    infeasible = np.zeros(m, dtype=np.bool_)
    ratio = np.zeros(m)
    qs = np.empty(2)
    jac = np.empty((2, 2))
    for k in range(m):
        i, j = min(starts[k], ends[k]), max(starts[k], ends[k])
        if i == j:
            continue
        infeasible[k], ratio[k] = _check_leg(i, j, points, q, phi, configs, kin, vel, kv, ka,
                                             kw, kw_dot, n_samples, qs, jac)
    return infeasible, ratio


@njit(cache=True)
def joint_tensor(q_both: np.ndarray, vel: np.ndarray, acc: np.ndarray, jerk: np.ndarray,
                 has_jerk: bool) -> np.ndarray:
    """(N, 2, N, 2) joint-space rest-to-rest times between every pair of configurations.

    ``out[i, ci, j, cj]`` is the time from subtask i on branch ci to subtask j
    on branch cj (inf where a branch does not reach its subtask: NaN rows of
    ``q_both``, (N, 2 branches, 2 joints)).
    """
    n = q_both.shape[0]
    out = np.zeros((n, 2, n, 2))
    for i in range(n):
        for ci in range(2):
            for j in range(n):
                for cj in range(2):
                    if i == j and ci == cj:
                        continue
                    t = 0.0
                    for a in range(2):
                        d = abs(q_both[j, cj, a] - q_both[i, ci, a])
                        if not math.isfinite(d):
                            t = np.inf
                            break
                        if has_jerk:
                            ta = scurve_time_nb(d, vel[a], acc[a], jerk[a])
                        else:
                            ta = trapezoid_time_nb(d, vel[a], acc[a])
                        t = max(t, ta)
                    out[i, ci, j, cj] = t
    return out

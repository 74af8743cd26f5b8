"""Rest-to-rest joint-space leg times of an n-joint arm.

Two models of the same move q_a -> q_b (every joint starts and ends at rest):

* :func:`trapezoid_leg_times` - the synchronised trapezoid, closed form: every
  joint follows the same time profile s(t) from 0 to 1 scaled by its distance
  ``d_j`` (phase synchronisation: the move is a straight line in joint space,
  which is what the leg collision sweep checks), so s may move at most
  ``V = min_j v_j / d_j`` and accelerate at most ``A = min_j a_j / d_j``; the
  time is ``2 / sqrt(A)`` when full speed is never reached (``V^2 / A >= 1``)
  and ``1 / V + V / A`` otherwise. With jerk limits, s also jerks at most
  ``J = min_j j_j / d_j`` and the time is the exact 7-segment profile's
  (:func:`~subtask_opt.arm._kinematics_kernels.scurve_time_nb`). Vectorised: an (a, n)
  by (b, n) pair of configuration sets gives the (a, b) matrix of leg times in one numba
  kernel. This is the time model the sequencer searches with: the ``joint`` model.
* :func:`ruckig_leg_time` - ruckig's time-optimal profile of the same
  straight joint line with the arm's jerk limits (the executed time,
  :class:`StraightLeg`): equal to the first to round-off, so the time the search
  optimises is the time the trajectory drives (``tests/arm/test_serial.py``).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from subtask_opt.arm._kinematics_kernels import scurve_time_nb
from subtask_opt.base.errors import ParameterError


class JointLimits(NamedTuple):
    """Per-joint velocity, acceleration and jerk limits, (n,) float64 each, > 0; ``jerk``
    empty (0,) when the arm has none."""

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray = np.zeros(0)


def joint_limits(velocity: Any, acceleration: Any, jerk: Any = None) -> JointLimits:
    """Validated :class:`JointLimits` (ParameterError naming the bad field)."""
    v = np.ascontiguousarray(velocity, dtype=np.float64)
    a = np.ascontiguousarray(acceleration, dtype=np.float64)
    j = np.zeros(0) if jerk is None else np.ascontiguousarray(jerk, dtype=np.float64)
    for name, arr in (("velocity", v), ("acceleration", a), ("jerk", j)):
        if name == "jerk" and jerk is None:
            continue
        if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise ParameterError(f"JointLimits.{name} must be a non-empty list of finite "
                                 f"values > 0, got {arr.tolist()}")
    if v.shape != a.shape or (jerk is not None and j.shape != v.shape):
        raise ParameterError(f"JointLimits.velocity, acceleration and jerk must have the same "
                             f"length, got {v.size}, {a.size} and {j.size}")
    return JointLimits(v, a, j)


@njit(cache=True, inline="always")
def _leg_time(qa, r, qb, c, inv_v, inv_a, inv_j):
    tv = 0.0  # 1 / V: the path parameter's speed limit
    ta = 0.0  # 1 / A: its acceleration limit
    tj = 0.0  # 1 / J: its jerk limit (when the arm has jerk limits)
    jerk = inv_j.shape[0] > 0
    for j in range(inv_v.shape[0]):
        d = abs(qb[c, j] - qa[r, j])
        x = d * inv_v[j]
        if x > tv:
            tv = x
        y = d * inv_a[j]
        if y > ta:
            ta = y
        if jerk:
            z = d * inv_j[j]
            if z > tj:
                tj = z
    out = 0.0
    if tv == 0.0:
        out = 0.0
    elif jerk:
        out = scurve_time_nb(1.0, 1.0 / tv, 1.0 / ta, 1.0 / tj)
    elif ta >= tv * tv:  # full speed never reached: a triangle
        out = 2.0 * math.sqrt(ta)
    else:
        out = tv + ta / tv
    return out


@njit(cache=True)
def _trapezoid_matrix(qa, qb, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    out = np.empty((qa.shape[0], qb.shape[0]))
    for r in range(qa.shape[0]):
        for c in range(qb.shape[0]):
            out[r, c] = _leg_time(qa, r, qb, c, inv_v, inv_a, inv_j)
    return out


@njit(cache=True)
def _trapezoid_square(q, limits):
    """The (m, m) matrix of q to itself: the upper triangle, mirrored tile by tile
    (exactly symmetric; half the arithmetic, and the tiles keep the mirror writes local)."""
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    m = q.shape[0]
    out = np.empty((m, m))
    tile = 64
    for r0 in range(0, m, tile):
        for c0 in range(r0, m, tile):
            for r in range(r0, min(r0 + tile, m)):
                for c in range(max(c0, r), min(c0 + tile, m)):
                    t = _leg_time(q, r, q, c, inv_v, inv_a, inv_j)
                    out[r, c] = t
                    out[c, r] = t
    return out


def trapezoid_square(q: Any, limits: JointLimits) -> np.ndarray:
    """(m, m) synchronised trapezoid times between every pair of the configurations
    ``q`` (m, n): :func:`trapezoid_leg_times` of ``q`` to itself, exactly symmetric."""
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=np.float64)))
    n = limits.velocity.shape[0]
    if a.ndim != 2 or a.shape[1] != n or not np.all(np.isfinite(a)):
        raise ParameterError(f"trapezoid_square needs finite (m, {n}) configurations, "
                             f"got shape {a.shape}")
    return _trapezoid_square(a, limits)  # type: ignore[no-any-return]


def trapezoid_leg_times(qa: Any, qb: Any, limits: JointLimits) -> np.ndarray:
    """(a, b) synchronised trapezoid times of every leg ``qa[r] -> qb[c]`` (see module doc).

    Args:
        qa: (a, n) or (n,) start configurations.
        qb: (b, n) or (n,) end configurations.
        limits: the joints' velocity and acceleration limits.
    """
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(qa, dtype=np.float64)))
    b = np.ascontiguousarray(np.atleast_2d(np.asarray(qb, dtype=np.float64)))
    n = limits.velocity.shape[0]
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != n or b.shape[1] != n:
        raise ParameterError(f"trapezoid_leg_times needs (a, {n}) and (b, {n}) configurations, "
                             f"got {a.shape} and {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ParameterError("trapezoid_leg_times: configurations must be finite")
    return _trapezoid_matrix(a, b, limits)  # type: ignore[no-any-return]


class StraightLeg:
    """A rest-to-rest straight joint line q0 + (q1 - q0) s(t), s from 0 to 1 by ruckig.

    ``s`` is ruckig's time-optimal 1-D profile under the tightest scaled limits
    (``min_j v_j / d_j``, ``min_j a_j / d_j``, ``min_j jerk_j / d_j``), so every joint
    keeps its limits and the arm stays on the line the collision sweep checked.
    """

    def __init__(self, q0: np.ndarray, q1: np.ndarray, traj: Any) -> None:
        self.q0 = q0
        self.dq = q1 - q0
        self._traj = traj
        self.duration = float(traj.duration)

    def at_time(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (n,), at leg time t (s)."""
        p, v, a = self._traj.at_time(float(t))
        return self.q0 + self.dq * p[0], self.dq * v[0], self.dq * a[0]


def ruckig_trajectory(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                      jerk: Any = None) -> StraightLeg:
    """Time-optimal rest-to-rest straight joint line q0 -> q1 (:class:`StraightLeg`).

    ``jerk`` None: no jerk limit (a trapezoid). ParameterError if the two are equal
    or ruckig cannot plan the move.
    """
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    a = np.asarray(q0, dtype=np.float64)
    b = np.asarray(q1, dtype=np.float64)
    d = np.abs(b - a)
    if not d.any():
        raise ParameterError("ruckig_trajectory: q0 and q1 are the same")
    moving = d > 0
    v_s = float(np.min(np.asarray(velocity, dtype=np.float64)[moving] / d[moving]))
    a_s = float(np.min(np.asarray(acceleration, dtype=np.float64)[moving] / d[moving]))
    j_s = (math.inf if jerk is None
           else float(np.min(np.asarray(jerk, dtype=np.float64)[moving] / d[moving])))
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [1.0]
    inp.current_velocity = [0.0]
    inp.current_acceleration = [0.0]
    inp.target_velocity = [0.0]
    inp.target_acceleration = [0.0]
    inp.max_velocity = [v_s]
    inp.max_acceleration = [a_s]
    inp.max_jerk = [j_s]
    traj = Trajectory(1)
    status = otg.calculate(inp, traj)
    if status not in (Result.Working, Result.Finished):
        raise ParameterError(f"ruckig cannot plan the joint move {a.tolist()} -> "
                             f"{b.tolist()}: {status}")
    return StraightLeg(a, b, traj)


def ruckig_leg_time(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                    jerk: Any = None) -> float:
    """Duration (s) of :func:`ruckig_trajectory` (0 for q0 == q1)."""
    if np.array_equal(np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)):
        return 0.0
    return float(ruckig_trajectory(q0, q1, velocity, acceleration, jerk).duration)


__all__ = ["JointLimits", "StraightLeg", "joint_limits", "ruckig_leg_time", "ruckig_trajectory",
           "trapezoid_square",
           "trapezoid_leg_times"]

"""Rest-to-rest joint-space leg times of an n-joint arm.

Two models of the same move q_a -> q_b (every joint starts and ends at rest):

* :func:`trapezoid_leg_times` - the synchronised trapezoid, closed form: every
  joint follows the same time profile s(t) from 0 to 1 scaled by its distance
  ``d_j`` (phase synchronisation: the move is a straight line in joint space,
  which is what the leg collision sweep checks), so s may move at most
  ``V = min_j v_j / d_j`` and accelerate at most ``A = min_j a_j / d_j``; the
  time is ``2 / sqrt(A)`` when full speed is never reached (``V^2 / A >= 1``)
  and ``1 / V + V / A`` otherwise. Vectorised: an (a, n) by (b, n) pair of configuration sets gives
  the (a, b) matrix of leg times in one numba kernel. This is the time model
  the sequencer searches with.
* :func:`ruckig_leg_time` - ruckig's time-optimal profile of the same
  straight joint line with the arm's jerk limits (the executed time,
  :class:`StraightLeg`); without jerk limits it equals the trapezoid time (to
  round-off), with them it is longer.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError


class JointLimits(NamedTuple):
    """Per-joint velocity and acceleration limits, (n,) float64 each, > 0."""

    velocity: np.ndarray
    acceleration: np.ndarray


def joint_limits(velocity: Any, acceleration: Any) -> JointLimits:
    """Validated :class:`JointLimits` (ParameterError naming the bad field)."""
    v = np.ascontiguousarray(velocity, dtype=np.float64)
    a = np.ascontiguousarray(acceleration, dtype=np.float64)
    for name, arr in (("velocity", v), ("acceleration", a)):
        if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise ParameterError(f"JointLimits.{name} must be a non-empty list of finite "
                                 f"values > 0, got {arr.tolist()}")
    if v.shape != a.shape:
        raise ParameterError(f"JointLimits.velocity and acceleration must have the same "
                             f"length, got {v.size} and {a.size}")
    return JointLimits(v, a)


@njit(cache=True, inline="always")
def _leg_time(qa, r, qb, c, inv_v, inv_a):
    tv = 0.0  # 1 / V: the path parameter's speed limit
    ta = 0.0  # 1 / A: its acceleration limit
    for j in range(inv_v.shape[0]):
        d = abs(qb[c, j] - qa[r, j])
        x = d * inv_v[j]
        if x > tv:
            tv = x
        y = d * inv_a[j]
        if y > ta:
            ta = y
    if tv == 0.0:
        return 0.0
    if ta >= tv * tv:  # full speed never reached: a triangle
        return 2.0 * math.sqrt(ta)
    return tv + ta / tv


@njit(cache=True)
def _trapezoid_matrix(qa, qb, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    out = np.empty((qa.shape[0], qb.shape[0]))
    for r in range(qa.shape[0]):
        for c in range(qb.shape[0]):
            out[r, c] = _leg_time(qa, r, qb, c, inv_v, inv_a)
    return out


@njit(cache=True)
def _trapezoid_square(q, limits):
    """The (m, m) matrix of q to itself: the upper triangle, mirrored tile by tile
    (exactly symmetric; half the arithmetic, and the tiles keep the mirror writes local)."""
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    m = q.shape[0]
    out = np.empty((m, m))
    tile = 64
    for r0 in range(0, m, tile):
        for c0 in range(r0, m, tile):
            for r in range(r0, min(r0 + tile, m)):
                for c in range(max(c0, r), min(c0 + tile, m)):
                    t = _leg_time(q, r, q, c, inv_v, inv_a)
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

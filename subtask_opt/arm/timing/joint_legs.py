"""Rest-to-rest joint-space leg times of an n-joint arm.

Two models of the same move q_a -> q_b (every joint starts and ends at rest):

* :func:`trapezoid_leg_times` - the synchronised per-joint trapezoid, closed
  form: joint j alone needs ``T_j = 2 sqrt(d_j / a_j)`` when its distance
  ``d_j <= v_j^2 / a_j`` (it never reaches full speed) and
  ``T_j = d_j / v_j + v_j / a_j`` otherwise; the synchronised move takes
  ``T = max_j T_j`` (the other joints are slowed down to finish with the
  slowest). Vectorised: an (a, n) by (b, n) pair of configuration sets gives
  the (a, b) matrix of leg times in one numba kernel. This is the time model
  the sequencer searches with.
* :func:`ruckig_leg_time` - ruckig's time-optimal synchronised profile with
  the arm's jerk limits (the executed time); without jerk limits it equals the
  trapezoid time (to round-off), with them it is longer.
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


@njit(cache=True)
def _trapezoid_matrix(qa, qb, limits):
    v = limits.velocity
    acc = limits.acceleration
    n = v.shape[0]
    # joint j reaches full speed beyond the distance v^2 / a
    full = np.empty(n)
    for j in range(n):
        full[j] = v[j] * v[j] / acc[j]
    out = np.empty((qa.shape[0], qb.shape[0]))
    for r in range(qa.shape[0]):
        for c in range(qb.shape[0]):
            t = 0.0
            for j in range(n):
                d = abs(qb[c, j] - qa[r, j])
                if d <= full[j]:
                    tj = 2.0 * math.sqrt(d / acc[j])
                else:
                    tj = d / v[j] + v[j] / acc[j]
                if tj > t:
                    t = tj
            out[r, c] = t
    return out


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


def ruckig_trajectory(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                      jerk: Any = None) -> Any:
    """Ruckig's time-optimal rest-to-rest ``Trajectory`` q0 -> q1 (offline API).

    ``jerk`` None: no jerk limit (a trapezoid per joint). ParameterError if
    ruckig cannot plan the move.
    """
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    a = np.asarray(q0, dtype=np.float64)
    b = np.asarray(q1, dtype=np.float64)
    n = a.size
    otg = Ruckig(n)
    inp = InputParameter(n)
    inp.current_position = a.tolist()
    inp.target_position = b.tolist()
    inp.current_velocity = [0.0] * n
    inp.current_acceleration = [0.0] * n
    inp.target_velocity = [0.0] * n
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = [float(x) for x in velocity]
    inp.max_acceleration = [float(x) for x in acceleration]
    inp.max_jerk = [math.inf] * n if jerk is None else [float(x) for x in jerk]
    traj = Trajectory(n)
    status = otg.calculate(inp, traj)
    if status not in (Result.Working, Result.Finished):
        raise ParameterError(f"ruckig cannot plan the joint move {a.tolist()} -> "
                             f"{b.tolist()}: {status}")
    return traj


def ruckig_leg_time(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                    jerk: Any = None) -> float:
    """Duration (s) of :func:`ruckig_trajectory` (0 for q0 == q1)."""
    if np.array_equal(np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)):
        return 0.0
    return float(ruckig_trajectory(q0, q1, velocity, acceleration, jerk).duration)


__all__ = ["JointLimits", "joint_limits", "ruckig_leg_time", "ruckig_trajectory",
           "trapezoid_leg_times"]

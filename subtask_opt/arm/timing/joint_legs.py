"""Rest-to-rest joint moves of an n-joint arm: the ``joint`` time model and its execution.

The ``joint`` model is the same move on every robot: each joint follows its own
time-optimal rest-to-rest profile under its velocity, acceleration and (where the arm has
them) jerk limits, stretched so that every joint starts and stops together (ruckig's time
synchronisation). Its duration is the slowest joint's minimum time,
``max_j T(|q_b,j - q_a,j|; v_j, a_j, jerk_j)``, with ``T`` the exact trapezoid, or with
jerk limits the exact 7-segment profile's time
(:func:`~subtask_opt.arm._kinematics_kernels.scurve_time_nb`).

* :func:`joint_leg_times` / :func:`joint_leg_square` - that time, vectorised: an (a, n) by
  (b, n) pair of configuration sets gives the (a, b) matrix of leg times in one numba
  kernel. This is what the sequencer searches with (a planar arm's ``joint`` model is the
  same formula, :func:`~subtask_opt.arm._kinematics_kernels.joint_tensor`).
* :func:`joint_move` - ruckig's time-synchronised profile of the same move (offline API),
  the executed trajectory of a leg (:class:`JointMove`): its duration equals the planned
  time to round-off, so the time the search optimises is the time the trajectory drives
  (``tests/arm/test_serial_problem.py``). Every joint moves monotonically from its start
  to its goal (no overshoot, no reversal; tested), which is what the collision sweep of a
  leg relies on (:meth:`~subtask_opt.arm.scene.CollisionChecker.leg_samples`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from subtask_opt.arm._kinematics_kernels import scurve_time_nb, trapezoid_time_nb
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
def _leg_time(qa, r, qb, c, velocity, acceleration, jerk):
    out = 0.0
    limited = jerk.shape[0] > 0
    for j in range(velocity.shape[0]):
        d = abs(qb[c, j] - qa[r, j])
        if limited:
            t = scurve_time_nb(d, velocity[j], acceleration[j], jerk[j])
        else:
            t = trapezoid_time_nb(d, velocity[j], acceleration[j])
        if t > out:
            out = t
    return out


@njit(cache=True)
def _leg_matrix(qa, qb, limits):
    out = np.empty((qa.shape[0], qb.shape[0]))
    for r in range(qa.shape[0]):
        for c in range(qb.shape[0]):
            out[r, c] = _leg_time(qa, r, qb, c, limits.velocity, limits.acceleration,
                                  limits.jerk)
    return out


@njit(cache=True)
def _leg_square(q, limits):
    """The (m, m) matrix of q to itself: the upper triangle, mirrored tile by tile
    (exactly symmetric; half the arithmetic, and the tiles keep the mirror writes local)."""
    m = q.shape[0]
    out = np.empty((m, m))
    tile = 64
    for r0 in range(0, m, tile):
        for c0 in range(r0, m, tile):
            for r in range(r0, min(r0 + tile, m)):
                for c in range(max(c0, r), min(c0 + tile, m)):
                    t = _leg_time(q, r, q, c, limits.velocity, limits.acceleration,
                                  limits.jerk)
                    out[r, c] = t
                    out[c, r] = t
    return out


def joint_leg_square(q: Any, limits: JointLimits) -> np.ndarray:
    """(m, m) ``joint`` times between every pair of the configurations ``q`` (m, n):
    :func:`joint_leg_times` of ``q`` to itself, exactly symmetric."""
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=np.float64)))
    n = limits.velocity.shape[0]
    if a.ndim != 2 or a.shape[1] != n or not np.all(np.isfinite(a)):
        raise ParameterError(f"joint_leg_square needs finite (m, {n}) configurations, "
                             f"got shape {a.shape}")
    return _leg_square(a, limits)  # type: ignore[no-any-return]


def joint_leg_times(qa: Any, qb: Any, limits: JointLimits) -> np.ndarray:
    """(a, b) ``joint`` times of every leg ``qa[r] -> qb[c]`` (see module doc).

    Args:
        qa: (a, n) or (n,) start configurations.
        qb: (b, n) or (n,) end configurations.
        limits: the joints' velocity, acceleration and jerk limits.
    """
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(qa, dtype=np.float64)))
    b = np.ascontiguousarray(np.atleast_2d(np.asarray(qb, dtype=np.float64)))
    n = limits.velocity.shape[0]
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != n or b.shape[1] != n:
        raise ParameterError(f"joint_leg_times needs (a, {n}) and (b, {n}) configurations, "
                             f"got {a.shape} and {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ParameterError("joint_leg_times: configurations must be finite")
    return _leg_matrix(a, b, limits)  # type: ignore[no-any-return]


class JointMove:
    """One executed rest-to-rest joint move q0 -> q1 (:func:`joint_move`).

    Attributes:
        q0, q1: (n,) start and goal.
        duration: its duration (s); 0 when q0 == q1.
    """

    def __init__(self, q0: np.ndarray, q1: np.ndarray, profile: Any) -> None:
        self.q0 = q0
        self.q1 = q1
        self._profile = profile
        self.duration = 0.0 if profile is None else float(profile.duration)

    def states(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (T, n), at move times t (s, clamped to [0, duration])."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        n = self.q0.size
        if self._profile is None:
            zero = np.zeros((t.size, n))
            return np.tile(self.q0, (t.size, 1)), zero, zero.copy()
        out = [self._profile.at_time(float(tk)) for tk in t]
        return tuple(np.array([o[i] for o in out], dtype=np.float64).reshape(-1, n)
                     for i in range(3))  # type: ignore[return-value]

    def positions(self, t: Any) -> np.ndarray:
        """(T, n) joint positions at move times t (s)."""
        return self.states(t)[0]


def joint_move(q0: Any, q1: Any, velocity: Any, acceleration: Any,
               jerk: Any = None) -> JointMove:
    """Ruckig's time-optimal, time-synchronised rest-to-rest move q0 -> q1.

    ``jerk`` None: no jerk limit (trapezoids). ParameterError if ruckig cannot plan it.
    """
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    a = np.array(q0, dtype=np.float64).ravel()
    b = np.array(q1, dtype=np.float64).ravel()
    if np.array_equal(a, b):
        return JointMove(a, b, None)
    n = a.size
    otg = Ruckig(n)
    inp = InputParameter(n)
    inp.current_position = a.tolist()
    inp.target_position = b.tolist()
    inp.current_velocity = [0.0] * n
    inp.current_acceleration = [0.0] * n
    inp.target_velocity = [0.0] * n
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = np.broadcast_to(np.asarray(velocity, dtype=np.float64), (n,)).tolist()
    inp.max_acceleration = np.broadcast_to(np.asarray(acceleration, dtype=np.float64),
                                           (n,)).tolist()
    inp.max_jerk = ([math.inf] * n if jerk is None
                    else np.broadcast_to(np.asarray(jerk, dtype=np.float64), (n,)).tolist())
    profile = Trajectory(n)
    status = otg.calculate(inp, profile)
    if status not in (Result.Working, Result.Finished):
        raise ParameterError(f"ruckig cannot plan the joint move {a.tolist()} -> "
                             f"{b.tolist()}: {status}")
    return JointMove(a, b, profile)


def ruckig_leg_time(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                    jerk: Any = None) -> float:
    """Duration (s) of :func:`joint_move` (0 for q0 == q1)."""
    return joint_move(q0, q1, velocity, acceleration, jerk).duration


__all__ = ["JointLimits", "JointMove", "joint_leg_square", "joint_leg_times", "joint_limits",
           "joint_move", "ruckig_leg_time"]

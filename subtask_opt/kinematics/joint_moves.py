"""Rest-to-rest joint moves of an n-joint arm: the ``joint`` time model and its execution.

The ``joint`` model on every robot: every joint starts and ends at rest together, each
time-optimal under its velocity, acceleration and (where the arm has them) jerk limits,
and the time the search plans is the time ruckig executes (to round-off). How the joints
are synchronised is the one choice, and it follows from what can be hit:

* ``phase`` (serial arms, whose cells and links are collision-checked): every joint
  follows the same time profile s(t) from 0 to 1 scaled by its distance ``d_j``, so the
  move is the straight joint-space line the collision sweep checks
  (:meth:`~subtask_opt.cell.scene.CollisionChecker.leg_in_collision`); s may move at most
  ``V = min_j v_j / d_j``, accelerate at most ``A = min_j a_j / d_j`` (and jerk at most
  ``J = min_j j_j / d_j``). The time is ``2 / sqrt(A)`` when full speed is never reached
  (``V^2 / A >= 1``) and ``1 / V + V / A`` otherwise; with jerk limits the exact
  7-segment profile's (:func:`~subtask_opt.kinematics._kernels.scurve_time_nb`).
* ``time`` (planar arms, nothing to collide with: the thesis' model): each joint its own
  profile, stretched to end with the slowest, ``max_j T(d_j; v_j, a_j, j_j)``
  (:func:`~subtask_opt.kinematics._kernels.joint_tensor`). Never longer than the
  phase-synchronised move; equal when the limits are proportional. Measured on the UR5
  box cell (``benchmarks/same_answers.py``): time synchronisation's curved paths put more
  legs in collision and the tour came out 37% longer (13.95 s against 10.20 s), which is
  why serial arms keep the straight line.

:func:`joint_leg_times` / :func:`joint_leg_square` give the phase-synchronised times,
vectorised in numba (an (a, n) by (b, n) pair of configuration sets gives the (a, b)
matrix); :func:`joint_move` is ruckig's executed profile of either kind
(:class:`JointMove`), ``tests/arm/test_serial_problem.py`` checks planned = executed.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError
from subtask_opt.kinematics._kernels import scurve_time_nb


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
def _leg_matrix(qa, qb, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    out = np.empty((qa.shape[0], qb.shape[0]))
    for r in range(qa.shape[0]):
        for c in range(qb.shape[0]):
            out[r, c] = _leg_time(qa, r, qb, c, inv_v, inv_a, inv_j)
    return out


@njit(cache=True)
def _leg_square(q, limits):
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


def joint_leg_square(q: Any, limits: JointLimits) -> np.ndarray:
    """(m, m) phase-synchronised times between every pair of the configurations ``q`` (m, n):
    :func:`joint_leg_times` of ``q`` to itself, exactly symmetric."""
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=np.float64)))
    n = limits.velocity.shape[0]
    if a.ndim != 2 or a.shape[1] != n or not np.all(np.isfinite(a)):
        raise ParameterError(f"joint_leg_square needs finite (m, {n}) configurations, "
                             f"got shape {a.shape}")
    return _leg_square(a, limits)  # type: ignore[no-any-return]


def joint_leg_times(qa: Any, qb: Any, limits: JointLimits) -> np.ndarray:
    """(a, b) phase-synchronised times of every leg ``qa[r] -> qb[c]`` (see module doc).

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
        phase: the joints phase-synchronised (the straight line q0 + (q1 - q0) s(t), ``s``
            a 1-D ruckig profile) rather than time-synchronised (ruckig's n-DOF profile).
        duration: its duration (s); 0 when q0 == q1.
    """

    def __init__(self, q0: np.ndarray, q1: np.ndarray, profile: Any, phase: bool) -> None:
        self.q0 = q0
        self.q1 = q1
        self.phase = phase
        self._profile = profile
        self.duration = 0.0 if profile is None else float(profile.duration)

    def states(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (T, n), at move times t (s, clamped to [0, duration])."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        n = self.q0.size
        if self._profile is None:
            zero = np.zeros((t.size, n))
            return np.tile(self.q0, (t.size, 1)), zero, zero.copy()
        out = np.array([self._profile.at_time(float(tk)) for tk in t], dtype=np.float64)
        if self.phase:  # (T, 3, 1): the path parameter's position, speed, acceleration
            dq = self.q1 - self.q0
            return self.q0 + out[:, 0] * dq, out[:, 1] * dq, out[:, 2] * dq
        return out[:, 0], out[:, 1], out[:, 2]


def joint_move(q0: Any, q1: Any, velocity: Any, acceleration: Any, jerk: Any = None, *,
               phase: bool = True) -> JointMove:
    """Ruckig's time-optimal rest-to-rest move q0 -> q1, phase- or time-synchronised
    (module doc). ``jerk`` None: no jerk limit (trapezoids). ParameterError if ruckig
    cannot plan it."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    a = np.array(q0, dtype=np.float64).ravel()
    b = np.array(q1, dtype=np.float64).ravel()
    if np.array_equal(a, b):
        return JointMove(a, b, None, phase)
    n = a.size
    limits = [np.broadcast_to(np.asarray(x, dtype=np.float64), (n,)) if x is not None
              else np.full(n, math.inf) for x in (velocity, acceleration, jerk)]
    if phase:  # the path parameter under the tightest scaled limits of the moving joints
        d = np.abs(b - a)
        moving = d > 0
        limits = [np.array([float(np.min(x[moving] / d[moving]))]) for x in limits]
        start, goal = [0.0], [1.0]
    else:
        start, goal = a.tolist(), b.tolist()
    dof = len(start)
    otg = Ruckig(dof)
    inp = InputParameter(dof)
    inp.current_position = start
    inp.target_position = goal
    inp.current_velocity = [0.0] * dof
    inp.current_acceleration = [0.0] * dof
    inp.target_velocity = [0.0] * dof
    inp.target_acceleration = [0.0] * dof
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = (x.tolist() for x in limits)
    profile = Trajectory(dof)
    status = otg.calculate(inp, profile)
    if status not in (Result.Working, Result.Finished):
        raise ParameterError(f"ruckig cannot plan the joint move {a.tolist()} -> "
                             f"{b.tolist()}: {status}")
    return JointMove(a, b, profile, phase)


def ruckig_leg_time(q0: Any, q1: Any, velocity: Any, acceleration: Any,
                    jerk: Any = None) -> float:
    """Duration (s) of :func:`joint_move` (0 for q0 == q1)."""
    return joint_move(q0, q1, velocity, acceleration, jerk).duration


__all__ = ["JointLimits", "JointMove", "joint_leg_square", "joint_leg_times", "joint_limits",
           "joint_move", "ruckig_leg_time"]

"""Executing a serial-arm tour: ruckig legs home -> targets -> home, and a validator.

:func:`serial_trajectory` turns a :class:`~subtask_opt.arm.serial_problem.SerialReport`
into a time-parameterised joint trajectory: one ruckig time-optimal
synchronised rest-to-rest profile per leg (jerk-limited when the arm has jerk
limits), stopping at every target. Its duration is the result's
``total_time``.

:func:`validate_serial_trajectory` samples it densely and checks joint
positions, velocities, accelerations and (with jerk limits) jerk against the
limits, rest at every target, collisions with the scene and the arm itself at
every sample, and that each target's configuration reaches its pose (FK).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.arm.timing.joint_legs import ruckig_trajectory
from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range

if TYPE_CHECKING:
    from subtask_opt.arm.serial_problem import SerialProblem, SerialReport

RTOL = 1e-3
"""Relative slack on velocity, acceleration and jerk limits (round-off of the profiles)."""
QTOL = 1e-7
"""Slack on joint position limits (rad)."""
MAX_SAMPLES = 2_000_000


class SerialTrajectory:
    """The joint trajectory of a serial-arm tour (ruckig's offline API style).

    Attributes:
        problem: the problem it executes.
        waypoints: (N + 2, n) home, the targets' configurations in tour order, home.
        durations: (N + 1,) leg durations (s).
        duration: total time (s).
    """

    def __init__(self, problem: SerialProblem, waypoints: np.ndarray, trajectories: list[Any],
                 durations: np.ndarray) -> None:
        self.problem = problem
        self.result: SerialReport | None = None  # the tour it executes (serial_trajectory)
        self.waypoints = waypoints
        self._trajs = trajectories
        self.durations = durations
        self.starts = np.concatenate([[0.0], np.cumsum(durations)])
        self.duration = float(self.starts[-1])

    def __repr__(self) -> str:
        return f"SerialTrajectory({len(self.durations)} legs, duration {self.duration:.4f} s)"

    def states(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (T, n), at tour times t (clamped to [0, duration])."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        n = self.waypoints.shape[1]
        q = np.empty((t.size, n))
        qd = np.zeros((t.size, n))
        qdd = np.zeros((t.size, n))
        which = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0,
                        len(self.durations) - 1)
        for s, (k, tk) in enumerate(zip(which, t, strict=True)):
            traj = self._trajs[k]
            if traj is None:  # a leg of zero length
                q[s] = self.waypoints[k]
                continue
            local = min(max(tk - self.starts[k], 0.0), self.durations[k])
            p, v, a = traj.at_time(float(local))
            q[s], qd[s], qdd[s] = p, v, a
        return q, qd, qdd

    def at_time(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint position, velocity and acceleration, each (n,), at time t (s)."""
        q, qd, qdd = self.states([t])
        return q[0], qd[0], qdd[0]

    def sample_times(self, dt: float) -> np.ndarray:
        """Every ``dt`` from 0, plus every leg boundary (sorted, unique)."""
        require_in_range("SerialTrajectory", "dt", dt, 1e-5, 10.0)
        if self.duration / dt > MAX_SAMPLES:
            raise ParameterError(f"SerialTrajectory.dt = {dt:g} s gives more than "
                                 f"{MAX_SAMPLES} samples for {self.duration:.4g} s")
        grid = np.arange(int(math.floor(self.duration / dt)) + 1) * dt
        return np.union1d(grid, self.starts)

    def tool_positions(self, q: np.ndarray) -> np.ndarray:
        """(T, 3) tool-tip positions at joint rows q (Pinocchio FK)."""
        arm = self.problem.arm
        return np.array([arm.fk(row)[:3, 3] for row in q])

    def to_csv(self, path: str | Path, dt: float = 0.01) -> Path:
        """Write ``t,q1..qn,dq1..dqn,x,y,z`` rows every ``dt`` s (s, rad, rad/s, m)."""
        t = self.sample_times(dt)
        q, qd, _ = self.states(t)
        xyz = self.tool_positions(q)
        n = q.shape[1]
        header = ",".join(["t"] + [f"q{j + 1}" for j in range(n)]
                          + [f"dq{j + 1}" for j in range(n)] + ["x", "y", "z"])
        path = Path(path)
        try:
            np.savetxt(path, np.column_stack([t, q, qd, xyz]), delimiter=",", header=header,
                       comments="", fmt="%.10g")
        except OSError as exc:
            raise InputDataError(f"cannot write trajectory CSV {path}: {exc}") from None
        return path


def serial_trajectory(problem: SerialProblem, result: SerialReport) -> SerialTrajectory:
    """Ruckig legs through ``result``'s configurations, home -> targets -> home."""
    lim = problem.arm.limits
    path = result.tour_configurations()
    trajs: list[Any] = []
    durations = []
    for k in range(len(path) - 1):
        if np.array_equal(path[k], path[k + 1]):
            trajs.append(None)
            durations.append(0.0)
            continue
        traj = ruckig_trajectory(path[k], path[k + 1], lim.velocity,
                                 problem.limits.acceleration, lim.jerk)
        trajs.append(traj)
        durations.append(float(traj.duration))
    trajectory = SerialTrajectory(problem, path, trajs, np.array(durations))
    trajectory.result = result
    return trajectory


@dataclass(frozen=True)
class SerialValidation:
    """What :func:`validate_serial_trajectory` found.

    Attributes:
        ok: nothing violated.
        n_samples, dt: samples checked and the step (s).
        duration: the trajectory's duration (s).
        max_velocity_ratio, max_acceleration_ratio: max over samples and joints of |.|/limit.
        max_jerk_ratio: the same for finite-difference jerk (None: no jerk limits).
        position_margin: smallest distance to a position limit (rad).
        collisions: samples in collision.
        max_position_error, max_axis_error: worst FK miss of a target configuration
            (m; rad between the tool z axis and the target's axis).
        violations: one line per kind of violation.
    """

    ok: bool
    n_samples: int
    dt: float
    duration: float
    max_velocity_ratio: float
    max_acceleration_ratio: float
    max_jerk_ratio: float | None
    position_margin: float
    collisions: int
    max_position_error: float
    max_axis_error: float
    violations: tuple[str, ...]

    def summary(self) -> str:
        head = "valid" if self.ok else f"INVALID: {'; '.join(self.violations)}"
        jerk = "-" if self.max_jerk_ratio is None else f"{self.max_jerk_ratio:.4f}"
        return (f"trajectory {head} ({self.n_samples} samples at dt={self.dt:g} s, duration "
                f"{self.duration:.4f} s, max |qd|/limit {self.max_velocity_ratio:.4f}, "
                f"|qdd|/limit {self.max_acceleration_ratio:.4f}, jerk {jerk}, collisions "
                f"{self.collisions}, FK miss {self.max_position_error:.2e} m / "
                f"{self.max_axis_error:.2e} rad)")


def validate_serial_trajectory(trajectory: SerialTrajectory, result: SerialReport, *,
                               dt: float = 0.005, rtol: float = RTOL,
                               qtol: float = QTOL) -> SerialValidation:
    """Sample every ``dt`` s (and every leg boundary) and check everything (module doc)."""
    require_in_range("validate_serial_trajectory", "rtol", rtol, 0.0, 1.0)
    problem = trajectory.problem
    arm = problem.arm
    lim = arm.limits
    t = trajectory.sample_times(dt)
    q, qd, qdd = trajectory.states(t)
    vr = float((np.abs(qd) / lim.velocity).max())
    ar = float((np.abs(qdd) / problem.limits.acceleration).max())
    margin = float(np.minimum(q - lim.lower, lim.upper - q).min())
    violations = []
    if margin < -qtol:
        violations.append(f"position limit exceeded by {-margin:.3g} rad")
    if vr > 1 + rtol:
        violations.append(f"velocity {vr:.4f} x limit")
    if ar > 1 + rtol:
        violations.append(f"acceleration {ar:.4f} x limit")
    jr = None
    if lim.jerk is not None:
        grid = np.isclose(np.mod(t + 1e-12, dt), 0.0, atol=1e-9)
        tg = t[grid]
        if tg.size > 1:
            jr = float((np.abs(np.diff(qdd[grid], axis=0)) / np.diff(tg)[:, None]
                        / lim.jerk).max())
            if jr > 1 + rtol:
                violations.append(f"jerk {jr:.4f} x limit")
    at_rest = np.abs(qd[np.isin(t, trajectory.starts)]).max()
    if at_rest > 1e-6:
        violations.append(f"not at rest at a target (|qd| = {at_rest:.3g})")
    collisions = 0
    if problem.checker is not None:
        collisions = sum(problem.checker.in_collision(row) for row in q)
        if collisions:
            violations.append(f"{collisions} samples in collision")
    pos_err = axis_err = 0.0
    for i, qi in enumerate(result.configurations):
        pose = arm.fk(qi)
        cands = problem.targets.poses[i]
        pe = np.linalg.norm(cands[:, :3, 3] - pose[:3, 3], axis=1)
        k = int(np.argmin(pe))
        cosang = float(np.clip(cands[k, :3, 2] @ pose[:3, 2], -1.0, 1.0))
        pos_err = max(pos_err, float(pe[k]))
        axis_err = max(axis_err, math.acos(cosang))
    if pos_err > 1e-5 or axis_err > 1e-4:
        violations.append(f"a configuration misses its target by {pos_err:.3g} m / "
                          f"{axis_err:.3g} rad")
    for name, value in (("total_time", result.total_time),
                        ("the planned time", result.planned_time)):
        if abs(trajectory.duration - value) > 0.005 * value:
            violations.append(f"duration {trajectory.duration:.4f} s differs from {name} "
                              f"{value:.4f} s by more than 0.5%")
    return SerialValidation(ok=not violations, n_samples=int(t.size), dt=float(dt),
                            duration=trajectory.duration, max_velocity_ratio=vr,
                            max_acceleration_ratio=ar, max_jerk_ratio=jr,
                            position_margin=margin, collisions=int(collisions),
                            max_position_error=pos_err, max_axis_error=axis_err,
                            violations=tuple(violations))


__all__ = ["SerialTrajectory", "SerialValidation", "serial_trajectory",
           "validate_serial_trajectory"]

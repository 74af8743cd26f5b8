"""The executable joint trajectory of a solved tour, for every robot, and one validator.

:func:`build_trajectory` (``subtask_opt.trajectory``) turns the
:class:`~subtask_opt.tour.solve.Result` of an arm problem into a :class:`Trajectory`:
rest-to-rest legs through the stops of the tour (the home first and, for a closed tour,
last; open tours end at their last target), each a :class:`Leg` of

* a joint move: ruckig's time-optimal synchronised profile, jerk-limited when the arm
  has jerk limits, as the ``joint`` model timed it
  (:func:`~subtask_opt.kinematics.joint_moves.joint_move`): on a serial arm
  phase-synchronised (the straight joint-space line its collision sweep checked), on a
  planar arm time-synchronised (each joint its own profile, all ending together);
* (planar arms) a straight line: the time-optimal parameterisation of the line under the
  joint and Cartesian limits (:mod:`subtask_opt.arm.timing._line_kernels`), jerk-limited
  like the ``line`` time model times it.

Tours of the ``joint`` and ``line`` models are executed as they were timed, so the
duration is the planned time (:attr:`Trajectory.predicted_time`). A planar arm's
Cartesian models (``paper``, ``trapezoid``) promise straight lines at Cartesian limits
the arm may not manage: they are executed as the ``line`` model would drive the same
legs (a joint move where the line is impossible), so the duration is what the arm
really needs and ``predicted_time`` what the model promised.

:func:`validate` samples a trajectory densely and checks, for every robot: joint
positions, velocities, accelerations and (with jerk limits) jerk against the limits,
rest at every stop, that every stop's configuration reaches its target (FK), the
duration against the planned time (models the arm executes as timed), and collisions
with the scene and the arm itself at every sample where the problem has a checker.

Sampling steps must lie in [:data:`MIN_DT`, :data:`MAX_DT`] s and give at most
:data:`MAX_SAMPLES` samples; the count is estimated before anything is allocated.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.arm.timing import _line_kernels as _lk
from subtask_opt.base.errors import InputDataError, ParameterError, require_positive
from subtask_opt.kinematics import _kernels as _k
from subtask_opt.kinematics.joint_moves import joint_move

# Relative slack of the validator on velocity and acceleration limits: the line
# legs meet their limits exactly at the grid points of the path and to
# O(grid spacing^2) between them; ruckig's profiles to round-off.
DEFAULT_RTOL = 1e-3
# Absolute slack on joint position limits (rad).
DEFAULT_QTOL = 1e-7
# Relative slack on jerk limits. The jerk is checked by finite differences of the
# sampled accelerations on the uniform grid k dt: a difference quotient is the mean
# jerk over its step, so for a continuous acceleration it never exceeds the largest
# jerk; the slack only covers round-off and the lines' check between grid instants.
DEFAULT_JTOL = 1e-3
# Range of sampling steps (s) and the most samples one call may allocate.
MIN_DT = 1e-6
MAX_DT = 10.0
MAX_SAMPLES = 10_000_000
# How far a stop's configuration may miss its target (m; rad between tool axes).
FK_POSITION_TOL = 1e-5
FK_AXIS_TOL = 1e-4
# Largest |executed - planned| / planned for the models the arm executes as timed.
DURATION_RTOL = 0.005
HOME = -1
"""The stop index of a home (a serial arm's home configuration, a planar home point)."""

States = tuple[np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True, eq=False)
class Leg:
    """One rest-to-rest move of a trajectory.

    Attributes:
        start: time the leg starts (s) within the tour.
        duration: its duration (s).
        kind: ``"joint"`` (ruckig), ``"detour"`` (ruckig moves through waypoints) or
            ``"line"`` (a planar straight line).
        from_stop, to_stop: target indices (:data:`HOME` for a home).
        from_config, to_config: the configurations at both ends (a planar arm's elbow
            branch, 0 down and 1 up; a serial arm's index among the target's IK
            solutions; 0 at a home).
        q_from, q_to: (n,) joint positions at both ends.
        waypoints: (k, n) the joint-space corners the leg passes, ends included, or None
            (a planar line); a ``"detour"`` leg (a serial arm's leg planned around an
            obstacle) stops at each and moves straight between them.
    """

    start: float
    duration: float
    kind: str
    from_stop: int
    to_stop: int
    from_config: int
    to_config: int
    q_from: np.ndarray
    q_to: np.ndarray
    _eval: Callable[[np.ndarray], States] = field(repr=False)
    waypoints: np.ndarray | None = field(default=None, repr=False)

    def states(self, t: np.ndarray) -> States:
        """(q, qd, qdd), each (T, n), at leg-local times t (clamped to [0, duration])."""
        return self._eval(np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration))


@dataclass(frozen=True, eq=False)
class TrajectorySamples:
    """A trajectory sampled at a fixed step: times (T,), joints (T, n), tool (T, 2 or 3)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tool: np.ndarray

    def to_csv(self, path: str | Path) -> Path:
        """Write ``t,q1..qn,dq1..dqn,x,y[,z]`` rows (SI units: s, rad, rad/s, m)."""
        n = self.q.shape[1]
        header = ",".join(["t"] + [f"q{j + 1}" for j in range(n)]
                          + [f"dq{j + 1}" for j in range(n)] + list("xyz"[:self.tool.shape[1]]))
        path = Path(path)
        table = np.column_stack([self.t, self.q, self.qd, self.tool])
        try:
            np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.10g")
        except OSError as exc:
            raise InputDataError(f"cannot write trajectory CSV {path}: {exc}") from None
        return path


@dataclass(frozen=True)
class Limits:
    """The joint limits a trajectory is judged by, (n,) arrays (jerk None: not limited)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray | None


def arm_limits(arm: Any) -> Limits:
    """The joint limits of a planar :class:`~subtask_opt.kinematics.planar.Arm` or a
    :class:`~subtask_opt.kinematics.serial.SerialArm` (which then needs acceleration limits)."""
    if hasattr(arm, "joint_limits"):
        lim = arm.joint_limits
        return Limits(lim.lower, lim.upper, lim.velocity, lim.acceleration, lim.jerk)
    lim = arm.limits
    return Limits(lim.lower, lim.upper, lim.velocity, lim.require("acceleration"), lim.jerk)


class Trajectory:
    """The time-parameterised joint trajectory of a tour, any robot.

    Attributes:
        arm: the robot's model (a planar :class:`~subtask_opt.kinematics.planar.Arm` or a
            :class:`~subtask_opt.kinematics.serial.SerialArm`).
        legs: the moves, in order.
        duration: total time (s).
        predicted_time: the tour time the search planned.
        time_model: the model the tour was optimised under.
        problem: the compiled problem the tour belongs to (its targets, and a serial
            arm's collision checker), or None.
        limits: the joint limits (:func:`arm_limits` of ``arm``).
    """

    def __init__(self, arm: Any, legs: list[Leg], predicted_time: float, time_model: str,
                 problem: Any = None) -> None:
        if not legs:
            raise ParameterError("a trajectory needs at least one leg")
        self.arm = arm
        self.legs = legs
        self.predicted_time = float(predicted_time)
        self.time_model = time_model
        self.problem = problem
        self.limits = arm_limits(arm)
        self.starts = np.array([leg.start for leg in legs] + [legs[-1].start
                                                              + legs[-1].duration])
        self.duration = float(self.starts[-1])

    @property
    def planar(self) -> bool:
        return hasattr(self.arm, "kinematics")

    def __repr__(self) -> str:
        n_line = sum(leg.kind == "line" for leg in self.legs)
        return (f"Trajectory({self.arm.name}: {len(self.legs)} legs, {n_line} lines, "
                f"{len(self.legs) - n_line} joint moves; duration {self.duration:.4f} s)")

    def states(self, t: Any) -> States:
        """(q, qd, qdd), each (T, n), at tour times t (clamped to [0, duration])."""
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        if not np.all(np.isfinite(t)):
            raise ParameterError(f"times must be finite, got {t[~np.isfinite(t)][:3].tolist()}")
        t = np.clip(t, 0.0, self.duration)
        n = len(self.limits.velocity)
        q, qd, qdd = (np.empty((len(t), n)) for _ in range(3))
        which = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0,
                        len(self.legs) - 1)
        for k in np.unique(which):
            sel = which == k
            leg = self.legs[k]
            q[sel], qd[sel], qdd[sel] = leg.states(t[sel] - leg.start)
        return q, qd, qdd

    def at_time(self, t: float) -> States:
        """Joint position, velocity and acceleration, each (n,), at time t (s)."""
        q, qd, qdd = self.states([t])
        return q[0], qd[0], qdd[0]

    def sample_times(self, dt: float) -> np.ndarray:
        """Every ``dt`` s from 0, plus every leg boundary (sorted, unique).

        Raises:
            ParameterError: dt outside [MIN_DT, MAX_DT] or more than MAX_SAMPLES samples.
        """
        n = _sample_count("Trajectory", self.duration, dt)
        grid = np.arange(n + 1) * dt
        return np.union1d(grid[grid <= self.duration], self.starts)

    def tool_positions(self, q: np.ndarray) -> np.ndarray:
        """The tool tip at joint rows q: (T, 2) ``x, y`` (planar) or (T, 3) (serial)."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        if self.planar:
            return _k.fk_batch(self.arm.kinematics, q)[:, :2]
        return np.array([self.arm.fk(row)[:3, 3] for row in q]).reshape(-1, 3)

    def sample(self, dt: float = 0.01) -> TrajectorySamples:
        """Samples every ``dt`` seconds from 0, plus every leg boundary."""
        t = self.sample_times(dt)
        q, qd, qdd = self.states(t)
        return TrajectorySamples(t, q, qd, qdd, self.tool_positions(q))

    def to_csv(self, path: str | Path, dt: float = 0.01) -> Path:
        """Write the samples at step ``dt`` as CSV (see :meth:`TrajectorySamples.to_csv`)."""
        return self.sample(dt).to_csv(path)


def _sample_count(owner: str, duration: float, dt: float) -> int:
    """floor(duration / dt), after checking dt and that the samples fit MAX_SAMPLES."""
    require_positive(owner, "dt", dt)
    if not MIN_DT <= dt <= MAX_DT:
        raise ParameterError(f"{owner}.dt must be in [{MIN_DT:g}, {MAX_DT:g}] s, got {dt!r}")
    estimate = duration / dt + 2.0
    if estimate > MAX_SAMPLES:
        raise ParameterError(
            f"{owner}.dt = {dt:g} s would need about {estimate:.3g} samples for the "
            f"{duration:.4g} s trajectory, more than the limit of {MAX_SAMPLES:.0e}; "
            f"use dt >= {duration / (MAX_SAMPLES - 2):.3g} s")
    return int(math.floor(duration / dt))


def _line_leg(p_from: np.ndarray, p_to: np.ndarray, q_from: np.ndarray, q_to: np.ndarray,
              branch: int, arm: Any, grid: int, reverse: bool) -> Any:
    """Straight line p_from -> p_to as the ``line`` model drives it: (duration, evaluator).

    None when the arm cannot follow the line on ``branch``. The profile is computed in
    the direction the travel-time tensor used (``reverse``: computed p_to -> p_from and
    played backwards), so the duration is the tensor's time to the last bit.
    """
    from subtask_opt.arm.timing.models import line_limits

    a, b, qa, qb = (p_to, p_from, q_to, q_from) if reverse else (p_from, p_to, q_from, q_to)
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    st, sg, qs, x, w, tau, lam, duration = _lk.line_profile(
        arm.kinematics, a, b, branch, np.ascontiguousarray(qa, dtype=np.float64),
        np.ascontiguousarray(qb, dtype=np.float64), line_limits(arm, grid))
    if st != _lk.LINE_OK:
        return None

    def evaluate(t: np.ndarray) -> States:
        tt = duration - t if reverse else t
        q, qd, qdd, _ = _lk.line_states(arm.kinematics, a, b, branch, sg, qs, x, w, tau, lam,
                                        np.ascontiguousarray(tt, dtype=np.float64))
        return (q, -qd, qdd) if reverse else (q, qd, qdd)

    return float(duration), evaluate


def build_trajectory(result: Any) -> Trajectory:
    """The executable joint trajectory of an arm problem's answer (the module docstring).

    Raises:
        ParameterError: not the :class:`~subtask_opt.tour.solve.Result` of an arm problem.
    """
    from subtask_opt.arm.report import TourReport
    from subtask_opt.arm.serial_problem import SerialReport
    from subtask_opt.tour.solve import Result

    report = getattr(result, "report", None)
    if not isinstance(result, Result) or not isinstance(report, (TourReport, SerialReport)):
        what = ("a Result without an arm's report" if isinstance(result, Result)
                else type(result).__name__)
        raise ParameterError(f"trajectory needs the Result of an arm problem "
                             f"(solve(ArmProblem)), got {what}")
    if isinstance(report, SerialReport):
        return from_serial_report(report)
    return _planar(result, report)


def from_serial_report(report: Any) -> Trajectory:
    """Phase-synchronised ruckig legs through the report's configurations from home."""
    problem = report.problem
    lim = arm_limits(problem.arm)
    path = report.tour_configurations()
    stops = [HOME] + [int(i) for i in report.order] + ([] if report.open_path else [HOME])
    index = [0 if s == HOME else int(report.configuration_index[s]) for s in stops]
    legs: list[Leg] = []
    start = 0.0
    detours = getattr(report, "detours", {})
    for k in range(len(path) - 1):
        waypoints = detours.get(k)
        if waypoints is None:
            move = joint_move(path[k], path[k + 1], lim.velocity, lim.acceleration, lim.jerk)
            legs.append(Leg(start, move.duration, "joint", stops[k], stops[k + 1], index[k],
                            index[k + 1], move.q0, move.q1, move.states,
                            np.array([move.q0, move.q1])))
            start += move.duration
            continue
        duration, states = _chained_moves(np.asarray(waypoints), lim)
        legs.append(Leg(start, duration, "detour", stops[k], stops[k + 1], index[k],
                        index[k + 1], np.array(path[k]), np.array(path[k + 1]), states,
                        np.array(waypoints)))
        start += duration
    return Trajectory(problem.arm, legs, report.planned_time, "joint", problem)


def _chained_moves(waypoints: np.ndarray, lim: Limits) -> tuple[float, Callable[..., States]]:
    """Rest-to-rest phase-synchronised ruckig moves through ``waypoints`` (a detour, see
    :mod:`subtask_opt.cell.detour`): the total duration and the states at leg times."""
    moves = [joint_move(a, b, lim.velocity, lim.acceleration, lim.jerk)
             for a, b in zip(waypoints[:-1], waypoints[1:], strict=True)]
    starts = np.concatenate([[0.0], np.cumsum([m.duration for m in moves])])

    def evaluate(t: np.ndarray) -> States:
        t = np.atleast_1d(t)
        n = waypoints.shape[1]
        q, qd, qdd = (np.empty((len(t), n)) for _ in range(3))
        which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(moves) - 1)
        for k in np.unique(which):
            sel = which == k
            q[sel], qd[sel], qdd[sel] = moves[k].states(t[sel] - starts[k])
        return q, qd, qdd
    return float(starts[-1]), evaluate


def _planar(result: Any, report: Any) -> Trajectory:
    """Ruckig joint moves and straight lines as the time model timed the tour's legs."""
    from subtask_opt.arm.timing.models import MOVE_JOINT, MOVE_LINE, MOVE_NONE

    problem = report.problem  # the compiled problem searched (a home point its last subtask)
    arm = problem.arm
    timing = problem.timing
    lim = arm_limits(arm)
    configs = np.asarray(report.configurations, dtype=np.int64)
    homed = problem.size > len(result.order)
    stops = ([problem.size - 1] if homed else []) + [int(i) for i in result.order]
    if result.constraints is None or result.constraints.tour != "open":
        stops.append(stops[0])
    # A Cartesian model (no move tensor): each leg is driven as the ``line`` model with
    # the joint fallback would drive it, a line where the arm can follow it.
    moves = timing.branch_moves
    qb = timing.branch_joints
    grid = timing.line_grid or 512
    points = problem.subtasks.points
    legs: list[Leg] = []
    start = 0.0
    for i, j in zip(stops[:-1], stops[1:], strict=True):
        ci, cj = int(configs[i]), int(configs[j])
        if moves is None or qb is None:
            assert timing.joint_positions is not None
            q0, q1 = timing.joint_positions[i], timing.joint_positions[j]
            move = MOVE_LINE if ci == cj else MOVE_JOINT
        else:
            q0, q1 = qb[i, ci], qb[j, cj]
            move = int(moves[i, ci, j, cj])
        if move == MOVE_NONE:
            raise ParameterError(f"leg {i} -> {j} has no feasible move (excluded line)")
        line = None
        if move == MOVE_LINE:
            line = _line_leg(points[i], points[j], q0, q1, ci, arm, grid, reverse=i > j)
            if line is None and moves is not None:
                raise ParameterError(f"the straight line {i} -> {j} is not feasible for "
                                     f"{arm.name}, but the time model drove it")
        kind = "line"
        if line is None:
            kind = "joint"
            joint = joint_move(q0, q1, lim.velocity, lim.acceleration, lim.jerk, phase=False)
            line = joint.duration, joint.states
        duration, ev = line
        home = problem.size - 1 if homed else None
        legs.append(Leg(start, duration, kind, HOME if i == home else i,
                        HOME if j == home else j, ci, cj, np.array(q0, dtype=np.float64),
                        np.array(q1, dtype=np.float64), ev))
        start += duration
    return Trajectory(arm, legs, result.total_time, problem.time_model, problem)


@dataclass(frozen=True)
class ValidationReport:
    """What :func:`validate` found.

    Attributes:
        ok: nothing violated.
        n_samples, dt: samples checked and the step (s).
        duration, predicted_time: executed and planned tour times (s).
        max_velocity_ratio, max_acceleration_ratio: max over samples of |qd| / limit and
            |qdd| / limit, per joint.
        max_jerk_ratio: the same for the finite-difference jerk on the uniform grid, per
            joint; None when the arm has no jerk limits (not checked).
        position_margin: smallest distance to a position limit (rad; < 0 beyond).
        collisions: samples in collision; None when the problem has no collision checker.
        max_position_error: worst FK miss of a stop's configuration (m).
        max_axis_error: worst angle between a stop's tool axis and its target's (rad);
            None for planar points (no axis).
        violations: one line per kind of violation.
        rtol, qtol, jtol: the tolerances used.
        legs_in_collision: legs whose straight joint segments (a detour's between its
            waypoints) the clearance-bounded sweep finds in collision; None without a
            collision checker.
    """

    ok: bool
    n_samples: int
    dt: float
    duration: float
    predicted_time: float
    max_velocity_ratio: tuple[float, ...]
    max_acceleration_ratio: tuple[float, ...]
    max_jerk_ratio: tuple[float, ...] | None
    position_margin: float
    collisions: int | None
    max_position_error: float
    max_axis_error: float | None
    violations: tuple[str, ...]
    rtol: float
    qtol: float
    jtol: float
    legs_in_collision: int | None = None

    @property
    def duration_error(self) -> float:
        """|duration - predicted| / predicted."""
        return abs(self.duration - self.predicted_time) / self.predicted_time

    def summary(self) -> str:
        """One line: valid or not, the samples, durations and the largest ratios."""
        head = "valid" if self.ok else f"INVALID ({'; '.join(self.violations)})"
        jerk = ("jerk not checked (no jerk limits)" if self.max_jerk_ratio is None
                else f"max |dddq|/limit {max(self.max_jerk_ratio):.4f}")
        collisions = ("" if self.collisions is None
                      else f", samples in collision {self.collisions}, legs in collision "
                           f"{self.legs_in_collision}")
        axis = "" if self.max_axis_error is None else f" / {self.max_axis_error:.2e} rad"
        return (f"trajectory {head}: {self.n_samples} samples at dt={self.dt:g} s, duration "
                f"{self.duration:.4f} s (planned {self.predicted_time:.4f} s), max |qd|/limit "
                f"{max(self.max_velocity_ratio):.4f}, max |qdd|/limit "
                f"{max(self.max_acceleration_ratio):.4f}, {jerk}{collisions}, FK miss "
                f"{self.max_position_error:.2e} m{axis}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the verdict, the largest ratios and errors, the tolerances."""
        return {"valid": self.ok, "violations": list(self.violations),
                "duration": self.duration, "planned_time": self.predicted_time,
                "max_velocity_ratio": max(self.max_velocity_ratio),
                "max_acceleration_ratio": max(self.max_acceleration_ratio),
                "max_jerk_ratio": (None if self.max_jerk_ratio is None
                                   else max(self.max_jerk_ratio)),
                "samples_in_collision": self.collisions,
                "legs_in_collision": self.legs_in_collision,
                "max_position_error": self.max_position_error,
                "max_axis_error": self.max_axis_error,
                "samples": self.n_samples, "dt": self.dt,
                "tolerances": {"rtol": self.rtol, "qtol": self.qtol, "jtol": self.jtol}}


def validate(trajectory: Trajectory, *, dt: float | None = None, rtol: float = DEFAULT_RTOL,
             qtol: float = DEFAULT_QTOL, jtol: float = DEFAULT_JTOL) -> ValidationReport:
    """Sample ``trajectory`` every ``dt`` seconds (and at every leg boundary) and check it.

    A sample violates a limit when a joint position leaves [lower - qtol, upper + qtol],
    or |velocity| or |acceleration| > (1 + rtol) x its limit. With jerk limits, the jerk
    is checked by finite differences: on the uniform grid t_k = k dt,
    |qdd(t_k+1) - qdd(t_k)| / dt must stay within (1 + jtol) x the limit (the difference
    quotient is the mean jerk over the step, never above the largest one for a
    continuous acceleration; an acceleration step shows up as a jerk of step / dt).
    The arm must be at rest at every stop; every stop's configuration must reach its
    target within :data:`FK_POSITION_TOL` m (and a 3-D target's axis within
    :data:`FK_AXIS_TOL` rad); the duration must be within :data:`DURATION_RTOL` of the
    planned time for the models the arm executes as timed (``joint``, ``line``); and,
    where the problem has a collision checker, no sample may be in collision.

    ``dt`` defaults to 1 ms, or 5 ms when every sample is also checked for collisions.

    Raises:
        ParameterError: not a trajectory, a tolerance <= 0, dt outside
            [MIN_DT, MAX_DT] or more than MAX_SAMPLES samples.
    """
    if not isinstance(trajectory, Trajectory):
        raise ParameterError(f"validate needs a trajectory from subtask_opt.trajectory, got "
                             f"{type(trajectory).__name__}")
    for name, value in (("rtol", rtol), ("qtol", qtol), ("jtol", jtol)):
        require_positive("validate", name, value)
    problem = trajectory.problem
    checker = getattr(problem, "checker", None)
    if dt is None:
        dt = 1e-3 if checker is None else 5e-3
    t = trajectory.sample_times(dt)
    grid = np.isin(t, np.arange(_sample_count("validate", trajectory.duration, dt) + 1) * dt)
    lim = trajectory.limits
    q, qd, qdd = trajectory.states(t)
    vr = np.abs(qd) / lim.velocity
    ar = np.abs(qdd) / lim.acceleration
    margin = np.minimum(q - lim.lower, lim.upper - q)
    checks = [("position", t, margin < -qtol, lambda s, a: f"q{a + 1} = {q[s, a]:.6g} rad"),
              ("velocity", t, vr > 1 + rtol,
               lambda s, a: f"|dq{a + 1}| = {vr[s, a]:.6g} x limit"),
              ("acceleration", t, ar > 1 + rtol,
               lambda s, a: f"|ddq{a + 1}| = {ar[s, a]:.6g} x limit")]
    jerk_ratio: tuple[float, ...] | None = None
    if lim.jerk is not None and grid.sum() > 1:
        jr = np.abs(np.diff(qdd[grid], axis=0)) / np.diff(t[grid])[:, None] / lim.jerk
        jerk_ratio = tuple(float(v) for v in jr.max(axis=0))
        checks.append(("jerk", t[grid], jr > 1 + jtol,
                       lambda s, a: f"|dddq{a + 1}| = {jr[s, a]:.6g} x limit by finite "
                                    f"differences at dt = {dt:g} s"))
    violations = []
    for name, times, bad, text in checks:
        hits = np.argwhere(bad)
        if hits.size:
            s, a = hits[0]
            violations.append(f"{name} limit exceeded at t = {times[s]:.6g} s ({text(s, a)}; "
                              f"{len(hits)} samples)")
    rest = float(np.abs(qd[np.isin(t, trajectory.starts)]).max())
    if rest > 1e-6 * float(np.max(lim.velocity)):
        violations.append(f"arm not at rest at a stop (|qd| = {rest:.3g} rad/s)")
    collisions = swept = None
    if checker is not None:
        collisions = int(sum(checker.in_collision(row) for row in q))
        if collisions:
            violations.append(f"{collisions} samples in collision")
        # and every straight joint segment by the clearance-bounded sweep (the samples in
        # time can be far apart in space on a fast leg)
        swept = 0
        for k, leg in enumerate(trajectory.legs):
            corners = leg.waypoints
            if corners is None:
                continue
            segments = [i for i in range(len(corners) - 1) if checker.leg_in_collision(
                corners[i], corners[i + 1], problem.clearance)]
            if segments:
                swept += 1
                violations.append(f"leg {k} ({leg.kind}) collides on segment {segments[0]} by "
                                  f"the swept check at clearance {problem.clearance:g} m")
    position_error, axis_error = _fk_misses(trajectory)
    if position_error > FK_POSITION_TOL or (axis_error or 0.0) > FK_AXIS_TOL:
        violations.append(f"a configuration misses its target by {position_error:.3g} m"
                          + ("" if axis_error is None else f" / {axis_error:.3g} rad"))
    executed_as_timed = trajectory.time_model in ("joint", "line")
    if executed_as_timed and (abs(trajectory.duration - trajectory.predicted_time)
                              > DURATION_RTOL * trajectory.predicted_time):
        violations.append(f"duration {trajectory.duration:.4f} s differs from the planned "
                          f"{trajectory.predicted_time:.4f} s by more than "
                          f"{100 * DURATION_RTOL:g}%")
    return ValidationReport(
        ok=not violations, n_samples=len(t), dt=float(dt), duration=trajectory.duration,
        predicted_time=trajectory.predicted_time,
        max_velocity_ratio=tuple(float(v) for v in vr.max(axis=0)),
        max_acceleration_ratio=tuple(float(v) for v in ar.max(axis=0)),
        max_jerk_ratio=jerk_ratio, position_margin=float(margin.min()),
        collisions=collisions, legs_in_collision=swept,
        max_position_error=position_error, max_axis_error=axis_error,
        violations=tuple(violations), rtol=float(rtol), qtol=float(qtol), jtol=float(jtol))


def _fk_misses(trajectory: Trajectory) -> tuple[float, float | None]:
    """The worst distance (m) and, for 3-D targets, tool-axis angle (rad) between a stop's
    configuration and its target (0 and None without a problem to compare with)."""
    problem = trajectory.problem
    ends = [(leg.to_stop, leg.q_to) for leg in trajectory.legs if leg.to_stop != HOME]
    if problem is None or not ends:
        return 0.0, None
    stops = np.array([s for s, _ in ends])
    q = np.array([qs for _, qs in ends])
    if trajectory.planar:
        miss = np.hypot(*(trajectory.tool_positions(q) - problem.subtasks.points[stops]).T)
        return float(miss.max()), None
    position = axis = 0.0
    for stop, qs in ends:
        pose = trajectory.arm.fk(qs)
        candidates = problem.targets.poses[stop]
        errors = np.linalg.norm(candidates[:, :3, 3] - pose[:3, 3], axis=1)
        best = int(np.argmin(errors))
        cosine = float(np.clip(candidates[best, :3, 2] @ pose[:3, 2], -1.0, 1.0))
        position = max(position, float(errors[best]))
        axis = max(axis, math.acos(cosine))
    return position, axis


__all__ = ["DEFAULT_JTOL", "DEFAULT_QTOL", "DEFAULT_RTOL", "HOME", "Leg", "Limits",
           "MAX_DT", "MAX_SAMPLES", "MIN_DT", "Trajectory", "TrajectorySamples",
           "ValidationReport", "arm_limits", "build_trajectory",
           "from_serial_report", "validate"]

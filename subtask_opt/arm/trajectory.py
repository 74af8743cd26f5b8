"""Executable joint trajectories of a solved tour, and a validator.

:func:`tour_trajectory` turns a :class:`~subtask_opt.arm.planar_problem.Result` into a
time-parameterised joint trajectory of the closed tour, rest to rest at every
subtask:

* a joint move is ruckig's time-optimal synchronised trajectory (offline API:
  ``Ruckig(2)``, ``InputParameter``, ``Trajectory``, ``calculate``), jerk-limited
  when the arm has jerk limits;
* a straight-line leg is the time-optimal parameterisation of the line under
  the joint and Cartesian limits (:mod:`subtask_opt.arm.timing._line_kernels`).

Tours of the ``joint`` and ``line`` models are executed as they were timed, so
the trajectory's duration is the predicted tour time. Tours of the Cartesian
models (``paper``, ``trapezoid``) promise straight lines at Cartesian limits
the arm may not manage: they are executed as the ``line`` model would drive
the same legs (a joint move where the line is impossible), so the duration is
what the arm really needs, and :attr:`TourTrajectory.predicted_time` keeps
what the model promised.

When the arm has joint jerk limits every leg honours them: joint moves are
ruckig's jerk-limited profiles, and a straight line is the time-optimal
acceleration-limited profile averaged over a window (which makes its
acceleration continuous) and slowed down uniformly until the velocity,
acceleration and jerk limits hold
(:func:`subtask_opt.arm.timing._line_kernels.line_profile`); the ``line``
time model times the legs the same way, so the executed duration is the
predicted one. Without jerk limits (``asr_twodof``) lines are
acceleration-limited and joint moves trapezoids.

:func:`validate_trajectory` samples a trajectory densely and reports every
joint position, velocity, acceleration or jerk limit it exceeds.

Sampling steps: ``dt`` of :meth:`TourTrajectory.sample`, :meth:`TourTrajectory.to_csv`
and :func:`validate_trajectory` must lie in [:data:`MIN_DT`, :data:`MAX_DT`] s
and give at most :data:`MAX_SAMPLES` samples; the count is estimated before
anything is allocated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.arm import _kinematics_kernels as _k
from subtask_opt.arm.timing import _line_kernels as _lk
from subtask_opt.base.errors import InputDataError, ParameterError, require_positive

if TYPE_CHECKING:
    from subtask_opt.arm.model import Arm
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.tour.solve import Result

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

CSV_HEADER = "t,q1,q2,dq1,dq2,x,y"


@dataclass(frozen=True, eq=False)
class Leg:
    """One rest-to-rest move of a tour trajectory.

    Attributes:
        start: time the leg starts (s) within the tour.
        duration: its duration (s).
        kind: ``"joint"`` (ruckig) or ``"line"`` (straight line).
        from_subtask, to_subtask: subtask indices.
        from_config, to_config: elbow branches at both ends (0 down, 1 up).
        q_from, q_to: (2,) joint positions at both ends.
    """

    start: float
    duration: float
    kind: str
    from_subtask: int
    to_subtask: int
    from_config: int
    to_config: int
    q_from: np.ndarray
    q_to: np.ndarray
    _eval: Any = field(repr=False, default=None)

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (T, 2), at leg-local times t (clamped to [0, duration])."""
        return self._eval(np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration))


@dataclass(frozen=True, eq=False)
class TrajectorySamples:
    """A trajectory sampled at a fixed step: times (T,), joints (T, 2), tip (T, 2)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    xy: np.ndarray

    def to_csv(self, path: str | Path) -> Path:
        """Write ``t,q1,q2,dq1,dq2,x,y`` rows (SI units: s, rad, rad/s, m)."""
        path = Path(path)
        table = np.column_stack([self.t, self.q, self.qd, self.xy])
        try:
            np.savetxt(path, table, delimiter=",", header=CSV_HEADER, comments="", fmt="%.10g")
        except OSError as exc:
            raise InputDataError(f"cannot write trajectory CSV {path}: {exc}") from None
        return path


class TourTrajectory:
    """The time-parameterised joint trajectory of a closed tour.

    Attributes:
        arm: the robot.
        legs: the moves, in order (the last returns to the first subtask).
        duration: total time (s).
        predicted_time: the tour time the sequencing model promised.
        time_model: the model the tour was optimised under.
    """

    def __init__(self, arm: Arm, legs: list[Leg], predicted_time: float,
                 time_model: str) -> None:
        self.arm = arm
        self.legs = legs
        self.predicted_time = float(predicted_time)
        self.time_model = time_model
        self._starts = np.array([leg.start for leg in legs] + [legs[-1].start
                                                               + legs[-1].duration])
        self.duration = float(self._starts[-1])

    def __repr__(self) -> str:
        n_line = sum(leg.kind == "line" for leg in self.legs)
        return (f"TourTrajectory({len(self.legs)} legs: {n_line} lines, "
                f"{len(self.legs) - n_line} joint moves; duration {self.duration:.4f} s)")

    def states(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (T, 2), at tour times t (clamped to [0, duration])."""
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        if not np.all(np.isfinite(t)):
            raise ParameterError(f"times must be finite, got {t[~np.isfinite(t)][:3].tolist()}")
        t = np.clip(t, 0.0, self.duration)
        q = np.empty((len(t), 2))
        qd = np.empty((len(t), 2))
        qdd = np.empty((len(t), 2))
        which = np.clip(np.searchsorted(self._starts, t, side="right") - 1, 0,
                        len(self.legs) - 1)
        for k in np.unique(which):
            sel = which == k
            leg = self.legs[k]
            q[sel], qd[sel], qdd[sel] = leg.states(t[sel] - leg.start)
        return q, qd, qdd

    def at_time(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint position, velocity and acceleration, each (2,), at time t (s)."""
        q, qd, qdd = self.states([t])
        return q[0], qd[0], qdd[0]

    def sample(self, dt: float = 0.01) -> TrajectorySamples:
        """Samples every ``dt`` seconds from 0, plus the final instant.

        Raises:
            ParameterError: dt outside [MIN_DT, MAX_DT] or more than MAX_SAMPLES samples.
        """
        n = _sample_count("TourTrajectory.sample", self.duration, dt)
        t = np.arange(n + 1) * dt
        if t[-1] < self.duration:
            t = np.append(t, self.duration)
        q, qd, qdd = self.states(t)
        xy = _k.fk_batch(self.arm.kinematics, np.ascontiguousarray(q))[:, :2]
        return TrajectorySamples(t, q, qd, qdd, xy)

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


def _ruckig_leg(q0: np.ndarray, q1: np.ndarray, arm: Arm):
    """Ruckig's rest-to-rest trajectory q0 -> q1: (duration, evaluator)."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    jl = arm.joint_limits
    otg = Ruckig(2)
    inp = InputParameter(2)
    inp.current_position = [float(v) for v in q0]
    inp.target_position = [float(v) for v in q1]
    inp.current_velocity = [0.0, 0.0]
    inp.current_acceleration = [0.0, 0.0]
    inp.target_velocity = [0.0, 0.0]
    inp.target_acceleration = [0.0, 0.0]
    inp.max_velocity = [float(v) for v in jl.velocity]
    inp.max_acceleration = [float(v) for v in jl.acceleration]
    inp.max_jerk = [math.inf, math.inf] if jl.jerk is None else [float(v) for v in jl.jerk]
    traj = Trajectory(2)
    status = otg.calculate(inp, traj)
    if status not in (Result.Working, Result.Finished):
        raise ParameterError(f"ruckig cannot plan the joint move {q0.tolist()} -> "
                             f"{q1.tolist()}: {status}")

    def evaluate(t: np.ndarray):
        out = [traj.at_time(float(tk)) for tk in t]
        return (np.array([o[0] for o in out]).reshape(-1, 2),
                np.array([o[1] for o in out]).reshape(-1, 2),
                np.array([o[2] for o in out]).reshape(-1, 2))

    return float(traj.duration), evaluate


def _line_leg(p_from: np.ndarray, p_to: np.ndarray, q_from: np.ndarray, q_to: np.ndarray,
              branch: int, arm: Arm, grid: int, reverse: bool) -> Any:
    """Straight line p_from -> p_to as the ``line`` model drives it: (duration, evaluator).

    None when the arm cannot follow the line on ``branch``.

    The profile is computed in the direction the travel-time tensor used
    (``reverse``: computed p_to -> p_from and played backwards), so the
    duration is the tensor's time to the last bit.
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

    def evaluate(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        tt = duration - t if reverse else t
        q, qd, qdd, _ = _lk.line_states(arm.kinematics, a, b, branch, sg, qs, x, w, tau, lam,
                                        np.ascontiguousarray(tt, dtype=np.float64))
        return (q, -qd, qdd) if reverse else (q, qd, qdd)

    return float(duration), evaluate


def tour_trajectory(problem: PlanarProblem, result: Result) -> TourTrajectory:
    """The executable joint trajectory of ``result``'s tour (see the module docstring).

    Raises:
        ParameterError: the problem has no arm (a custom matrix), or the result
            does not belong to the problem.
    """
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.timing.models import MOVE_JOINT, MOVE_LINE, MOVE_NONE
    from subtask_opt.tour.solve import Result

    if not isinstance(problem, PlanarProblem) or problem.arm is None:
        raise ParameterError("tour_trajectory needs a problem built from subtasks and an arm "
                             f"(got {type(problem).__name__}; a custom matrix has no robot to "
                             "move)")
    if not isinstance(result, Result):
        raise ParameterError(f"tour_trajectory needs the problem's Result, got "
                             f"{type(result).__name__}")
    if len(result.order) != problem.size:
        raise ParameterError(f"result has {len(result.order)} subtasks, the problem "
                             f"{problem.size}")
    arm = problem.arm
    timing = problem.timing
    if result.report is None:
        raise ParameterError("tour_trajectory needs the Result of an arm problem (it has no "
                             "report of configurations)")
    configs = np.asarray(result.report.configurations, dtype=np.int64)
    # A Cartesian model (no move tensor): each leg is driven as the ``line`` model with
    # the joint fallback would drive it, a line where the arm can follow it.
    moves = timing.branch_moves
    qb = timing.branch_joints
    grid = timing.line_grid or 512
    points = problem.subtasks.points
    order = np.asarray(result.order, dtype=np.int64)
    n = len(order)
    legs: list[Leg] = []
    start = 0.0
    for k in range(n):
        i, j = int(order[k]), int(order[(k + 1) % n])
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
        if line is not None:
            duration, ev = line
            kind = "line"
        else:
            duration, ev = _ruckig_leg(q0, q1, arm)
            kind = "joint"
        legs.append(Leg(start, duration, kind, i, j, ci, cj, q0.copy(), q1.copy(), ev))
        start += duration
    return TourTrajectory(arm, legs, result.total_time, problem.time_model)


@dataclass(frozen=True)
class ValidationReport:
    """What :func:`validate_trajectory` found.

    Attributes:
        ok: no limit exceeded at any sample.
        n_samples: samples checked.
        dt: the sampling step (s).
        duration, predicted_time: executed and promised tour times (s).
        max_velocity_ratio, max_acceleration_ratio: max over samples of
            |qd| / limit and |qdd| / limit, per joint.
        position_margin: smallest distance to a position limit (rad; < 0 beyond).
        violations: one line per exceeded limit (first sample of each kind).
        rtol, qtol: the tolerances used.
        max_jerk_ratio: max over the uniform grid of |finite-difference jerk| /
            limit, per joint; None when the arm has no jerk limits (not checked).
        jtol: the relative tolerance on the jerk limits.
    """

    ok: bool
    n_samples: int
    dt: float
    duration: float
    predicted_time: float
    max_velocity_ratio: tuple[float, float]
    max_acceleration_ratio: tuple[float, float]
    position_margin: float
    violations: tuple[str, ...]
    rtol: float
    qtol: float
    max_jerk_ratio: tuple[float, float] | None = None
    jtol: float = DEFAULT_JTOL

    @property
    def duration_error(self) -> float:
        """|duration - predicted| / predicted."""
        return abs(self.duration - self.predicted_time) / self.predicted_time

    def summary(self) -> str:
        """One line: valid or not, the samples, durations and the largest limit ratios."""
        head = "valid" if self.ok else f"INVALID ({len(self.violations)} violations)"
        jerk = ("jerk not checked (no jerk limits)" if self.max_jerk_ratio is None
                else f"max |dddq|/limit {max(self.max_jerk_ratio):.4f}")
        return (f"trajectory {head}: {self.n_samples} samples at dt={self.dt:g} s, duration "
                f"{self.duration:.4f} s (predicted {self.predicted_time:.4f} s), max |qd|/limit "
                f"{max(self.max_velocity_ratio):.4f}, max |qdd|/limit "
                f"{max(self.max_acceleration_ratio):.4f}, {jerk}")


def validate_trajectory(trajectory: TourTrajectory, *, dt: float = 1e-3,
                        rtol: float = DEFAULT_RTOL, qtol: float = DEFAULT_QTOL,
                        jtol: float = DEFAULT_JTOL) -> ValidationReport:
    """Sample ``trajectory`` every ``dt`` seconds (and at every leg boundary) and check limits.

    A sample violates a limit when a joint position leaves [lower - qtol,
    upper + qtol], or |velocity| > (1 + rtol) limit, or |acceleration| >
    (1 + rtol) limit. When the arm has jerk limits, the jerk is checked by
    finite differences: on the uniform grid t_k = k dt, |qdd(t_k+1) - qdd(t_k)| / dt
    must stay within (1 + jtol) x the jerk limit (the difference quotient is the
    mean jerk over the step, never above the largest one for a continuous
    acceleration; an acceleration step shows up as a jerk of step / dt). The arm
    must also be at rest at the subtasks.

    Raises:
        ParameterError: not a trajectory, a tolerance <= 0, dt outside
            [MIN_DT, MAX_DT] or more than MAX_SAMPLES samples.
    """
    if not isinstance(trajectory, TourTrajectory):
        raise ParameterError(f"validate_trajectory needs a TourTrajectory, "
                             f"got {type(trajectory).__name__}")
    require_positive("validate_trajectory", "rtol", rtol)
    require_positive("validate_trajectory", "qtol", qtol)
    require_positive("validate_trajectory", "jtol", jtol)
    n = _sample_count("validate_trajectory", trajectory.duration, dt)
    jl = trajectory.arm.joint_limits
    grid = np.arange(n + 1) * dt
    grid = grid[grid <= trajectory.duration]
    t = np.union1d(grid, trajectory._starts)
    q, qd, qdd = trajectory.states(t)
    vr = np.abs(qd) / jl.velocity
    ar = np.abs(qdd) / jl.acceleration
    margin = np.minimum(q - jl.lower, jl.upper - q)
    checks = [("position", t, margin < -qtol, lambda s, a: f"q{a + 1} = {q[s, a]:.6g} rad"),
              ("velocity", t, vr > 1 + rtol,
               lambda s, a: f"|dq{a + 1}| = {vr[s, a]:.6g} x limit"),
              ("acceleration", t, ar > 1 + rtol,
               lambda s, a: f"|ddq{a + 1}| = {ar[s, a]:.6g} x limit")]
    jerk_ratio: tuple[float, float] | None = None
    if jl.jerk is not None and len(grid) > 1:
        on_grid = np.isin(t, grid)
        jr = np.abs(np.diff(qdd[on_grid], axis=0)) / np.diff(t[on_grid])[:, None] / jl.jerk
        jerk_ratio = (float(jr[:, 0].max()), float(jr[:, 1].max()))
        checks.append(("jerk", t[on_grid], jr > 1 + jtol,
                       lambda s, a: f"|dddq{a + 1}| = {jr[s, a]:.6g} x limit by finite "
                                    f"differences at dt = {dt:g} s"))
    violations = []
    for name, times, bad, text in checks:
        hits = np.argwhere(bad)
        if hits.size:
            s, a = hits[0]
            violations.append(f"{name} limit exceeded at t = {times[s]:.6g} s ({text(s, a)}; "
                              f"{len(hits)} samples)")
    rest = np.abs(qd[np.isin(t, trajectory._starts)]).max()
    if rest > 1e-6 * float(np.max(jl.velocity)):
        violations.append(f"arm not at rest at a subtask (|qd| = {rest:.3g} rad/s)")
    return ValidationReport(
        ok=not violations, n_samples=len(t), dt=float(dt), duration=trajectory.duration,
        predicted_time=trajectory.predicted_time,
        max_velocity_ratio=(float(vr[:, 0].max()), float(vr[:, 1].max())),
        max_acceleration_ratio=(float(ar[:, 0].max()), float(ar[:, 1].max())),
        position_margin=float(margin.min()), violations=tuple(violations), rtol=float(rtol),
        qtol=float(qtol), max_jerk_ratio=jerk_ratio, jtol=float(jtol))


__all__ = ["CSV_HEADER", "DEFAULT_JTOL", "DEFAULT_QTOL", "DEFAULT_RTOL", "Leg", "MAX_DT",
           "MAX_SAMPLES", "MIN_DT", "TourTrajectory", "TrajectorySamples", "ValidationReport",
           "tour_trajectory", "validate_trajectory"]

"""Executable joint trajectories of a solved tour, and a validator.

:func:`tour_trajectory` turns a :class:`~subtask_opt.arm.sequencing.Result` into a
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

Straight-line legs are acceleration-limited (the path parameterisation has
no jerk limit); joint moves are jerk-limited when the arm has jerk limits.

:func:`validate_trajectory` samples a trajectory densely and reports every
joint position, velocity or acceleration limit it exceeds.
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
    from subtask_opt.arm.sequencing import Result, SequencingProblem

# Relative slack of the validator on velocity and acceleration limits: the line
# legs meet their limits exactly at the grid points of the path and to
# O(grid spacing^2) between them; ruckig's profiles to round-off.
DEFAULT_RTOL = 1e-3
# Absolute slack on joint position limits (rad).
DEFAULT_QTOL = 1e-7

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
        """Samples every ``dt`` seconds from 0, plus the final instant."""
        require_positive("TourTrajectory.sample", "dt", dt)
        n = int(math.floor(self.duration / dt))
        t = np.arange(n + 1) * dt
        if t[-1] < self.duration:
            t = np.append(t, self.duration)
        q, qd, qdd = self.states(t)
        xy = _k.fk_batch(self.arm.kinematics, np.ascontiguousarray(q))[:, :2]
        return TrajectorySamples(t, q, qd, qdd, xy)

    def to_csv(self, path: str | Path, dt: float = 0.01) -> Path:
        """Write the samples at step ``dt`` as CSV (see :meth:`TrajectorySamples.to_csv`)."""
        return self.sample(dt).to_csv(path)


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
              branch: int, arm: Arm, grid: int, reverse: bool):
    """Time-optimal straight line p_from -> p_to: (duration, evaluator).

    The profile is computed in the direction the travel-time tensor used
    (``reverse``: computed p_to -> p_from and played backwards), so the
    duration is the tensor's time to the last bit.
    """
    jl = arm.joint_limits
    cl = arm.cartesian_limits
    a, b, qa, qb = (p_to, p_from, q_to, q_from) if reverse else (p_from, p_to, q_from, q_to)
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    st, sg, qs, der = _lk.line_geometry(arm.kinematics, a, b, branch,
                                    np.ascontiguousarray(qa, dtype=np.float64),
                                    np.ascontiguousarray(qb, dtype=np.float64), grid)
    ok = st == _lk.LINE_OK
    if ok:
        ok, x, w, duration = _lk.topp_profile(der, sg,
                                               np.array(jl.velocity), np.array(jl.acceleration),
                                               cl.kv, cl.ka, cl.kw, cl.kw_dot)
    if not ok:
        raise ParameterError(f"the straight line {a.tolist()} -> {b.tolist()} is not feasible "
                             f"for {arm.name} (status {st})")

    def evaluate(t: np.ndarray):
        tt = duration - t if reverse else t
        q, qd, qdd = _lk.line_states(arm.kinematics, a, b, branch, sg, qs, x, w,
                                     np.ascontiguousarray(tt))
        return (q, -qd, qdd) if reverse else (q, qd, qdd)

    return float(duration), evaluate


def tour_trajectory(problem: SequencingProblem, result: Result) -> TourTrajectory:
    """The executable joint trajectory of ``result``'s tour (see the module docstring).

    Raises:
        ParameterError: the problem has no arm (a custom matrix), or the result
            does not belong to the problem.
    """
    from subtask_opt.arm.sequencing import Result, SequencingProblem
    from subtask_opt.arm.timing.models import MOVE_LINE, MOVE_NONE, travel_times

    if not isinstance(problem, SequencingProblem) or not isinstance(result, Result):
        raise ParameterError("tour_trajectory needs a SequencingProblem and its Result")
    if problem.arm is None or problem.subtasks is None:
        raise ParameterError("tour_trajectory needs a problem built from subtasks and an arm "
                             "(a custom matrix has no robot to move)")
    if len(result.order) != problem.size:
        raise ParameterError(f"result has {len(result.order)} subtasks, the problem "
                             f"{problem.size}")
    arm = problem.arm
    timing = problem.timing
    configs = np.asarray(result.configurations, dtype=np.int64)
    if timing.branch_moves is None:  # a Cartesian model: drive its lines as the arm can
        timing = travel_times(problem.subtasks, arm, "line", configurations=configs,
                              line_fallback="joint")
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
        move = int(moves[i, ci, j, cj])
        if move == MOVE_NONE:
            raise ParameterError(f"leg {i} -> {j} has no feasible move (excluded line)")
        q0, q1 = qb[i, ci], qb[j, cj]
        if move == MOVE_LINE:
            duration, ev = _line_leg(points[i], points[j], q0, q1, ci, arm, grid,
                                     reverse=i > j)
            kind = "line"
        else:
            duration, ev = _ruckig_leg(q0, q1, arm)
            kind = "joint"
        legs.append(Leg(start, duration, kind, i, j, ci, cj, q0.copy(), q1.copy(), ev))
        start += duration
    return TourTrajectory(arm, legs, result.total_time, result.time_model)


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

    @property
    def duration_error(self) -> float:
        """|duration - predicted| / predicted."""
        return abs(self.duration - self.predicted_time) / self.predicted_time

    def summary(self) -> str:
        head = "valid" if self.ok else f"INVALID ({len(self.violations)} violations)"
        return (f"trajectory {head}: {self.n_samples} samples at dt={self.dt:g} s, duration "
                f"{self.duration:.4f} s (predicted {self.predicted_time:.4f} s), max |qd|/limit "
                f"{max(self.max_velocity_ratio):.4f}, max |qdd|/limit "
                f"{max(self.max_acceleration_ratio):.4f}")


def validate_trajectory(trajectory: TourTrajectory, *, dt: float = 1e-3,
                        rtol: float = DEFAULT_RTOL, qtol: float = DEFAULT_QTOL
                        ) -> ValidationReport:
    """Sample ``trajectory`` every ``dt`` seconds (and at every leg boundary) and check limits.

    A sample violates a limit when a joint position leaves [lower - qtol,
    upper + qtol], or |velocity| > (1 + rtol) limit, or |acceleration| >
    (1 + rtol) limit. The arm must also be at rest at the subtasks.
    """
    if not isinstance(trajectory, TourTrajectory):
        raise ParameterError(f"validate_trajectory needs a TourTrajectory, "
                             f"got {type(trajectory).__name__}")
    require_positive("validate_trajectory", "dt", dt)
    require_positive("validate_trajectory", "rtol", rtol)
    require_positive("validate_trajectory", "qtol", qtol)
    jl = trajectory.arm.joint_limits
    t = np.union1d(np.arange(0.0, trajectory.duration, dt), trajectory._starts)
    q, qd, qdd = trajectory.states(t)
    vr = np.abs(qd) / jl.velocity
    ar = np.abs(qdd) / jl.acceleration
    margin = np.minimum(q - jl.lower, jl.upper - q)
    violations = []
    checks = [("position", margin < -qtol, lambda s, a: f"q{a + 1} = {q[s, a]:.6g} rad"),
              ("velocity", vr > 1 + rtol, lambda s, a: f"|dq{a + 1}| = {vr[s, a]:.6g} x limit"),
              ("acceleration", ar > 1 + rtol,
               lambda s, a: f"|ddq{a + 1}| = {ar[s, a]:.6g} x limit")]
    for name, bad, text in checks:
        hits = np.argwhere(bad)
        if hits.size:
            s, a = hits[0]
            violations.append(f"{name} limit exceeded at t = {t[s]:.6g} s ({text(s, a)}; "
                              f"{len(hits)} samples)")
    rest = np.abs(qd[np.isin(t, trajectory._starts)]).max()
    if rest > 1e-6 * float(np.max(jl.velocity)):
        violations.append(f"arm not at rest at a subtask (|qd| = {rest:.3g} rad/s)")
    return ValidationReport(
        ok=not violations, n_samples=len(t), dt=float(dt), duration=trajectory.duration,
        predicted_time=trajectory.predicted_time,
        max_velocity_ratio=tuple(float(v) for v in vr.max(axis=0)),
        max_acceleration_ratio=tuple(float(v) for v in ar.max(axis=0)),
        position_margin=float(margin.min()), violations=tuple(violations), rtol=float(rtol),
        qtol=float(qtol))


__all__ = ["CSV_HEADER", "Leg", "TourTrajectory", "TrajectorySamples", "ValidationReport",
           "tour_trajectory", "validate_trajectory"]

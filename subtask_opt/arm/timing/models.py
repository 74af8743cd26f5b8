"""Time models: the N x N matrix of minimum rest-to-rest travel times between subtasks.

Four models (:data:`TIME_MODELS`):

``paper``
    Eq. (6)-(19) of the source paper as SPEC.md section 1 restates them:
    via-points at fraction k of each straight move, the rotation between the
    tool angles at the via-points, t = t_acc + t_lin + t_dec with the max of
    eq. (18). Kept for reproduction: for a translation-dominated move it gives
    (1 - 2k) d / Kv + 2 Kv / Ka, not the true optimum.
``trapezoid`` (default)
    The exact time-optimal rest-to-rest straight Cartesian move: a trapezoid
    (or triangle for short moves) in translation (Kv, Ka) and in rotation
    (Kw, Kw_dot) of the net change of tool angle, synchronised: the time is
    the larger of the two.
``joint``
    Joint-space rest-to-rest: the max over joints of the per-joint optimum,
    a trapezoid, or the jerk-limited S-curve when the arm has jerk limits
    (what ruckig computes for a 1-DOF move), on the chosen elbow branch.
``line``
    The straight Cartesian line, traversed as fast as the joint velocity and
    acceleration limits and the Cartesian limits (Kv, Ka, and Kw, Kw_dot on the
    tool angle, which follows the arm) allow together: a numerical time-optimal
    path parameterisation (:mod:`subtask_opt.arm.timing._line_kernels`). A line the arm
    cannot follow (through the inner disc, past a joint limit, through a
    singularity, or between different elbow branches) is replaced by a joint
    move (``line_fallback="joint"``, the default) or excluded
    (``line_fallback="exclude"``: infinite time). When the arm has joint jerk
    limits the line is driven jerk-limited: the acceleration-limited optimum
    averaged over a window of width tau (continuous acceleration) and slowed
    down uniformly by lambda until every velocity, acceleration and jerk limit
    holds; its time lambda (T + tau), with tau searched per leg, is exactly what
    :func:`subtask_opt.arm.trajectory.build_trajectory` executes. Not the
    jerk-limited optimum, but a feasible profile and its honest time.

For ``joint`` and ``line`` the result also holds the times between every pair
of *configurations* (:attr:`TimingResult.branch_times`), from which
:mod:`subtask_opt.tour.configurations` chooses one elbow branch per subtask.

The Cartesian models drive a straight line that the arm may not be able to
follow: :class:`LegCheck` reports the legs that leave the workspace of their
elbow branch and the joint speeds each leg needs (the legs asked for, e.g. a
tour's, or all pairs on demand).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from subtask_opt.arm.targets import Targets, describe
from subtask_opt.arm.timing import _line_kernels as _lk
from subtask_opt.base.errors import (
    ParameterError,
    UnreachableError,
    require_in_range,
    require_int,
    require_non_negative,
    require_positive,
)
from subtask_opt.kinematics import _kernels as _k
from subtask_opt.kinematics.planar import BRANCH_NAMES, Arm
from subtask_opt.tour.configurations import gather

TIME_MODELS: tuple[str, ...] = ("paper", "trapezoid", "joint", "line")
LINE_FALLBACKS: tuple[str, ...] = ("joint", "exclude")
# How a leg between two configurations is driven (TimingResult.branch_moves).
MOVE_NONE, MOVE_JOINT, MOVE_LINE = -1, 0, 1
LINE_STATUS_NAMES: dict[int, str] = {
    _lk.LINE_OK: "ok",
    _lk.LINE_ANNULUS: "leaves the reachable annulus",
    _lk.LINE_JOINT_LIMIT: "passes a joint limit",
    _lk.LINE_SINGULAR: "passes a singularity",
    4: "changes elbow branch",
}


def trapezoid_time(distance: float, vmax: float, amax: float) -> float:
    """Exact minimum rest-to-rest time over ``distance`` with speed/acceleration limits.

    ``d/v + v/a`` if ``d >= v**2/a`` (trapezoid), else ``2 sqrt(d/a)`` (triangle).
    The numba version is :func:`subtask_opt.kinematics._kernels.trapezoid_time_nb`.
    """
    require_non_negative("trapezoid_time", "distance", distance)
    require_positive("trapezoid_time", "vmax", vmax)
    require_positive("trapezoid_time", "amax", amax)
    return float(_k.trapezoid_time_nb(float(distance), float(vmax), float(amax)))


def scurve_time(distance: float, vmax: float, amax: float, jmax: float) -> float:
    """Exact minimum rest-to-rest time of the jerk-limited 1-DOF profile (zero end accelerations).

    Cases: cruise at vmax if the distance allows, else a lower peak speed; the
    acceleration phases reach amax only when the jerk allows. The numba
    version is :func:`subtask_opt.kinematics._kernels.scurve_time_nb`.
    """
    require_non_negative("scurve_time", "distance", distance)
    require_positive("scurve_time", "vmax", vmax)
    require_positive("scurve_time", "amax", amax)
    require_positive("scurve_time", "jmax", jmax)
    return float(_k.scurve_time_nb(float(distance), float(vmax), float(amax), float(jmax)))


@dataclass(frozen=True, eq=False)
class LegCheck:
    """Joint-limit check of the straight-line legs of a Cartesian time model.

    Each leg i-j is driven with the exact time-optimal Cartesian trapezoid
    (translation and rotation synchronised, the ``trapezoid`` model's motion,
    also for the ``paper`` model, whose own timing is not a realisable
    profile), sampled along the line with IK on the endpoints' elbow branch.

    Nothing is computed on construction: :meth:`legs` checks the legs you name
    (a tour's N legs: what :func:`subtask_opt.solve` reports), the all-pairs
    arrays and counts below check all N (N - 1) / 2 legs on first use (at
    N = 1000 about a hundred times the cost of the travel-time matrix).

    Attributes:
        arm: the robot.
        points: (N, 2) subtask positions.
        joints: (N, 2) joint angles at each subtask on its branch.
        tool_angles: (N,) tool angles of the time model (rad).
        configurations: (N,) elbow branch of each subtask.
        n_samples: samples per leg (>= 2).
    """

    arm: Arm
    points: np.ndarray
    joints: np.ndarray
    tool_angles: np.ndarray
    configurations: np.ndarray
    n_samples: int = 64

    def legs(self, starts: Any, ends: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(outside_annulus, speed_ratio)`` of the legs ``starts[k] -> ends[k]``, each (M,).

        The entries the all-pairs arrays hold at ``[starts[k], ends[k]]``, computed
        for these legs only.

        Raises:
            ParameterError: ``starts`` and ``ends`` are not equal-length index
                vectors in [0, N - 1].
        """
        n = self.points.shape[0]
        a = np.asarray(starts)
        b = np.asarray(ends)
        if (a.ndim != 1 or a.shape != b.shape or a.dtype.kind not in "iu"
                or b.dtype.kind not in "iu" or (a.size and (
                    min(a.min(), b.min()) < 0 or max(a.max(), b.max()) >= n))):
            raise ParameterError(f"LegCheck.legs needs two equal-length vectors of subtask "
                                 f"indices in [0, {n - 1}], got {starts!r} and {ends!r}")
        cl = self.arm.cartesian_limits
        # writable copies (O(N)): the kernel's one compiled signature
        return _k.leg_check(np.array(self.points, dtype=np.float64),
                            np.array(self.joints, dtype=np.float64),
                            np.array(self.tool_angles, dtype=np.float64),
                            np.array(self.configurations, dtype=np.int64), self.arm.kinematics,
                            np.array(self.arm.joint_limits.velocity, dtype=np.float64),
                            cl.kv, cl.ka, cl.kw, cl.kw_dot, self.n_samples,
                            a.astype(np.int64), b.astype(np.int64))

    @cached_property
    def _all_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        n = self.points.shape[0]
        iu, ju = np.triu_indices(n, 1)
        bad, ratio = self.legs(iu, ju)
        outside = np.zeros((n, n), dtype=bool)
        speed = np.zeros((n, n))
        outside[iu, ju] = outside[ju, iu] = bad
        speed[iu, ju] = speed[ju, iu] = ratio
        outside.setflags(write=False)
        speed.setflags(write=False)
        return outside, speed

    @property
    def outside_annulus(self) -> np.ndarray:
        """(N, N) bool, True where the straight line leaves the reachable annulus,
        passes a joint limit, or would have to change elbow branch (all pairs)."""
        return self._all_pairs[0]

    @property
    def speed_ratio(self) -> np.ndarray:
        """(N, N) max over samples and joints of |q_dot| / velocity limit (inf where
        ``outside_annulus``; 0 on the diagonal; all pairs)."""
        return self._all_pairs[1]

    def _upper(self) -> np.ndarray:
        n = self.speed_ratio.shape[0]
        return np.triu(np.ones((n, n), dtype=bool), 1)

    @property
    def n_legs(self) -> int:
        """Number of unordered legs i < j."""
        n = self.speed_ratio.shape[0]
        return n * (n - 1) // 2

    @property
    def n_infeasible(self) -> int:
        """Legs (i < j) whose straight line the arm cannot follow at all."""
        return int((self.outside_annulus & self._upper()).sum())

    @property
    def n_overspeed(self) -> int:
        """Feasible legs (i < j) that need a joint speed above its limit."""
        return int(((self.speed_ratio > 1.0) & ~self.outside_annulus & self._upper()).sum())

    @property
    def worst_ratio(self) -> float:
        """Largest |q_dot| / limit over the feasible legs (0 if there is none)."""
        finite = self.speed_ratio[~self.outside_annulus]
        return float(finite.max()) if finite.size else 0.0

    @property
    def share_infeasible(self) -> float:
        """n_infeasible / n_legs."""
        return self.n_infeasible / self.n_legs

    @property
    def share_overspeed(self) -> float:
        """n_overspeed / number of feasible legs (0 if there is none)."""
        feasible = self.n_legs - self.n_infeasible
        return self.n_overspeed / feasible if feasible else 0.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (the ``infeasible_legs`` entry of the CLI's --json)."""
        upper = self._upper()
        infeasible = np.argwhere(self.outside_annulus & upper)
        over = np.argwhere((self.speed_ratio > 1.0) & ~self.outside_annulus & upper)
        return {
            "n_legs": self.n_legs,
            "n_infeasible": self.n_infeasible,
            "n_overspeed": self.n_overspeed,
            "share_infeasible": self.share_infeasible,
            "share_overspeed": self.share_overspeed,
            "worst_ratio": self.worst_ratio,
            "infeasible": infeasible.tolist(),
            "overspeed": [[int(i), int(j), float(self.speed_ratio[i, j])] for i, j in over],
        }

    def summary(self) -> str:
        """One line for the CLI's warning."""
        return (f"{self.n_infeasible} of {self.n_legs} straight legs impossible for the arm "
                f"({100 * self.share_infeasible:.0f}%), {self.n_overspeed} of the others need "
                f"joint speeds above the limit ({100 * self.share_overspeed:.0f}%, worst "
                f"{self.worst_ratio:.2f}x)")


@dataclass(frozen=True, eq=False)
class TimingResult:
    """Output of :func:`travel_times`.

    Which optional fields a model fills (the others are None / defaults)::

        model       leg_check   branch_times/moves/joints   line_status/fallback/grid
        paper       yes (1)     -                           -
        trapezoid   yes (1)     -                           -
        joint       -           yes                         -
        line        -           yes                         yes

    (1) unless ``check_legs=False``. ``matrix``, ``model``, ``configurations``,
    ``joint_positions`` and ``tool_angles`` are always set by :func:`travel_times`.

    Attributes:
        matrix: (N, N) minimum rest-to-rest travel times (s), symmetric, zero
            diagonal, for the elbow branches in ``configurations`` (inf for a
            leg the ``line`` model excludes).
        model: the time model's name.
        configurations: (N,) int64 elbow branch used at each subtask (0 down, 1 up).
        leg_check: joint check of the straight legs (Cartesian models with
            ``check_legs``), else None.
        joint_positions: (N, 2) joint angles at each subtask on its branch
            (None for a matrix that came from elsewhere).
        tool_angles: (N,) tool angles the Cartesian models used (rad), or None.
        branch_times: (``joint`` and ``line``) (N, 2, N, 2) time from subtask
            i on branch ci to subtask j on branch cj, ``[i, ci, j, cj]``; inf
            where a branch does not reach its subtask or the leg is excluded.
        branch_moves: (N, 2, N, 2) int8 how each of those legs is driven:
            :data:`MOVE_LINE`, :data:`MOVE_JOINT` or :data:`MOVE_NONE`.
        branch_joints: (N, 2, 2) joint angles of every subtask on both
            branches (NaN where a branch does not reach it).
        line_status: (``line``) (N, N, 2) int64 why the straight line i-j on
            branch c is infeasible (0 feasible; keys of :data:`LINE_STATUS_NAMES`).
        line_fallback: (``line``) ``"joint"`` or ``"exclude"``.
        line_grid: (``line``) intervals of the path discretisation.
    """

    matrix: np.ndarray
    model: str
    configurations: np.ndarray
    leg_check: LegCheck | None = None
    joint_positions: np.ndarray | None = None
    tool_angles: np.ndarray | None = None
    branch_times: np.ndarray | None = None
    branch_moves: np.ndarray | None = None
    branch_joints: np.ndarray | None = None
    line_status: np.ndarray | None = None
    line_fallback: str = "joint"
    line_grid: int = 0

    def moves(self, configurations: Any = None) -> np.ndarray | None:
        """(N, N) int8 move kind of every leg for the given (default: own) configurations."""
        if self.branch_moves is None:
            return None
        c = self.configurations if configurations is None else np.asarray(configurations)
        return gather(self.branch_moves, c.astype(np.int64))

    def line_failure(self, i: int, j: int, ci: int, cj: int) -> str | None:
        """Why the straight line from (i, ci) to (j, cj) is not driven, or None if it is."""
        if self.line_status is None:
            return None
        if ci != cj:
            return LINE_STATUS_NAMES[4]
        st = int(self.line_status[i, j, ci])
        return None if st == _lk.LINE_OK else LINE_STATUS_NAMES[st]

    def line_summary(self, order: Any, configurations: Any) -> dict[str, Any] | None:
        """(``line``) JSON-ready report of the tour's legs whose straight line is infeasible."""
        if self.line_status is None:
            return None
        order = np.asarray(order)
        c = np.asarray(configurations)
        legs = []
        n = len(order)
        for k in range(n):
            a, b = int(order[k]), int(order[(k + 1) % n])
            why = self.line_failure(a, b, int(c[a]), int(c[b]))
            if why is not None:
                legs.append({"leg": k, "from": a, "to": b, "reason": why,
                             "replaced_by": "joint move" if self.line_fallback == "joint"
                             else None})
        upper = np.triu(np.ones((len(c), len(c)), dtype=bool), 1)
        same = c[:, None] == c[None, :]
        idx = np.arange(len(c))
        status = self.line_status[idx[:, None], idx[None, :], c[:, None]]
        bad = upper & (~same | (status != _lk.LINE_OK))
        return {"fallback": self.line_fallback, "n_lines": int(upper.sum()),
                "n_infeasible_lines": int(bad.sum()), "tour_legs_not_straight": legs}


def _explicit_configurations(configurations: Any, q_both: np.ndarray, points: np.ndarray,
                             arm: Arm) -> np.ndarray:
    arr = np.asarray(configurations)
    n = len(points)
    if arr.shape != (n,) or not np.isin(arr, (0, 1)).all():
        raise ParameterError(
            f"travel_times.configurations must be {n} values, each 0 or 1, got {configurations!r}")
    configs = arr.astype(np.int64)
    ok = np.isfinite(q_both[np.arange(n), configs]).all(axis=1)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise UnreachableError(
            f"subtask {i} at ({points[i, 0]:.6g}, {points[i, 1]:.6g}) is not reachable "
            f"{BRANCH_NAMES[configs[i]]} by {arm.name} within its joint limits")
    return configs


def travel_times(subtasks: Targets, arm: Arm, model: str = "trapezoid", *, k: float = 0.1,
                 elbow: int = 0, configurations: Any = None, check_legs: bool = True,
                 n_samples: int = 64, line_fallback: str = "joint",
                 line_grid: int | None = None) -> TimingResult:
    """The N x N matrix of minimum rest-to-rest travel times under a time model.

    Args:
        subtasks: the points (and optional tool angles).
        arm: the robot (limits from ``arm.cartesian_limits`` / ``arm.joint_limits``).
        model: one of :data:`TIME_MODELS`.
        k: via-point fraction of the ``paper`` model, 0 <= k < 0.5 (at 0.5 the
            via-points meet and the model's time collapses to zero).
        elbow: preferred elbow branch (0 elbow-down, 1 elbow-up); a subtask the
            preferred branch cannot reach within the joint limits uses the other.
        configurations: optional (N,) explicit branch (0/1) per subtask,
            overriding ``elbow``; each must reach its subtask.
        check_legs: attach a :class:`LegCheck` (Cartesian models only; it checks
            legs when asked, nothing here).
        n_samples: samples per straight leg in the check (>= 2).
        line_fallback: (``line``) ``"joint"`` drives an infeasible line as a
            joint move, ``"exclude"`` gives it an infinite time.
        line_grid: (``line``) intervals of the path discretisation (>= 16);
            without jerk limits the time converges from above as 1/line_grid
            (512: within 0.3%); None: :func:`default_line_grid` of the arm.

    Raises:
        ParameterError: unknown model, bad k, elbow, n_samples, line_fallback
            or line_grid.
        UnreachableError: a subtask no branch reaches (names its index).
    """
    if model not in TIME_MODELS:
        raise ParameterError(
            f"unknown time model {model!r}: expected one of {', '.join(TIME_MODELS)}")
    if not (isinstance(subtasks, Targets) and subtasks.planar):
        raise ParameterError(f"subtasks must be planar Targets, got {describe(subtasks)}")
    require_in_range("travel_times", "k", k, 0.0, 0.5)
    if k >= 0.5:
        raise ParameterError(f"travel_times.k must be < 0.5 (via-points would meet), got {k!r}")
    if elbow not in (0, 1) or isinstance(elbow, bool):
        raise ParameterError(f"travel_times.elbow must be 0 (elbow-down) or 1 (elbow-up), "
                             f"got {elbow!r}")
    require_int("travel_times", "n_samples", n_samples, 2)
    if line_fallback not in LINE_FALLBACKS:
        raise ParameterError(f"travel_times.line_fallback must be one of "
                             f"{', '.join(LINE_FALLBACKS)}, got {line_fallback!r}")
    if line_grid is None:
        line_grid = default_line_grid(arm)
    require_int("travel_times", "line_grid", line_grid, 16)
    # Writable C-contiguous copies: one numba signature per kernel.
    points = np.array(subtasks.points, dtype=np.float64, order="C")
    arm.check_reachable(points)

    q_both, _ = _k.ik_batch(arm.kinematics, points, True)  # (N, 2 branches, 2)
    if configurations is None:
        preferred_ok = np.isfinite(q_both[:, elbow]).all(axis=1)
        configs = np.where(preferred_ok, elbow, 1 - elbow).astype(np.int64)
    else:
        configs = _explicit_configurations(configurations, q_both, points, arm)
    q = np.ascontiguousarray(q_both[np.arange(len(points)), configs])
    if subtasks.theta is not None:
        phi = np.array(subtasks.theta, dtype=np.float64)
    else:
        phi = np.ascontiguousarray(_k.fk_batch(arm.kinematics, q)[:, 2])

    cl = arm.cartesian_limits
    leg_check = None
    extra: dict[str, Any] = {}
    if model in ("joint", "line"):
        extra = _branch_tensors(points, q_both, arm, model, line_fallback, line_grid)
        matrix = np.ascontiguousarray(gather(extra["branch_times"], configs))
        np.fill_diagonal(matrix, 0.0)
    else:
        matrix = _k.cartesian_matrix(points, phi, configs, arm.kinematics, cl.kv, cl.ka, cl.kw,
                                     cl.kw_dot, model == "paper", float(k),
                                     subtasks.theta is not None)
    for arr in (matrix, points, configs, q, phi, *extra.values()):
        arr.setflags(write=False)
    if check_legs and model in ("paper", "trapezoid"):
        leg_check = LegCheck(arm, points, q, phi, configs, n_samples)
    if model == "line":
        extra.update(line_fallback=line_fallback, line_grid=line_grid)
    return TimingResult(matrix, model, configs, leg_check, q, phi, **extra)


# Search settings of the jerk-limited line (see :class:`_line_kernels.LineLimits`):
# averaging widths from 1e-3 to 2 x the acceleration-limited duration (12 log-spaced,
# plus those beside the gaps between its largest acceleration jumps), refined by 4
# golden-section steps, each judged at 24 evenly spaced instants and in the pieces the
# largest jumps make; the width chosen is measured exactly; the stretch factor gets 1e-4
# of slack.
_TAU_RANGE = (1e-3, 2.0)
_N_TAU, _N_GOLDEN, _N_SEARCH = 12, 4, 24
_LINE_MARGIN = 1e-4


LINE_GRID = 512
"""Path intervals of a straight line by default: without jerk limits its time converges
from above as 1/grid, within 0.3% at 512 (asr_twodof: median +0.02% against 1024)."""
LINE_GRID_JERK = 256
"""Path intervals by default of an arm with joint jerk limits. Its lines' times then come
from a search over averaging widths whose spread line by line (about +-2% between grids)
dwarfs the grid's own error (planar_2r, 16 subtasks: median -0.07% at 256 and -0.01% at
512 against 1024), and every part of a line's cost is proportional to the grid but the
width estimates (a 100-subtask matrix: 1.4x v0.1's CPU at 256, 2x at 512)."""


def default_line_grid(arm: Arm) -> int:
    """The path intervals :func:`travel_times` times ``arm``'s straight lines on by default:
    :data:`LINE_GRID_JERK` with joint jerk limits, else :data:`LINE_GRID`."""
    return LINE_GRID if arm.joint_limits.jerk is None else LINE_GRID_JERK


def line_limits(arm: Arm, grid: int = LINE_GRID) -> _lk.LineLimits:
    """The kernel parameters of ``arm``'s straight-line moves on a path grid of ``grid`` intervals.

    With joint jerk limits the line is driven jerk-limited (see
    :func:`subtask_opt.arm.timing._line_kernels.line_profile`).
    """
    require_int("line_limits", "grid", grid, 16)
    cl = arm.cartesian_limits
    jl = arm.joint_limits
    jerk = np.ones(2) if jl.jerk is None else np.array(jl.jerk, dtype=np.float64)
    return _lk.LineLimits(np.array(jl.velocity, dtype=np.float64),
                          np.array(jl.acceleration, dtype=np.float64), jerk,
                          float(cl.kv), float(cl.ka), float(cl.kw), float(cl.kw_dot),
                          jl.jerk is not None, int(grid), _N_TAU, _N_GOLDEN, _N_SEARCH,
                          _TAU_RANGE[0], _TAU_RANGE[1], _LINE_MARGIN)


def _branch_tensors(points: np.ndarray, q_both: np.ndarray, arm: Arm, model: str,
                    line_fallback: str, line_grid: int) -> dict[str, np.ndarray]:
    """Times and move kinds between every pair of configurations (``joint``/``line``)."""
    jl = arm.joint_limits
    vel = np.array(jl.velocity)
    acc = np.array(jl.acceleration)
    jerk = np.zeros(2) if jl.jerk is None else np.array(jl.jerk)
    q_both = np.ascontiguousarray(q_both)
    joint = _k.joint_tensor(q_both, vel, acc, jerk, jl.jerk is not None)
    out = {"branch_joints": q_both}
    if model == "joint":
        out["branch_times"] = joint
        out["branch_moves"] = np.where(np.isfinite(joint), MOVE_JOINT, MOVE_NONE).astype(np.int8)
        return out
    line, status = _lk.line_tensor(points, q_both, arm.kinematics, line_limits(arm, line_grid))
    n = len(points)
    line4 = np.full((n, 2, n, 2), np.inf)
    for c in range(2):
        line4[:, c, :, c] = line[:, :, c]
    use_line = np.isfinite(line4)
    if line_fallback == "joint":
        times = np.where(use_line, line4, joint)
        moves = np.where(use_line, MOVE_LINE, np.where(np.isfinite(joint), MOVE_JOINT,
                                                       MOVE_NONE))
    else:
        times = line4
        moves = np.where(use_line, MOVE_LINE, MOVE_NONE)
    idx = np.arange(n)
    for c in range(2):  # staying put: no move at all
        times[idx, c, idx, c] = 0.0
    out.update(branch_times=times, branch_moves=moves.astype(np.int8), line_status=status)
    return out


__all__ = ["LINE_FALLBACKS", "LINE_STATUS_NAMES", "LegCheck", "MOVE_JOINT", "MOVE_LINE",
           "MOVE_NONE", "TIME_MODELS", "TimingResult", "scurve_time", "trapezoid_time",
           "travel_times"]

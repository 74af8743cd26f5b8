"""Order the subtasks of a planar arm for minimum total travel time.

A :class:`PlanarProblem` turns subtasks + arm + time model into the matrix of
minimum rest-to-rest travel times (or, choosing the elbows, a clustered problem over
both configurations of every subtask); :func:`solve` hands that robot-free problem to
:func:`subtask_opt.tour.solve.solve` and adds what the tour means for the arm
(:class:`~subtask_opt.arm.report.TourReport`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from subtask_opt._kernel_cache import compiling
from subtask_opt.arm.report import tour_report
from subtask_opt.base.errors import InputDataError, NoPathError, ParameterError
from subtask_opt.base.stop import StoppingCriterion, check_time_limit
from subtask_opt.tour.clustered import ConfiguredData
from subtask_opt.tour.constraints import TourConstraints, checked
from subtask_opt.tour.problem import ClusteredProblem, MatrixProblem, _validated_order
from subtask_opt.tour.solve import Result, SolverParams
from subtask_opt.tour.solve import solve as solve_tour

if TYPE_CHECKING:
    from subtask_opt.arm.targets import Targets
    from subtask_opt.arm.timing.models import TimingResult
    from subtask_opt.kinematics.planar import Arm

CONFIGURATION_MODES = ("fixed", "optimize")
DEFAULT_TIME_MODEL = "joint"
"""The time model API and CLI use by default: one the arm can execute."""


def default_configurations(time_model: str) -> str:
    """The configuration mode a time model gets by default (API and CLI alike)."""
    return "optimize" if time_model in ("joint", "line") else "fixed"


@dataclass(frozen=True)
class PlanarProblem:
    """Subtasks, the arm that visits them and the time model between them.

    The travel-time matrix is computed once, on construction. For a matrix of
    your own use :class:`MatrixProblem`.

    Attributes:
        subtasks: the points to visit.
        arm: the robot (see :func:`subtask_opt.load_planar_arm`).
        time_model: ``"joint"`` (default: times the arm can execute),
            ``"line"``, ``"trapezoid"`` or ``"paper"`` (see
            :mod:`subtask_opt.arm.timing`).
        first: index of the subtask the closed tour starts and ends at
            (default: the first row).
        k: via-point fraction of the paper's time model.
        elbow: IK branch used at every subtask (0 or 1) with fixed
            configurations; a subtask that branch cannot reach uses the other.
        configurations: ``"optimize"`` (default for the ``joint`` and ``line``
            models) lets :func:`solve` choose the order and one elbow
            configuration per subtask together (a generalised TSP, see
            :mod:`subtask_opt.tour.configurations`); ``"fixed"`` visits every
            subtask on the ``elbow`` branch (the only choice for the Cartesian
            models). ``None`` picks the default for the model.
        line_fallback: (``line``) what to do with a straight line the arm
            cannot follow: ``"joint"`` drives that leg as a joint move,
            ``"exclude"`` forbids it.
        check_all_legs: (Cartesian models) also check every straight line the
            arm might drive, not only the answer's legs, into
            ``Result.report.diagnostics["all_pairs_leg_check"]``: N (N - 1) / 2
            legs, a hundred times the matrix's cost at N = 1000. The tour's own
            legs are always checked (:class:`~subtask_opt.arm.report.TourReport`).

    With ``configurations="optimize"``, :attr:`matrix` holds the times at the
    ``elbow`` branch; :meth:`decode` gives the best configurations of an order.
    """

    subtasks: Targets
    arm: Arm
    time_model: str = DEFAULT_TIME_MODEL
    first: int | None = None
    k: float = 0.1
    elbow: int = 0
    configurations: str | None = None
    line_fallback: str = "joint"
    check_all_legs: bool = False
    timing: TimingResult = field(init=False, compare=False, repr=False)
    _tour: MatrixProblem | ClusteredProblem = field(init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        from subtask_opt.arm.targets import Targets, describe
        from subtask_opt.arm.timing.models import travel_times
        from subtask_opt.kinematics.planar import Arm

        if isinstance(self.arm, str):
            raise ParameterError(f"PlanarProblem.arm must be an Arm; got the name "
                                 f"{self.arm!r}: load it with load_planar_arm({self.arm!r})")
        if not isinstance(self.arm, Arm):
            raise ParameterError(f"PlanarProblem.arm must be an Arm, got "
                                 f"{type(self.arm).__name__}")
        if not (isinstance(self.subtasks, Targets) and self.subtasks.planar):
            raise ParameterError(f"PlanarProblem.subtasks must be planar Targets (see "
                                 f"load_subtasks), got {describe(self.subtasks)}")
        if self.subtasks.theta is not None and self.time_model in ("joint", "line"):
            warnings.warn(f"the {self.time_model} model ignores the subtasks' theta: a 2-link "
                          "arm cannot choose its tool angle (it follows from the position and "
                          "the elbow)", UserWarning, stacklevel=3)
        mode = self.configurations or default_configurations(self.time_model)
        if mode not in CONFIGURATION_MODES:
            raise ParameterError(
                f"PlanarProblem.configurations must be one of "
                f"{', '.join(CONFIGURATION_MODES)}, got {self.configurations!r}")
        object.__setattr__(self, "configurations", mode)
        if not isinstance(self.check_all_legs, bool):
            raise ParameterError(f"PlanarProblem.check_all_legs must be True or False, "
                                 f"got {self.check_all_legs!r}")
        check_time_limit("before the leg times")
        with compiling(f"timing-{self.time_model}", "the time-model kernels"):
            timing = travel_times(self.subtasks, self.arm, self.time_model, k=self.k,
                                  elbow=self.elbow, line_fallback=self.line_fallback)
        check_time_limit(f"in the leg times of {len(self.subtasks)} subtasks")
        object.__setattr__(self, "timing", timing)
        if mode == "optimize":
            if timing.branch_times is None:
                raise ParameterError(
                    f"PlanarProblem.configurations='optimize' needs the joint or line time "
                    f"model (the {self.time_model!r} model does not time elbow changes)")
        # Legs the line model excludes are the only infinite times allowed.
        excluded = self.line_fallback == "exclude" and self.time_model == "line"
        fixed = MatrixProblem(timing.matrix, first=self.first, allow_impossible=excluded)
        tour: MatrixProblem | ClusteredProblem = fixed
        if mode == "optimize":
            assert timing.branch_times is not None and timing.branch_joints is not None
            tour = ClusteredProblem(timing.branch_times, matrix=fixed.matrix,
                                    present=np.isfinite(timing.branch_joints).all(axis=2),
                                    first=self.first)
        object.__setattr__(self, "_tour", tour)

    @property
    def matrix(self) -> np.ndarray:
        """The N x N travel times at the fixed configurations (read-only)."""
        return self._tour.matrix

    @property
    def size(self) -> int:
        return self._tour.size

    @property
    def symmetric(self) -> bool:
        """Whether the travel times are the same both ways (all built-in models)."""
        return self._tour.symmetric

    @property
    def optimizes_configurations(self) -> bool:
        """Whether :func:`solve` chooses the elbow configurations."""
        return isinstance(self._tour, ClusteredProblem)

    @property
    def tour_problem(self) -> MatrixProblem | ClusteredProblem:
        """The robot-free problem this compiles into: the matrix at the fixed
        configurations, or the clustered problem over both elbows."""
        return self._tour

    def configured_data(self) -> ConfiguredData:
        """The per-configuration leg times the GA decodes (``configurations="optimize"``)."""
        if not isinstance(self._tour, ClusteredProblem):
            raise ParameterError("this problem has fixed configurations")
        return self._tour.configured_data()

    def tour_time(self, order: np.ndarray) -> float:
        """Total time of the closed tour visiting ``order`` (validated).

        With ``configurations="optimize"``: the time with the best
        configurations for that order (see :meth:`decode`).
        """
        return self.decode(order)[0]

    def decode(self, order: np.ndarray) -> tuple[float, np.ndarray]:
        """``(tour time, configurations)``: the best elbow configurations for ``order``.

        For a problem with fixed configurations these are the fixed ones.
        """
        order = _validated_order(order, self.size)
        if not self.optimizes_configurations:
            return (float(np.sum(self.matrix[order, np.roll(order, -1)])),
                    np.asarray(self.timing.configurations))
        from subtask_opt.tour.configurations import best_configurations

        assert self.timing.branch_times is not None
        return best_configurations(order, self.timing.branch_times)


def solve(problem: PlanarProblem | MatrixProblem | ClusteredProblem, *, seed: int = 0,
          stop: StoppingCriterion | list[StoppingCriterion] | None = None,
          params: SolverParams | None = None, progress: bool = False,
          certify: bool = False, certify_time_limit: float = 60.0,
          constraints: TourConstraints | None = None, home_branch: int | None = None) -> Result:
    """Find a minimum-time tour through the problem's subtasks (or nodes).

    A tour problem goes to :func:`subtask_opt.tour.solve.solve` as it is (see there for
    the arguments). An arm problem is compiled first: a home point (``constraints.home
    = (x, y)``) becomes one more subtask, checked reachable, that the tour starts and
    ends at (``home_branch``: in that elbow configuration, a home given as joint
    values); the answer then gets the arm's report of its tour (the elbows chosen in
    ``report.configurations``), and its ``configurations`` are the (N, 2) joint angles
    of every subtask (input order, the home left out).
    """
    if not isinstance(problem, PlanarProblem):
        return solve_tour(problem, seed=seed, stop=stop, params=params, progress=progress,
                          certify=certify, certify_time_limit=certify_time_limit,
                          constraints=constraints)
    constraints = checked(constraints, problem.first)
    constraints.check_size(problem.size, matrix_home=False)
    shaped, searched = constraints, problem
    if constraints.home is not None:
        searched = _with_home(problem, constraints.home, home_branch)  # type: ignore[arg-type]
        shaped = replace(constraints, home=searched.size - 1)
    try:
        result = solve_tour(searched.tour_problem, seed=seed, stop=stop, params=params,
                            progress=progress, certify=certify,
                            certify_time_limit=certify_time_limit, constraints=shaped)
    except NoPathError as exc:  # only the line model excludes legs
        raise NoPathError(f"{exc}: no tour avoids the excluded straight lines; use "
                          "line_fallback='joint' to drive such legs as joint moves") from None
    configs = (result.configurations if result.configurations is not None
               else np.asarray(searched.timing.configurations))
    tour = (np.concatenate([[searched.size - 1], result.order]) if shaped.home is not None
            else result.order)
    report = tour_report(searched, tour, configs, result.leg_times,
                         home=searched.size - 1 if shaped.home is not None else None)
    timing = searched.timing
    if timing.branch_joints is None:
        joints = np.asarray(timing.joint_positions)[:problem.size]
    else:
        joints = timing.branch_joints[np.arange(searched.size), configs][:problem.size]
    return replace(result, report=report, constraints=constraints, configurations=joints)


def _with_home(problem: PlanarProblem, home: tuple[float, float],
               branch: int | None = None) -> PlanarProblem:
    """``problem`` with the home point appended as the last subtask (checked reachable),
    visited on elbow ``branch`` when one is given."""
    import dataclasses

    from subtask_opt.arm.targets import DUPLICATE_TOL, Targets
    from subtask_opt.base.errors import UnreachableError

    xy = np.array(home, dtype=float)
    try:
        problem.arm.check_reachable(xy.reshape(1, 2))
    except UnreachableError as exc:
        text = str(exc)
        why = text.partition(") ")[2] if text.startswith("subtask 0 at") else text
        raise InputDataError(f"home point ({xy[0]:.6g}, {xy[1]:.6g}) is unreachable: {why}") \
            from None
    pts = problem.subtasks.points
    close = np.flatnonzero(np.hypot(*(pts - xy).T) < DUPLICATE_TOL)
    if close.size:
        raise InputDataError(f"home point ({xy[0]:.6g}, {xy[1]:.6g}) is subtask {close[0]}; "
                             "a home is not a subtask (use start= for a closed tour from it)")
    theta = problem.subtasks.theta
    subtasks = Targets(np.vstack([pts, xy]),
                          None if theta is None else np.append(theta, 0.0),
                          problem.subtasks.name)
    searched = dataclasses.replace(problem, subtasks=subtasks, first=None)
    if branch is not None:
        _pin_branch(searched, searched.size - 1, branch)
    return searched


def _pin_branch(problem: PlanarProblem, node: int, branch: int) -> None:
    """Visit ``node`` of a just-built problem on elbow ``branch`` only."""
    letters = "du"
    tour = problem.tour_problem
    if not isinstance(tour, ClusteredProblem):
        fixed = int(np.asarray(problem.timing.configurations)[node])
        if fixed != branch:
            names = ("down", "up")
            raise ParameterError(
                f"the home configuration is elbow {names[branch]} ({letters[branch]}), but "
                f"this problem visits it elbow {names[fixed]} with fixed configurations: "
                f"use elbow={branch} or configurations='optimize'")
        return
    costs = np.array(tour.costs)
    costs[node, 1 - branch] = np.inf
    costs[:, :, node, 1 - branch] = np.inf
    present = np.array(tour.present)
    present[node, 1 - branch] = False
    if not present[node, branch]:
        raise InputDataError(f"the home configuration's elbow branch ({letters[branch]}) "
                             "cannot reach the home point")
    object.__setattr__(problem, "_tour", ClusteredProblem(costs, present=present))



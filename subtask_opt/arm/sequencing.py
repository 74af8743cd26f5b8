"""Order the subtasks of a planar arm for minimum total travel time.

A :class:`SequencingProblem` turns subtasks + arm + time model into the matrix
of minimum rest-to-rest travel times; :func:`solve` finds a closed tour over it
with the micro genetic algorithm of the paper (``preset="paper"``) or with our
default, a micro-GA whose children are polished by local search.

>>> from subtask_opt import load_arm, builtin_case, SequencingProblem, solve
>>> arm = load_arm("planar_2r")
>>> problem = SequencingProblem(builtin_case("random30", arm, seed=0), arm)
>>> result = solve(problem, seed=1)
>>> print(result.summary())  # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.arm import _configuration_kernels  # noqa: F401  (registers its GA kind)
from subtask_opt.arm.configurations import penalty_for
from subtask_opt.base.errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    require_in_range,
    require_int,
)
from subtask_opt.base.progress import progress_bar
from subtask_opt.base.results import History
from subtask_opt.base.stop import MaxGenerations, NoImprovement, StoppingCriterion, as_criteria
from subtask_opt.ga.config import GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import run_ga
from subtask_opt.ga.permutation import (
    SEARCH_EXACT,
    SEARCH_FAST,
    SEARCH_PAPER,
    make_aux,
    neighbour_table,
)

if TYPE_CHECKING:
    from subtask_opt.arm.model import Arm
    from subtask_opt.arm.tasks import SubtaskSet
    from subtask_opt.arm.timing.models import TimingResult

PRESETS = ("default", "paper")
CONFIGURATION_MODES = ("fixed", "optimize")


@dataclass(frozen=True)
class SolverParams:
    """How :func:`solve` searches.

    Attributes:
        preset: ``"paper"`` is the paper's micro-GA exactly (population 5,
            elitism, random pairing, greedy crossover with a random fallback,
            random restarts on convergence, no mutation, no local search).
            ``"default"`` keeps that loop and adds what makes it fast and
            reliable: nearest-city fallback in the crossover, a 2-opt/Or-opt
            local search around every change, and restarts that mix kicks of
            the best tour with randomised nearest-neighbour tours.
        population: micro-GA population size (the paper: 5).
        convergence_tol: relative cost spread below which the population
            counts as converged and restarts.
        grasp_share: (default preset) share of restart individuals built by
            randomised nearest neighbour instead of kicking the best tour.
        max_segment: (default preset) longest run of subtasks Or-opt moves.
        neighbours: (default preset) candidate list length of the local search.
    """

    preset: str = "default"
    population: int = 5
    convergence_tol: float = 0.01
    grasp_share: float = 0.25
    max_segment: int = 3
    neighbours: int = 8

    def __post_init__(self) -> None:
        if self.preset not in PRESETS:
            raise ParameterError(
                f"SolverParams.preset must be one of {', '.join(PRESETS)}, got {self.preset!r}")
        require_int("SolverParams", "population", self.population, 3)
        require_in_range("SolverParams", "convergence_tol", self.convergence_tol, 0.0, 1.0)
        require_in_range("SolverParams", "grasp_share", self.grasp_share, 0.0, 1.0)
        require_int("SolverParams", "max_segment", self.max_segment, 1)
        require_int("SolverParams", "neighbours", self.neighbours, 1)

    @classmethod
    def paper(cls) -> SolverParams:
        return cls(preset="paper")

    def default_stop(self) -> list[StoppingCriterion]:
        """Stopping criteria used when :func:`solve` is given none."""
        if self.preset == "paper":
            return [NoImprovement(2000), MaxGenerations(50_000)]
        # 15 stalled generations reach the certified optimum of every built-in
        # instance in benchmarks/sequencing.py; pass NoImprovement(50) for more certainty.
        return [NoImprovement(15), MaxGenerations(50_000)]


@dataclass(frozen=True)
class SequencingProblem:
    """Subtasks, the arm that visits them and the time model between them.

    The travel-time matrix is computed once, on construction. For a matrix of
    your own use :meth:`from_matrix`.

    Attributes:
        subtasks: the points to visit.
        arm: the robot (see :func:`subtask_opt.load_arm`).
        time_model: ``"trapezoid"`` (default), ``"paper"``, ``"joint"`` or
            ``"line"`` (see :mod:`subtask_opt.arm.timing.models`).
        first: index of the subtask the closed tour starts and ends at
            (default: the first row).
        k: via-point fraction of the paper's time model.
        elbow: IK branch used at every subtask (0 or 1); a subtask that branch
            cannot reach uses the other.
        configurations: ``"fixed"`` (default) visits every subtask on the
            ``elbow`` branch; ``"optimize"`` (``joint`` and ``line`` models)
            lets :func:`solve` choose the order and one elbow configuration per
            subtask together (a generalised TSP, see
            :mod:`subtask_opt.arm.configurations`).
        line_fallback: (``line``) what to do with a straight line the arm
            cannot follow: ``"joint"`` drives that leg as a joint move,
            ``"exclude"`` forbids it.

    With ``configurations="optimize"``, :attr:`matrix` still holds the times at
    the ``elbow`` branch; the :class:`Result` holds the matrix of the
    configurations the solver chose, and :meth:`tour_time` decodes the best
    configurations of the order it is given.
    """

    subtasks: SubtaskSet | None
    arm: Arm | None
    time_model: str = "trapezoid"
    first: int | None = None
    k: float = 0.1
    elbow: int = 0
    configurations: str = "fixed"
    line_fallback: str = "joint"
    timing: TimingResult | None = field(default=None, compare=False, repr=False)
    _matrix: np.ndarray = field(default=None, init=False, compare=False, repr=False)  # type: ignore[assignment]
    _symmetric: bool = field(default=False, init=False, compare=False, repr=False)
    _neighbours: np.ndarray = field(default=None, init=False, compare=False, repr=False)  # type: ignore[assignment]
    _data: np.ndarray | None = field(default=None, init=False, compare=False, repr=False)
    _penalty: float = field(default=0.0, init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.configurations not in CONFIGURATION_MODES:
            raise ParameterError(
                f"SequencingProblem.configurations must be one of "
                f"{', '.join(CONFIGURATION_MODES)}, got {self.configurations!r}")
        if self.timing is None:
            if self.subtasks is None or self.arm is None:
                raise ParameterError(
                    "SequencingProblem needs subtasks and an arm (or use from_matrix)")
            from subtask_opt.arm.timing.models import travel_times

            timing = travel_times(self.subtasks, self.arm, self.time_model, k=self.k,
                                  elbow=self.elbow, line_fallback=self.line_fallback)
            object.__setattr__(self, "timing", timing)
        branch_times = self.timing.branch_times  # type: ignore[union-attr]
        if self.configurations == "optimize":
            if branch_times is None:
                raise ParameterError(
                    f"SequencingProblem.configurations='optimize' needs the joint or line time "
                    f"model (the {self.time_model!r} model does not time elbow changes)")
            from subtask_opt.arm.configurations import pack_data

            data, penalty = pack_data(branch_times)
            object.__setattr__(self, "_data", data)
            object.__setattr__(self, "_penalty", penalty)
        # Legs the line model excludes are the only infinite times allowed.
        excluded = (np.isinf(self.timing.matrix)  # type: ignore[union-attr]
                    if getattr(self.timing, "line_fallback", "joint") == "exclude"
                    and self.time_model == "line" else None)
        matrix = _validated_matrix(self.timing.matrix, allow_inf=excluded)  # type: ignore[union-attr]
        object.__setattr__(self, "_matrix", matrix)
        object.__setattr__(self, "_symmetric",
                           bool(np.allclose(matrix, matrix.T, rtol=1e-12, atol=0.0)))
        object.__setattr__(self, "_neighbours", neighbour_table(matrix))
        n = matrix.shape[0]
        if self.first is not None and (
                isinstance(self.first, bool) or not isinstance(self.first, (int, np.integer))
                or not 0 <= self.first < n):
            raise ParameterError(
                f"SequencingProblem.first must be a subtask index in [0, {n - 1}], "
                f"got {self.first!r}")

    @classmethod
    def from_matrix(cls, matrix: np.ndarray, *, first: int | None = None) -> SequencingProblem:
        """A problem over a travel-time matrix of your own (N x N, finite, >= 0)."""
        from subtask_opt.arm.timing.models import TimingResult

        m = _validated_matrix(matrix)
        timing = TimingResult(matrix=m, model="custom",
                              configurations=np.zeros(m.shape[0], dtype=np.int64),
                              leg_check=None)
        return cls(subtasks=None, arm=None, time_model="custom", first=first, timing=timing)

    @property
    def matrix(self) -> np.ndarray:
        """The N x N travel times the solver minimises over (read-only)."""
        return self._matrix

    @property
    def size(self) -> int:
        return int(self._matrix.shape[0])

    @property
    def symmetric(self) -> bool:
        """Whether the travel times are the same both ways (all built-in models)."""
        return self._symmetric

    @property
    def optimizes_configurations(self) -> bool:
        """Whether :func:`solve` chooses the elbow configurations."""
        return self._data is not None

    def tour_time(self, order: np.ndarray) -> float:
        """Total time of the closed tour visiting ``order`` (validated).

        With ``configurations="optimize"``: the time with the best
        configurations for that order (see :meth:`decode`).
        """
        order = _validated_order(order, self.size)
        if self.optimizes_configurations:
            return self.decode(order)[0]
        return float(np.sum(self._matrix[order, np.roll(order, -1)]))

    def decode(self, order: np.ndarray) -> tuple[float, np.ndarray]:
        """``(tour time, configurations)``: the best elbow configurations for ``order``.

        For a problem with fixed configurations these are the fixed ones.
        """
        order = _validated_order(order, self.size)
        if not self.optimizes_configurations:
            return self.tour_time(order), np.asarray(self.timing.configurations)  # type: ignore[union-attr]
        from subtask_opt.arm.configurations import best_configurations

        return best_configurations(order, self.timing.branch_times)  # type: ignore[union-attr]


@dataclass(frozen=True)
class Result:
    """The answer of :func:`solve`.

    Attributes:
        order: 0-based subtask indices of the closed tour, starting at the
            problem's ``first`` subtask (or subtask 0).
        total_time: time of the closed tour (seconds under the time model).
        leg_times: ``leg_times[i]`` is the time from ``order[i]`` to
            ``order[(i + 1) % N]``.
        matrix: the N x N travel times that were optimised.
        generations, restarts: what the micro-GA did.
        runtime_s: wall time of the search (JIT compile excluded once warm).
        seed: the seed that reproduces this result.
        history: best and mean cost per generation, restart generations.
        preset, time_model, robot: what was solved and how.
        configurations: the IK branch used at each subtask (by index).
        infeasible_legs: the joint-limit check of the straight-line legs for
            the Cartesian models; for the ``line`` model, the tour's legs whose
            straight line is infeasible (``None`` for the joint model).
        leg_moves: how each leg is driven: ``"line"`` (straight line) or
            ``"joint"`` (joint-space move); None for a custom matrix.
        configurations_mode: ``"fixed"`` or ``"optimize"`` (chosen by the solver).
    """

    order: np.ndarray
    total_time: float
    leg_times: np.ndarray
    matrix: np.ndarray
    generations: int
    restarts: int
    runtime_s: float
    seed: int
    history: History
    preset: str
    time_model: str
    robot: str
    configurations: np.ndarray
    infeasible_legs: dict[str, Any] | None = None
    leg_moves: tuple[str, ...] | None = None
    configurations_mode: str = "fixed"

    @property
    def configuration_changes(self) -> int:
        """Legs whose two ends use different elbow configurations."""
        c = self.configurations[self.order]
        return int(np.sum(c != np.roll(c, -1)))

    def summary(self) -> str:
        """A few lines for a terminal."""
        lines = [
            f"{len(self.order)} subtasks, {self.time_model} time model, robot {self.robot}",
            f"total time {self.total_time:.4f} s  ({self.preset} preset, seed {self.seed}, "
            f"{self.generations} generations, {self.restarts} restarts, "
            f"{self.runtime_s * 1e3:.2f} ms)",
            "order: " + " ".join(str(int(i)) for i in self.order),
        ]
        if self.configurations_mode == "optimize":
            c = self.configurations[self.order]
            lines.append("elbow: " + " ".join("du"[int(b)] for b in c)
                         + f"  (d down, u up; {self.configuration_changes} changes)")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the CLI's ``--json``)."""
        return {
            "order": [int(i) for i in self.order],
            "total_time": self.total_time,
            "leg_times": self.leg_times.tolist(),
            "matrix": self.matrix.tolist(),
            "generations": self.generations,
            "restarts": self.restarts,
            "runtime_s": self.runtime_s,
            "seed": self.seed,
            "preset": self.preset,
            "time_model": self.time_model,
            "robot": self.robot,
            "configurations": [int(c) for c in self.configurations],
            "configurations_mode": self.configurations_mode,
            "leg_moves": None if self.leg_moves is None else list(self.leg_moves),
            "infeasible_legs": self.infeasible_legs,
            "history": self.history.to_dict(),
        }


def solve(problem: SequencingProblem, *, seed: int = 0,
          stop: StoppingCriterion | list[StoppingCriterion] | None = None,
          params: SolverParams | None = None, progress: bool = False) -> Result:
    """Find a minimum-time closed tour through the problem's subtasks.

    Args:
        problem: what to solve.
        seed: random seed; the same seed gives the same result.
        stop: one stopping criterion or a list (any of them stops the run);
            default: ``params.default_stop()``.
        params: solver parameters (default: ``SolverParams()``).
        progress: show a progress bar on stderr for runs over a second.
    """
    if not isinstance(problem, SequencingProblem):
        raise ParameterError(f"solve needs a SequencingProblem, got {type(problem).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be an integer >= 0, got {seed!r}")
    params = params or SolverParams()
    criteria = as_criteria(stop, params.default_stop())
    matrix = problem.matrix
    n = problem.size
    paper = params.preset == "paper"
    configured = problem.optimizes_configurations
    if configured:
        data = problem._data
        kind = Kind.CONFIGURED_PERMUTATION
        search = SEARCH_PAPER if paper else SEARCH_FAST
        neighbours = neighbour_table(data[:, :n])
    else:
        # a GA tour may not use an excluded leg: a finite penalty keeps the costs comparable
        data = np.where(np.isfinite(matrix), matrix, penalty_for(matrix))
        neighbours = problem._neighbours
        kind = Kind.PERMUTATION
        if paper:
            search = SEARCH_PAPER
        else:
            search = SEARCH_FAST if problem.symmetric else SEARCH_EXACT
    aux = make_aux(neighbours, nearest_fallback=not paper,
                   grasp_share=params.grasp_share, max_segment=params.max_segment,
                   neighbours=params.neighbours, search=search)
    config = GAConfig(population=params.population, elite=1, crossover_rate=1.0,
                      mutation_rate=0.0, restart_on_convergence=True,
                      convergence_tol=params.convergence_tol)
    total = next((c.generations for c in criteria if isinstance(c, MaxGenerations)), None)
    with progress_bar(progress, total=total, desc="micro-GA", unit="gen") as bar:
        done = [0]

        def on_chunk(p) -> None:
            bar.update(p.generation - done[0])
            done[0] = p.generation
            bar.set_postfix_str(f"best {p.best_cost:.4f}")

        outcome = run_ga(kind, config, data, aux, max_genes=n, seed=int(seed),
                         criteria=criteria, on_chunk=on_chunk)
    order = _rotate(outcome.genes, problem.first if problem.first is not None else 0)
    timing = problem.timing
    configs = np.asarray(timing.configurations)  # type: ignore[union-attr]
    if configured:
        from subtask_opt.arm.configurations import induced_matrix

        _, configs = problem.decode(order)
        matrix = induced_matrix(timing.branch_times, configs)  # type: ignore[union-attr]
        matrix.setflags(write=False)
    legs = matrix[order, np.roll(order, -1)]
    if not np.all(np.isfinite(legs)):
        k = int(np.flatnonzero(~np.isfinite(legs))[0])
        raise NoPathError(
            f"no closed tour avoids the excluded straight lines (the best one needs the "
            f"impossible line {order[k]} -> {order[(k + 1) % n]}); use line_fallback='joint' "
            "to drive such legs as joint moves")
    leg_moves = None
    moves = timing.moves(configs)  # type: ignore[union-attr]
    if moves is not None:
        names = {0: "joint", 1: "line"}
        leg_moves = tuple(names[int(m)] for m in moves[order, np.roll(order, -1)])
    if problem.time_model == "line":
        infeasible = timing.line_summary(order, configs)  # type: ignore[union-attr]
    else:
        leg_check = getattr(timing, "leg_check", None)
        infeasible = leg_check.to_dict() if leg_check is not None else None
    return Result(
        order=order,
        total_time=float(np.sum(legs)),
        leg_times=legs,
        matrix=matrix,
        generations=outcome.generations,
        restarts=outcome.restarts,
        runtime_s=outcome.runtime_s,
        seed=int(seed),
        history=outcome.history,
        preset=params.preset,
        time_model=problem.time_model,
        robot=problem.arm.name if problem.arm is not None else "custom",
        configurations=configs,
        infeasible_legs=infeasible,
        leg_moves=leg_moves,
        configurations_mode="optimize" if configured else "fixed",
    )


def _rotate(tour: np.ndarray, first: int) -> np.ndarray:
    start = int(np.flatnonzero(tour == first)[0])
    return np.roll(np.asarray(tour, dtype=np.int64), -start)


def _validated_matrix(matrix: np.ndarray, allow_inf: np.ndarray | None = None) -> np.ndarray:
    m = np.array(matrix, dtype=float)
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputDataError(f"travel-time matrix must be square, got shape {m.shape}")
    if m.shape[0] < 3:
        raise InputDataError(f"need at least 3 subtasks, got {m.shape[0]}")
    bad = np.argwhere(~np.isfinite(m) & (True if allow_inf is None else ~allow_inf))
    if bad.size:
        i, j = bad[0]
        raise InputDataError(
            f"travel time from subtask {i} to {j} is {m[i, j]} (must be finite)")
    neg = np.argwhere(m < 0)
    if neg.size:
        i, j = neg[0]
        raise InputDataError(f"travel time from subtask {i} to {j} is negative ({m[i, j]})")
    m.setflags(write=False)
    return m


def _validated_order(order: np.ndarray, n: int) -> np.ndarray:
    o = np.asarray(order)
    if o.shape != (n,) or not np.array_equal(np.sort(o), np.arange(n)):
        raise ParameterError(f"order must be a permutation of 0..{n - 1}, got {order!r}")
    return o.astype(np.int64)


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

from .errors import InputDataError, ParameterError, require_in_range, require_int
from .ga.core import GAConfig, run_ga
from .ga.permutation import make_aux
from .ga.registry import EXACT_MEMETIC_OPERATORS, MEMETIC_OPERATORS, PAPER_OPERATORS
from .progress import progress_bar
from .result import History
from .stop import MaxGenerations, NoImprovement, StoppingCriterion, as_criteria

if TYPE_CHECKING:
    from .arm import Arm
    from .tasks import SubtaskSet
    from .timing import TimingResult

PRESETS = ("default", "paper")


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
    grasp_share: float = 0.5
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
        return [NoImprovement(30), MaxGenerations(50_000)]


@dataclass(frozen=True)
class SequencingProblem:
    """Subtasks, the arm that visits them and the time model between them.

    The travel-time matrix is computed once, on construction. For a matrix of
    your own use :meth:`from_matrix`.

    Attributes:
        subtasks: the points to visit.
        arm: the robot (see :func:`subtask_opt.load_arm`).
        time_model: ``"trapezoid"`` (default), ``"paper"`` or ``"joint"``
            (see :mod:`subtask_opt.timing`).
        first: index of the subtask the closed tour starts and ends at
            (default: the first row).
        k: via-point fraction of the paper's time model.
        elbow: IK branch used at every subtask (0 or 1).
    """

    subtasks: SubtaskSet | None
    arm: Arm | None
    time_model: str = "trapezoid"
    first: int | None = None
    k: float = 0.1
    elbow: int = 0
    timing: TimingResult | None = field(default=None, compare=False, repr=False)
    _matrix: np.ndarray = field(default=None, init=False, compare=False, repr=False)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.timing is None:
            if self.subtasks is None or self.arm is None:
                raise ParameterError(
                    "SequencingProblem needs subtasks and an arm (or use from_matrix)")
            from .timing import travel_times

            timing = travel_times(self.subtasks, self.arm, self.time_model, k=self.k,
                                  elbow=self.elbow)
            object.__setattr__(self, "timing", timing)
        matrix = _validated_matrix(self.timing.matrix)  # type: ignore[union-attr]
        object.__setattr__(self, "_matrix", matrix)
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
        from .timing import TimingResult

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
        return bool(np.allclose(self._matrix, self._matrix.T, rtol=1e-12, atol=0.0))

    def tour_time(self, order: np.ndarray) -> float:
        """Total time of the closed tour visiting ``order`` (validated)."""
        order = _validated_order(order, self.size)
        return float(np.sum(self._matrix[order, np.roll(order, -1)]))


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
            the Cartesian models (``None`` for the joint model).
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

    def summary(self) -> str:
        """A few lines for a terminal."""
        lines = [
            f"{len(self.order)} subtasks, {self.time_model} time model, robot {self.robot}",
            f"total time {self.total_time:.4f} s  ({self.preset} preset, seed {self.seed}, "
            f"{self.generations} generations, {self.restarts} restarts, "
            f"{self.runtime_s * 1e3:.2f} ms)",
            "order: " + " ".join(str(int(i)) for i in self.order),
        ]
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
    if paper:
        operators = PAPER_OPERATORS
    else:
        operators = MEMETIC_OPERATORS if problem.symmetric else EXACT_MEMETIC_OPERATORS
    aux = make_aux(matrix, nearest_fallback=not paper, grasp_share=params.grasp_share,
                   max_segment=params.max_segment, neighbours=params.neighbours)
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

        outcome = run_ga(operators, config, matrix, aux, max_genes=n, seed=int(seed),
                         criteria=criteria, on_chunk=on_chunk)
    order = _rotate(outcome.genes, problem.first if problem.first is not None else 0)
    legs = matrix[order, np.roll(order, -1)]
    timing = problem.timing
    leg_check = getattr(timing, "leg_check", None)
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
        configurations=np.asarray(timing.configurations),  # type: ignore[union-attr]
        infeasible_legs=leg_check.to_dict() if leg_check is not None else None,
    )


def _rotate(tour: np.ndarray, first: int) -> np.ndarray:
    start = int(np.flatnonzero(tour == first)[0])
    return np.roll(np.asarray(tour, dtype=np.int64), -start)


def _validated_matrix(matrix: np.ndarray) -> np.ndarray:
    m = np.array(matrix, dtype=float)
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputDataError(f"travel-time matrix must be square, got shape {m.shape}")
    if m.shape[0] < 3:
        raise InputDataError(f"need at least 3 subtasks, got {m.shape[0]}")
    bad = np.argwhere(~np.isfinite(m))
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


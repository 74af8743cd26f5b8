"""GA path planner on an occupancy grid (the thesis' chapter 4), on the shared GA core.

Genes are integer cells (x, y) stored as ``y * width + x``; a chromosome is a
variable-length polyline start -> waypoints -> goal (:mod:`._waypoint_kernels`).
The loop is :func:`subtask_opt.ga.loop.run_ga`: elitism, single-point
crossover, non-uniform mutation, stopping criteria from :mod:`subtask_opt.base.stop`.

Two registered planners share the loop and the operators:

* ``ga-paper`` (:meth:`GAPathParams.paper`) - the thesis as written: random
  initial paths redrawn until feasible, population 50, crossover 0.6,
  mutation 0.2, no local search, 100 generations (default ``stop``). In
  cluttered maps random paths are almost never feasible and it fails, as the
  thesis found.
* ``ga`` (:class:`GAPathParams` ``()``) - our improved planner: line-of-sight
  random trees as initial paths and the shortcut operator as ``improve``; by
  default it stops after 40 generations without improvement (at most 400).

Both honour ``stop`` (criteria of :mod:`subtask_opt.base.stop`) and ``seed``
(``None`` means seed 0, so an unseeded run is reproducible too).

The reported path is checked again, segment by segment, by
:func:`path_is_free` (exact segment / closed-cell test), so a path through an
obstacle is never reported as a success.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int, require_positive
from subtask_opt.base.geometry import polyline_length
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.base.stop import MaxGenerations, NoImprovement, StoppingCriterion, as_criteria
from subtask_opt.chromosomes import use
from subtask_opt.ga.config import GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import run_ga
from subtask_opt.planners.base import check_seed, register
from subtask_opt.planners.grid import _waypoint_kernels as wp
from subtask_opt.planners.grid._kernels import segment_hits
from subtask_opt.planners.grid.distance_transform import distance_field
from subtask_opt.planners.grid.world import GridWorld, check_small_grid

INITS = ("random", "visibility")

DEFAULT_STOP: tuple[StoppingCriterion, ...] = (MaxGenerations(400), NoImprovement(40))
"""``stop=None`` for ``ga``: 40 generations without a better path, at most 400."""
PAPER_STOP: tuple[StoppingCriterion, ...] = (MaxGenerations(100),)
"""``stop=None`` for ``ga-paper``: the thesis' 100 generations."""


@dataclass(frozen=True)
class GAPathParams:
    """Parameters of the GA path planner.

    The GA fields (``population`` ... ``mutation_horizon``) mean what they mean
    in :class:`~subtask_opt.ga.config.GAConfig` and are validated by
    :meth:`GAConfig.validate`; when to stop is the ``stop`` argument of
    :func:`plan`, not a parameter.

    Attributes:
        population: individuals per generation (thesis: 50).
        elite: best individuals copied unchanged into the next generation.
        crossover_rate: single-point crossover probability (thesis: 0.6).
        mutation_rate: non-uniform mutation probability (thesis: 0.1-0.3).
        tournament: parents picked by k-tournament (0 = uniformly).
        restart_on_convergence: re-seed a converged population (off: the thesis has none).
        convergence_tol: see :class:`GAConfig`.
        mutation_horizon: generations over which mutation steps shrink.
        max_genes: longest chromosome, start and goal included.
        penalty: ``Q``, added per blocked cell a path touches.
        init: ``"random"`` (thesis) or ``"visibility"`` (line-of-sight trees).
        init_tries: draws per initial member before keeping the least bad.
        shortcut: the ``improve`` operator drops waypoints that can be skipped.
        max_free_cells: larger grids are refused (the planner is meant for
            small workspaces like the thesis' 14 x 9; use the transforms on big maps).
    """

    population: int = 50
    elite: int = 2
    crossover_rate: float = 0.6
    mutation_rate: float = 0.3
    tournament: int = 3
    restart_on_convergence: bool = False
    convergence_tol: float = 0.01
    mutation_horizon: int = 400
    max_genes: int = 24
    penalty: float = 100.0
    init: str = "visibility"
    init_tries: int = 20
    shortcut: bool = True
    max_free_cells: int = 20000

    def __post_init__(self) -> None:
        owner = "GAPathParams"
        # the one GA validator; it reads only the GA fields, which this class shares
        GAConfig.validate(cast(GAConfig, self), owner)
        require_int(owner, "max_genes", self.max_genes, 2, 100_000)
        require_positive(owner, "penalty", self.penalty)
        if self.init not in INITS:
            raise ParameterError(f"{owner}.init must be one of {INITS}, got {self.init!r}")
        require_int(owner, "init_tries", self.init_tries, 1, 1_000_000)
        if not isinstance(self.shortcut, bool):
            raise ParameterError(f"{owner}.shortcut must be True or False, got {self.shortcut!r}")
        require_int(owner, "max_free_cells", self.max_free_cells, 1)

    @classmethod
    def paper(cls, **overrides: Any) -> GAPathParams:
        """The thesis' GA: random initial paths, no local search (run it with
        :data:`PAPER_STOP`, the default of planner ``ga-paper``)."""
        base = cls(elite=1, mutation_rate=0.2, tournament=2, mutation_horizon=100,
                   init="random", init_tries=50, shortcut=False)
        return replace(base, **overrides)

    def config(self) -> GAConfig:
        """The loop's configuration."""
        return GAConfig(population=self.population, elite=self.elite,
                        crossover_rate=self.crossover_rate, mutation_rate=self.mutation_rate,
                        restart_on_convergence=self.restart_on_convergence,
                        convergence_tol=self.convergence_tol, tournament=self.tournament,
                        mutation_horizon=self.mutation_horizon)


def path_is_free(world: GridWorld, path: np.ndarray) -> bool:
    """Whether every segment of ``path`` (cells) avoids every blocked cell (closed squares)."""
    blocked = world.occupancy.view(np.uint8)
    pts = np.asarray(path, dtype=np.int64)
    for (x0, y0), (x1, y1) in zip(pts[:-1], pts[1:], strict=True):
        if segment_hits(blocked, int(x0), int(y0), int(x1), int(y1), True):
            return False
    return True


def plan(world: GridWorld, start: Any, goal: Any, *, params: GAPathParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Plan a path with the GA (``params`` default: the improved :class:`GAPathParams`).

    ``seed``: None or an integer in [0, 2**63); None means 0. ``stop``: a
    stopping criterion or a list of them; None means :data:`DEFAULT_STOP`
    (:data:`PAPER_STOP` for ``init="random"`` params, the thesis' preset).

    Returns a :class:`PlanResult` whose ``history`` is the per-generation best
    and mean cost; ``success=False`` (outcome ``no_path``, with the reason)
    when the best path still crosses an obstacle. Start == goal gives a
    one-cell path of length 0. ``info`` holds ``fitness`` (``F = C / length``
    with ``C`` the straight-line distance, so 1 is the unobstructed optimum),
    ``generations``, ``seed`` and ``init``.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
        ParameterError: a bad seed or stop, or a grid over ``max_free_cells``.
    """
    params = params or GAPathParams()
    seed_value = check_seed(seed)
    seed_value = 0 if seed_value is None else seed_value
    name = "ga" if params.init == "visibility" else "ga-paper"
    criteria = as_criteria(stop, list(DEFAULT_STOP if params.init == "visibility"
                                      else PAPER_STOP))
    start_xy = world.check_cell("start", start)
    goal_xy = world.check_cell("goal", goal)
    check_small_grid(world, params.max_free_cells, "the GA path planner is for small grids")
    if start_xy == goal_xy:
        return PlanResult(np.array([start_xy], dtype=float), True, "ok: start is the goal", name,
                          info={"generations": 0, "seed": seed_value, "init": params.init,
                                "fitness": 1.0})
    t0 = time.perf_counter()
    # a segment may not pass a corner gap, so the GA can only reach the start's 4-connected
    # component: decide that in one distance transform instead of running out of generations
    field = distance_field(world, goal_xy, "octile", corner_cutting=False)
    if not np.isfinite(field[start_xy[1], start_xy[0]]):
        return PlanResult(np.zeros((0, 2)), False,
                          "no path: the goal is not connected to the start by free cells",
                          name, time.perf_counter() - t0,
                          info={"generations": 0, "seed": seed_value, "init": params.init,
                                "fitness": 0.0}, outcome=Outcome.NO_PATH)
    data = world.occupancy.astype(np.float64)
    aux = wp.make_aux(start_xy, goal_xy, penalty=params.penalty,
                      init=wp.INIT_VISIBILITY if params.init == "visibility" else wp.INIT_RANDOM,
                      init_tries=params.init_tries, shortcut=params.shortcut)
    out = run_ga(use(Kind.WAYPOINT_PATH), params.config(), data, aux, max_genes=params.max_genes,
                 seed=seed_value, criteria=criteria)
    runtime = time.perf_counter() - t0
    w = world.width
    path = np.stack([out.genes % w, out.genes // w], axis=1).astype(float)
    straight = float(np.hypot(goal_xy[0] - start_xy[0], goal_xy[1] - start_xy[1]))
    free = path_is_free(world, path)
    info = {"generations": out.generations, "seed": seed_value, "init": params.init,
            "fitness": straight / polyline_length(path) if free else 0.0}
    if not free:
        return PlanResult(np.zeros((0, 2)), False,
                          f"no collision-free path after {out.generations} generations "
                          f"(best still crosses obstacles)", name, runtime, out.history, info,
                          outcome=Outcome.NO_PATH)
    return PlanResult(path, True, "ok", name, runtime, out.history, info)


@register("grid", "ga", description="GA path planner, improved (line-of-sight init, shortcuts)",
          stochastic=True, iterative=True)
def plan_ga(world: GridWorld, start: Any, goal: Any, *, params: GAPathParams | None = None,
            seed: int | None = None, stop: Any = None) -> PlanResult:
    """The improved GA: :func:`plan` with ``GAPathParams()`` by default."""
    return plan(world, start, goal, params=params or GAPathParams(), seed=seed, stop=stop)


@register("grid", "ga-paper", description="GA path planner as in the thesis (random init)",
          stochastic=True, iterative=True)
def plan_ga_paper(world: GridWorld, start: Any, goal: Any, *, params: GAPathParams | None = None,
                  seed: int | None = None, stop: Any = None) -> PlanResult:
    """The thesis' GA: :func:`plan` with :meth:`GAPathParams.paper` by default."""
    return plan(world, start, goal, params=params or GAPathParams.paper(), seed=seed, stop=stop)

"""GA path planner on an occupancy grid (the thesis' chapter 4), on the shared GA core.

Genes are integer cells (x, y) stored as ``y * width + x``; a chromosome is a
variable-length polyline start -> waypoints -> goal (:mod:`._waypoint_kernels`).
The loop is :func:`subtask_opt.ga.loop.run_ga`: elitism, single-point
crossover, non-uniform mutation, stopping criteria from :mod:`subtask_opt.base.stop`.

Two presets:

* :meth:`GAPathParams.paper` - the thesis as written: random initial paths
  redrawn until feasible, population 50, crossover 0.6, mutation 0.2,
  100 generations, no local search. In cluttered maps random paths are
  almost never feasible and it fails, as the thesis found.
* the default (:class:`GAPathParams` ``()``) - our improved planner: the same
  loop and operators, but line-of-sight random walks as initial paths and
  the shortcut operator as ``improve``, run until 40 generations pass
  without improvement (at most 400).

The reported path is checked again, segment by segment, by
:func:`path_is_free` (exact segment / closed-cell test), so a path through an
obstacle is never reported as a success.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_in_range, require_int, require_positive
from subtask_opt.base.results import PlanResult
from subtask_opt.base.stop import MaxGenerations, NoImprovement
from subtask_opt.ga.config import GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import run_ga
from subtask_opt.planners.grid import _waypoint_kernels as wp
from subtask_opt.planners.grid._kernels import segment_hits
from subtask_opt.planners.grid.world import GridWorld

INITS = ("random", "visibility")


@dataclass(frozen=True)
class GAPathParams:
    """Parameters of the GA path planner.

    Attributes:
        population: individuals per generation (thesis: 50).
        elite: best individuals copied unchanged into the next generation.
        crossover_rate: single-point crossover probability (thesis: 0.6).
        mutation_rate: non-uniform mutation probability (thesis: 0.1-0.3).
        tournament: parents picked by k-tournament (0 = uniformly).
        max_generations: hard limit on generations (thesis: 100).
        stall_generations: stop after this many generations without a better
            path (``None``: run all ``max_generations``).
        max_genes: longest chromosome, start and goal included.
        penalty: ``Q``, added per blocked cell a path touches.
        init: ``"random"`` (thesis) or ``"visibility"`` (line-of-sight walks).
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
    max_generations: int = 400
    stall_generations: int | None = 40
    max_genes: int = 24
    penalty: float = 100.0
    init: str = "visibility"
    init_tries: int = 20
    shortcut: bool = True
    max_free_cells: int = 20000

    def __post_init__(self) -> None:
        owner = "GAPathParams"
        require_int(owner, "population", self.population, 2)
        require_int(owner, "elite", self.elite, 0)
        if self.elite >= self.population:
            raise ParameterError(
                f"{owner}.elite must be < population ({self.population}), got {self.elite!r}")
        require_in_range(owner, "crossover_rate", self.crossover_rate, 0.0, 1.0)
        require_in_range(owner, "mutation_rate", self.mutation_rate, 0.0, 1.0)
        require_int(owner, "tournament", self.tournament, 0)
        if self.tournament == 1 or self.tournament > self.population:
            raise ParameterError(
                f"{owner}.tournament must be 0 or in [2, population], got {self.tournament!r}")
        require_int(owner, "max_generations", self.max_generations, 1)
        if self.stall_generations is not None:
            require_int(owner, "stall_generations", self.stall_generations, 1)
        require_int(owner, "max_genes", self.max_genes, 2)
        require_positive(owner, "penalty", self.penalty)
        if self.init not in INITS:
            raise ParameterError(f"{owner}.init must be one of {INITS}, got {self.init!r}")
        require_int(owner, "init_tries", self.init_tries, 1)
        if not isinstance(self.shortcut, bool):
            raise ParameterError(f"{owner}.shortcut must be True or False, got {self.shortcut!r}")
        require_int(owner, "max_free_cells", self.max_free_cells, 1)

    @classmethod
    def paper(cls, **overrides: Any) -> GAPathParams:
        """The thesis' GA: random initial paths, 100 generations, no local search."""
        base = cls(elite=1, mutation_rate=0.2, tournament=2, max_generations=100,
                   stall_generations=None, init="random", init_tries=50, shortcut=False)
        return replace(base, **overrides)

    def config(self) -> GAConfig:
        return GAConfig(population=self.population, elite=self.elite,
                        crossover_rate=self.crossover_rate, mutation_rate=self.mutation_rate,
                        restart_on_convergence=False, tournament=self.tournament,
                        mutation_horizon=self.max_generations)


def path_is_free(world: GridWorld, path: np.ndarray) -> bool:
    """Whether every segment of ``path`` (cells) avoids every blocked cell (closed squares)."""
    blocked = world.occupancy.view(np.uint8)
    pts = np.asarray(path, dtype=np.int64)
    for (x0, y0), (x1, y1) in zip(pts[:-1], pts[1:], strict=True):
        if segment_hits(blocked, int(x0), int(y0), int(x1), int(y1), True):
            return False
    return True


def plan(world: GridWorld, start: Any, goal: Any, *, params: GAPathParams | None = None,
         seed: int = 0) -> PlanResult:
    """Plan a path with the GA.

    Returns a :class:`PlanResult` whose ``history`` is the per-generation best
    and mean cost; ``success=False`` (with the reason) when the best path still
    crosses an obstacle. ``info`` holds ``fitness`` (``F = C / length`` with
    ``C`` the straight-line distance, so 1 is the unobstructed optimum),
    ``generations``, ``seed`` and the preset's ``init``.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
    """
    params = params or GAPathParams()
    start_xy = world.check_cell("start", start)
    goal_xy = world.check_cell("goal", goal)
    name = "ga" if params.init == "visibility" else "ga-paper"
    n_free = int(np.count_nonzero(~world.occupancy))
    if n_free > params.max_free_cells:
        raise ParameterError(
            f"the GA path planner is for small grids; this one has {n_free} free cells, "
            f"more than max_free_cells={params.max_free_cells}")
    if start_xy == goal_xy:
        return PlanResult(np.array([start_xy], dtype=float), True, "ok: start is the goal", name)
    t0 = time.perf_counter()
    data = world.occupancy.astype(np.float64)
    aux = wp.make_aux(start_xy, goal_xy, penalty=params.penalty,
                      init=wp.INIT_VISIBILITY if params.init == "visibility" else wp.INIT_RANDOM,
                      init_tries=params.init_tries, shortcut=params.shortcut)
    criteria: list = [MaxGenerations(params.max_generations)]
    if params.stall_generations is not None:
        criteria.append(NoImprovement(params.stall_generations))
    out = run_ga(Kind.WAYPOINT_PATH, params.config(), data, aux, max_genes=params.max_genes,
                 seed=seed, criteria=criteria)
    runtime = time.perf_counter() - t0
    w = world.width
    path = np.stack([out.genes % w, out.genes // w], axis=1).astype(float)
    straight = float(np.hypot(goal_xy[0] - start_xy[0], goal_xy[1] - start_xy[1]))
    free = path_is_free(world, path)
    length = float(np.sum(np.hypot(*np.diff(path, axis=0).T)))
    info = {"generations": out.generations, "seed": seed, "init": params.init,
            "fitness": straight / length if free else 0.0}
    if not free:
        return PlanResult(np.zeros((0, 2)), False,
                          f"no collision-free path after {out.generations} generations "
                          f"(best still crosses obstacles)", name, runtime, out.history, info)
    return PlanResult(path, True, "ok", name, runtime, out.history, info)

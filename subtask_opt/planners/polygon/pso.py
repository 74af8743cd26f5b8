"""MAKLINK + improved Dijkstra + inertia-weight PSO (seed paper 003).

The improved-Dijkstra path crosses a sequence of free links; each crossing
point may slide along its link, so a path is one parameter in [0, 1] per
crossed link. Consecutive crossings lie on a common convex cell, so every
parameter vector is a collision-free path, and the PSO (Shi & Eberhart 1999,
``v <- w v + c1 r1 (p_i - x) + c2 r2 (p_g - x)``, ``x <- x + v``, inertia
weight falling linearly) searches that box for the shortest one. The swarm
starts with the improved path itself, so the result is never longer.

The loop runs in numba (:func:`._kernels.pso_run`, its parameters in a
:class:`._kernels.PSOConfig` named tuple) in chunks of
iterations between which the stopping criteria of :mod:`subtask_opt.base.stop` are
asked, as in the GA core: iteration-based criteria stop at the same iteration
however the run is chunked, so a seed reproduces its result.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_in_range, require_int, require_positive
from subtask_opt.base.geometry import polyline_length
from subtask_opt.base.results import History, Outcome, PlanResult
from subtask_opt.base.stop import (
    MaxGenerations,
    NoImprovement,
    Progress,
    StoppingCriterion,
    as_criteria,
    kernel_limits,
)
from subtask_opt.ga.loop import run_in_chunks
from subtask_opt.planners.base import check_seed, register
from subtask_opt.planners.polygon import _kernels as gk
from subtask_opt.planners.polygon import maklink
from subtask_opt.planners.polygon._routes import same_point
from subtask_opt.planners.polygon.world import PolygonWorld


@dataclass(frozen=True)
class PSOParams:
    """Inertia-weight PSO settings.

    Attributes:
        swarm: number of particles.
        w_start, w_end: inertia weight at the first iteration and from
            ``inertia_iterations`` on (linear in between). Shi & Eberhart use
            0.9 -> 0.4; 0.7 -> 0.4 with 40 particles never stalled short of
            the sleeve's optimum in 430 runs on ``seed003`` (0.9 did, 1 in 400).
        c1, c2: cognitive and social acceleration constants.
        v_max: largest change of a link parameter in one iteration.
        inertia_iterations: iterations over which the inertia weight falls.
    """

    swarm: int = 40
    w_start: float = 0.7
    w_end: float = 0.4
    c1: float = 2.0
    c2: float = 2.0
    v_max: float = 0.2
    inertia_iterations: int = 100

    def __post_init__(self) -> None:
        require_int("PSOParams", "swarm", self.swarm, 2)
        require_in_range("PSOParams", "w_start", self.w_start, 0.0, 2.0)
        require_in_range("PSOParams", "w_end", self.w_end, 0.0, 2.0)
        require_in_range("PSOParams", "c1", self.c1, 0.0, 4.0)
        require_in_range("PSOParams", "c2", self.c2, 0.0, 4.0)
        if self.c1 + self.c2 == 0:
            raise ParameterError("PSOParams: c1 + c2 must be > 0, got c1 = c2 = 0")
        require_positive("PSOParams", "v_max", self.v_max)
        if self.v_max > 1.0:
            raise ParameterError(f"PSOParams.v_max must be in (0, 1], got {self.v_max!r}")
        require_int("PSOParams", "inertia_iterations", self.inertia_iterations, 1)

    def kernel_config(self) -> gk.PSOConfig:
        """The kernel's view of these settings (a NamedTuple numba can cache)."""
        return gk.PSOConfig(w_start=float(self.w_start), w_end=float(self.w_end),
                            c1=float(self.c1), c2=float(self.c2), v_max=float(self.v_max),
                            inertia_iterations=float(self.inertia_iterations))


def default_stop() -> list[StoppingCriterion]:
    """200 iterations, or 50 without improvement."""
    return [MaxGenerations(200), NoImprovement(50)]


@dataclass(frozen=True)
class SwarmOutcome:
    """What :func:`optimize_crossings` found."""

    t: np.ndarray
    cost: float
    iterations: int
    history: History
    runtime_s: float


def optimize_crossings(links: np.ndarray, start: np.ndarray, goal: np.ndarray,
                       initial: np.ndarray, *, params: PSOParams | None = None, seed: int = 0,
                       stop: StoppingCriterion | list[StoppingCriterion] | None = None,
                       on_chunk: Callable[[Progress], None] | None = None) -> SwarmOutcome:
    """Minimise the length of start -> links[k] at t[k] -> goal over t in [0, 1]^k by PSO.

    ``initial`` (one t per link) is particle 0; the others start uniformly at random.
    """
    params = _check_params(params)
    criteria = as_criteria(stop, default_stop())
    rng = np.random.default_rng(check_seed(seed, owner="optimize_crossings seed"))
    links = np.ascontiguousarray(links, dtype=float).reshape(-1, 4)
    dim = len(links)
    x = rng.random((params.swarm, dim))
    x[0] = np.clip(initial, 0.0, 1.0)
    v = rng.uniform(-params.v_max, params.v_max, (params.swarm, dim))
    pbest = x.copy()
    pbest_cost = np.array([gk.crossing_path_length(p, links, start, goal) for p in x])
    i0 = int(np.argmin(pbest_cost))
    gbest = pbest[i0].copy()
    gbest_cost = np.array([pbest_cost[i0]])
    counters = np.zeros(2, dtype=np.int64)
    cfg = params.kernel_config()
    stall_limit, target = kernel_limits(criteria)

    t0 = time.perf_counter()
    hist_best: list[np.ndarray] = []
    hist_mean: list[np.ndarray] = []
    initial_best = float(gbest_cost[0])

    def run_chunk(n: int) -> int:
        hb, hm = np.empty(n), np.empty(n)
        ran = gk.pso_run(x, v, pbest, pbest_cost, gbest, gbest_cost, counters, links, start,
                         goal, cfg, rng, n, stall_limit, target, hb, hm)
        hist_best.append(hb[:ran])
        hist_mean.append(hm[:ran])
        return ran

    run_in_chunks(run_chunk, lambda: _progress(counters, gbest_cost, t0), criteria, on_chunk)
    history = History(initial_best=initial_best,
                      best_cost=np.concatenate(hist_best) if hist_best else np.zeros(0),
                      mean_cost=np.concatenate(hist_mean) if hist_mean else np.zeros(0))
    return SwarmOutcome(t=gbest, cost=float(gbest_cost[0]), iterations=int(counters[0]),
                        history=history, runtime_s=time.perf_counter() - t0)


def _progress(counters: np.ndarray, best: np.ndarray, t0: float) -> Progress:
    return Progress(generation=int(counters[0]), best_cost=float(best[0]),
                    generations_without_improvement=int(counters[0] - counters[1]),
                    runtime_s=time.perf_counter() - t0)


def _check_params(params: object) -> PSOParams:
    if params is None:
        return PSOParams()
    if not isinstance(params, PSOParams):
        raise ParameterError(f"pso params must be None or a PSOParams, got {params!r}")
    return params


@register("polygon", "pso", description="improved Dijkstra + inertia-weight PSO sliding the "
          "crossings along their links (seed paper 003)", stochastic=True, iterative=True)
def plan(world: PolygonWorld, start: Any, goal: Any, *, params: PSOParams | None = None,
         seed: int | None = None,
         stop: StoppingCriterion | list[StoppingCriterion] | None = None,
         on_chunk: Callable[[Progress], None] | None = None) -> PlanResult:
    """The paper's full pipeline: MAKLINK graph, Dijkstra, improved Dijkstra, PSO.

    Args:
        world: the polygon world (its MAKLINK graph is built once and cached).
        start, goal: free points.
        params: PSO settings.
        seed: random seed in [0, 2**63); ``None`` draws one, reported in ``info["seed"]``.
        stop: stopping criteria (default: 200 iterations or 50 without improvement).
        on_chunk: called with a :class:`~subtask_opt.base.stop.Progress` between chunks.

    Returns:
        A PlanResult (planner ``"pso"``) whose ``history`` has the best and
        mean length per iteration and whose ``info`` holds
        ``dijkstra_length``, ``improved_length``, ``links`` (crossed link
        ids), ``t`` (their parameters), ``iterations`` and ``seed``.

    Raises:
        InputDataError, UnreachableError: start or goal malformed, outside the
            bounds, inside an obstacle or on its boundary.
        ParameterError: bad ``params``, ``seed`` or ``stop``.
    """
    params = _check_params(params)
    criteria = as_criteria(stop, default_stop())
    seed = check_seed(seed, owner="pso seed")
    if seed is None:
        seed = int(np.random.SeedSequence().entropy % (1 << 63))  # type: ignore[operator]
    t0 = time.perf_counter()
    s = world.check_point("start", start)
    g = world.check_point("goal", goal)
    info: dict[str, Any] = {"seed": seed}
    if same_point(world.eps, s, g):
        info.update(dijkstra_length=0.0, improved_length=0.0, links=[], t=[], iterations=0)
        return PlanResult(path=np.array([s, g]), success=True, message="ok (start equals goal)",
                          planner="pso", runtime_s=time.perf_counter() - t0,
                          history=History(0.0, np.zeros(0), np.zeros(0)), info=info)
    graph = maklink.graph_for(world)
    d_length, route = graph.route(s, g)
    info["graph_links"] = graph.n_links
    if not math.isfinite(d_length):
        return PlanResult(path=np.zeros((0, 2)), success=False, planner="pso",
                          outcome=Outcome.NO_PATH,
                          message="no collision-free path: start and goal are separated by "
                                  "obstacles", runtime_s=time.perf_counter() - t0, info=info)
    improved = maklink.shortcut(world, np.vstack([s, graph.midpoints[route].reshape(-1, 2), g]))
    message = "ok"
    try:
        ids, t_init = maklink.crossed_links(graph, improved)
    except RuntimeError:  # numerically ambiguous crossings: start from the Dijkstra route
        ids, t_init = np.asarray(route, dtype=np.int64), np.full(len(route), 0.5)
        message = "ok (PSO started from the Dijkstra route)"
    improved_length = polyline_length(improved)
    if len(ids) == 0:  # start and goal share a cell: the straight line is optimal
        outcome = SwarmOutcome(t=np.zeros(0), cost=improved_length, iterations=0,
                               history=History(improved_length, np.zeros(0), np.zeros(0)),
                               runtime_s=0.0)
    else:
        outcome = optimize_crossings(graph.links[ids], s, g, t_init, params=params, seed=seed,
                                     stop=criteria, on_chunk=on_chunk)
    path = _straighten(world, np.vstack([s, maklink.points_on_links(graph, ids, outcome.t), g]))
    if not world.path_free(path):  # cannot happen with convex cells; guard numerical corner cases
        path, message = improved, "ok (PSO path rejected by the collision check; improved path)"
    info.update(dijkstra_length=d_length, improved_length=improved_length,
                links=[int(k) for k in ids], t=outcome.t.tolist(),
                iterations=outcome.iterations)
    return PlanResult(path=path, success=True, message=message, planner="pso",
                      runtime_s=time.perf_counter() - t0, history=outcome.history, info=info)


def _straighten(world: PolygonWorld, path: np.ndarray) -> np.ndarray:
    """Drop crossing points where the path goes (numerically) straight on.

    Crossings of links the path does not bend at are kept by the PSO at
    arbitrary precision; dropping them changes the length by < 1e-9 relative
    and leaves only the real corners.
    """
    tol = 1e-9 * max(polyline_length(path), world.eps)
    out = [path[0]]
    for i in range(1, len(path) - 1):
        a, b, c = out[-1], path[i], path[i + 1]
        detour = math.hypot(*(b - a)) + math.hypot(*(c - b)) - math.hypot(*(c - a))
        if detour > tol or not world.segment_free(a, c):
            out.append(b)
    out.append(path[-1])
    return np.array(out)

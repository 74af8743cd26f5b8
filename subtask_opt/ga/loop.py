"""The one genetic-algorithm loop of subtask_opt, and the chunk driver it shares with PSO.

A chromosome is a row of an int64 matrix plus a length, so fixed-length
permutations (the sequencing TSP) and variable-length waypoint lists (the GA
path planner) share one representation and one loop. What differs between
them are five numba operators per chromosome :class:`~subtask_opt.ga.kinds.Kind`,
resolved by :mod:`subtask_opt.ga.dispatch` (signatures there).

The loop is generational with elitism; it restarts the population (best +
fresh individuals) when it has converged, if configured to, which is the
micro-GA of Krishnakumar that the sequencing paper uses. Python drives the
kernel in chunks of generations (:func:`run_in_chunks`) and asks the stopping
criteria between chunks, because numba cannot call Python objects.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from subtask_opt._kernel_cache import compiling
from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.results import History
from subtask_opt.base.stop import (
    Progress,
    StoppingCriterion,
    kernel_limits,
)
from subtask_opt.ga import dispatch as ops
from subtask_opt.ga.config import GAConfig, LoopParams
from subtask_opt.ga.kinds import Kind, tag

# Layout of the int64 ``counters`` array (the loop's state between chunks).
_GEN, _LAST_IMPROVE, _RESTARTS, _BEST_LEN = range(4)


@dataclass(frozen=True)
class GAOutcome:
    """What the loop found: the best chromosome, its cost and how it got there."""

    genes: np.ndarray
    cost: float
    generations: int
    restarts: int
    history: History
    runtime_s: float
    seed: int
    extra: dict = field(default_factory=dict)


@njit(cache=True, inline="always")
def _pick_parent(costs, tournament, rng):
    n = costs.shape[0]
    best = rng.integers(0, n)
    for _ in range(tournament - 1):
        other = rng.integers(0, n)
        if costs[other] < costs[best]:
            best = other
    return best


@njit(cache=True, inline="always")
def _pick_pair(costs, tournament, rng):
    """Two distinct parent indices (a string never mates with itself)."""
    n = costs.shape[0]
    if tournament < 2:
        a = rng.integers(0, n)
        b = rng.integers(0, n - 1)
        if b >= a:
            b += 1
        return a, b
    a = _pick_parent(costs, tournament, rng)
    b = a
    for _ in range(16):
        b = _pick_parent(costs, tournament, rng)
        if b != a:
            return a, b
    b = rng.integers(0, n - 1)
    if b >= a:
        b += 1
    return a, b


@njit(cache=True, inline="always")
def _population_converged(costs, previous_costs, tol):
    """Costs within ``tol`` of each other, or the population stopped changing.

    The second test matters: with greedy crossover and no mutation a population
    can settle on a fixed point whose costs still differ by more than ``tol``.
    """
    lo = costs[0]
    hi = costs[0]
    for c in costs:
        lo = min(lo, c)
        hi = max(hi, c)
    if math.isfinite(hi) and hi - lo <= tol * abs(lo):
        return True
    return _same_multiset(costs, previous_costs)


@njit(cache=True, inline="always")
def _same_multiset(a, b):
    """``np.array_equal(np.sort(a), np.sort(b))`` for a small population, without
    compiling a general sort: each value occurs equally often in both."""
    for x in a:
        count = 0
        for y in a:
            count += y == x
        for y in b:
            count -= y == x
        if count != 0:
            return False
    return True


@njit(cache=True)
def _stable_argsort(costs):
    """Indices that sort ``costs``, ties by index: an insertion sort, which for the
    small populations of a GA is quick and compiles far faster than np.argsort."""
    n = costs.shape[0]
    order = np.arange(n)
    for i in range(1, n):
        k = order[i]
        j = i
        while j > 0 and costs[k] < costs[order[j - 1]]:
            order[j] = order[j - 1]
            j -= 1
        order[j] = k
    return order


@njit(cache=True)
def _reseed(kind, pop, lengths, costs, best, counters, data, aux, rng):
    """Best so far in slot 0 (once there is one) and fresh, improved individuals elsewhere."""
    best_len = counters[_BEST_LEN]
    first = 0
    if best_len > 0:
        pop[0, :best_len] = best[:best_len]
        lengths[0] = best_len
        costs[0] = ops.evaluate(kind, pop[0], best_len, data, aux)
        first = 1
    for i in range(first, pop.shape[0]):
        lengths[i] = ops.randomize(kind, pop[i], data, aux, rng, best, best_len)
        lengths[i] = ops.improve(kind, pop[i], lengths[i], data, aux)
        costs[i] = ops.evaluate(kind, pop[i], lengths[i], data, aux)


@njit(cache=True)
def evolve(kind, pop, lengths, costs, best, best_cost, counters, data, aux, params, rng,
           n_gens, stall_limit, target, hist_best, hist_mean, hist_restart):
    """Run up to ``n_gens`` generations in place; return how many ran.

    The first call (no best recorded yet) builds the initial population.
    Stops early when the best cost reaches ``target`` or when ``stall_limit``
    generations have passed without improvement. ``hist_*`` receive one entry
    per generation run (``hist_restart`` is 1 where a restart followed).
    """
    if n_gens == 0:  # a call that only compiles
        return 0
    n_pop, max_genes = pop.shape
    n_elite = params.elite
    p_cross = params.crossover_rate
    p_mut = params.mutation_rate
    restart = params.restart_on_convergence
    conv_tol = params.convergence_tol
    tournament = params.tournament
    horizon = params.mutation_horizon
    new_pop = np.empty((n_pop, max_genes), dtype=pop.dtype)
    new_lengths = np.empty(n_pop, dtype=lengths.dtype)
    new_costs = np.empty(n_pop)
    if counters[_BEST_LEN] == 0:  # first call: build the initial population
        _reseed(kind, pop, lengths, costs, best, counters, data, aux, rng)
        i_best = np.argmin(costs)
        counters[_BEST_LEN] = lengths[i_best]
        best[: lengths[i_best]] = pop[i_best, : lengths[i_best]]
        best_cost[0] = costs[i_best]
        best_cost[1] = costs[i_best]  # kept: the best of the initial population
    ran = 0
    for step in range(n_gens):
        if best_cost[0] <= target or counters[_GEN] - counters[_LAST_IMPROVE] >= stall_limit:
            break
        order = _stable_argsort(costs)
        for e in range(n_elite):
            src = order[e]
            new_pop[e, : lengths[src]] = pop[src, : lengths[src]]
            new_lengths[e] = lengths[src]
            new_costs[e] = costs[src]
        strength = min(counters[_GEN] / horizon, 1.0)
        for c in range(n_elite, n_pop):
            a, b = _pick_pair(costs, tournament, rng)
            child = new_pop[c]
            if p_cross >= 1.0 or rng.random() < p_cross:
                length = ops.crossover(kind, pop[a], lengths[a], pop[b], lengths[b], data, aux,
                                       rng, child)
            else:
                child[: lengths[a]] = pop[a, : lengths[a]]
                length = lengths[a]
            if p_mut > 0.0 and rng.random() < p_mut:
                length = ops.mutate(kind, child, length, data, aux, rng, strength)
            length = ops.improve(kind, child, length, data, aux)
            new_lengths[c] = length
            new_costs[c] = ops.evaluate(kind, child, length, data, aux)
        converged = restart and _population_converged(new_costs, costs, conv_tol)
        pop[:, :] = new_pop
        lengths[:] = new_lengths
        costs[:] = new_costs
        counters[_GEN] += 1
        i_best = np.argmin(costs)
        if costs[i_best] < best_cost[0]:
            best_cost[0] = costs[i_best]
            counters[_BEST_LEN] = lengths[i_best]
            best[: lengths[i_best]] = pop[i_best, : lengths[i_best]]
            counters[_LAST_IMPROVE] = counters[_GEN]
        hist_best[step] = best_cost[0]
        hist_mean[step] = np.mean(costs)
        hist_restart[step] = 0
        if converged:
            _reseed(kind, pop, lengths, costs, best, counters, data, aux, rng)
            counters[_RESTARTS] += 1
            hist_restart[step] = 1
        ran += 1
    return ran


def run_ga(
    kind: Kind,
    config: GAConfig,
    data: np.ndarray,
    aux: np.ndarray | tuple[object, ...],
    *,
    max_genes: int,
    seed: int,
    criteria: list[StoppingCriterion],
    on_chunk: Callable[[Progress], None] | None = None,
) -> GAOutcome:
    """Run the GA until a stopping criterion holds (see :func:`run_in_chunks`).

    The stall limit and the target cost are enforced inside the kernel, so a
    seeded run stops at the same generation however it is chunked. The kernel
    is compiled (or loaded from the cache) before the clock starts, so
    ``runtime_s`` never includes compilation.
    """
    if ops.registered(kind) is None:
        raise ParameterError(f"run_ga: no operators are registered for {kind!r}")
    require_int("run_ga", "max_genes", max_genes, 1)
    rng = np.random.default_rng(seed)
    data = np.ascontiguousarray(data, dtype=np.float64)
    if not isinstance(aux, tuple):  # a NamedTuple of parameters goes in as it is
        aux = np.ascontiguousarray(aux, dtype=np.float64)
    params: LoopParams = config.loop_params()
    pop = np.zeros((config.population, max_genes), dtype=np.int64)
    lengths = np.zeros(config.population, dtype=np.int64)
    costs = np.zeros(config.population)
    best = np.zeros(max_genes, dtype=np.int64)
    best_cost = np.zeros(2)  # [best so far, best of the initial population]
    counters = np.zeros(4, dtype=np.int64)
    stall_limit, target = kernel_limits(criteria)
    code = tag(kind)  # its type selects the kind's compiled loop
    with compiling(f"ga-{kind.name.lower()}", "the genetic algorithm"):  # before the clock
        evolve(code, pop, lengths, costs, best, best_cost, counters, data, aux, params, rng, 0,
               stall_limit, target, np.empty(0), np.empty(0), np.empty(0, dtype=np.int64))

    start = time.perf_counter()
    hist_best: list[np.ndarray] = []
    hist_mean: list[np.ndarray] = []
    hist_restart: list[np.ndarray] = []

    def run_chunk(n_gens: int) -> int:
        hb, hm, hr = np.empty(n_gens), np.empty(n_gens), np.empty(n_gens, dtype=np.int64)
        ran = evolve(code, pop, lengths, costs, best, best_cost, counters, data,
                     aux, params, rng, n_gens, stall_limit, target, hb, hm, hr)
        hist_best.append(hb[:ran])
        hist_mean.append(hm[:ran])
        hist_restart.append(hr[:ran])
        return ran

    run_in_chunks(run_chunk, lambda: _progress(counters, best_cost, start), criteria, on_chunk)
    runtime = time.perf_counter() - start

    restart_flags = np.concatenate(hist_restart) if hist_restart else np.zeros(0, np.int64)
    history = History(
        initial_best=float(best_cost[1]),
        best_cost=np.concatenate(hist_best) if hist_best else np.zeros(0),
        mean_cost=np.concatenate(hist_mean) if hist_mean else np.zeros(0),
        restarts=np.flatnonzero(restart_flags) + 1,
    )
    return GAOutcome(
        genes=best[: counters[_BEST_LEN]].copy(),
        cost=float(best_cost[0]),
        generations=int(counters[_GEN]),
        restarts=int(counters[_RESTARTS]),
        history=history,
        runtime_s=runtime,
        seed=seed,
    )


def _progress(counters: np.ndarray, best_cost: np.ndarray, start: float) -> Progress:
    return Progress(
        generation=int(counters[_GEN]),
        best_cost=float(best_cost[0]),
        generations_without_improvement=int(counters[_GEN] - counters[_LAST_IMPROVE]),
        runtime_s=time.perf_counter() - start,
    )


def run_in_chunks(run_chunk: Callable[[int], int], progress: Callable[[], Progress],
                  criteria: list[StoppingCriterion],
                  on_chunk: Callable[[Progress], None] | None = None) -> None:
    """Drive an iterative kernel until one of ``criteria`` holds.

    ``run_chunk(n)`` runs at most ``n`` iterations (it may stop early, e.g. at
    a stall limit or target it enforces itself) and returns how many ran;
    ``progress()`` describes the state between chunks. Chunks never pass a
    generation-based limit, so a seeded run is the same however it is chunked;
    they grow while fast so that time-based criteria are still checked often.
    ``on_chunk`` (a progress bar, say) is called after each chunk. The
    criteria are first asked after the first chunk, which also initialises.
    """
    chunk_cap = 64
    first = True
    while True:
        state = progress()
        if not first and any(c(state) for c in criteria):
            return
        first = False
        bounded = [b for b in (c.generations_left(state) for c in criteria) if b is not None]
        n = min(min(bounded) if bounded else chunk_cap, chunk_cap)
        t0 = time.perf_counter()
        ran = run_chunk(n)
        if time.perf_counter() - t0 < 0.05:
            chunk_cap = min(chunk_cap * 2, 1 << 20)
        if on_chunk is not None:
            on_chunk(progress())
        if ran < n or n == 0:  # the kernel met its own limit, or nothing was left to run
            return

"""The one genetic-algorithm loop of subtask_opt.

A chromosome is a row of an int64 matrix plus a length, so fixed-length
permutations (the sequencing TSP) and variable-length waypoint lists (the GA
path planner) share one representation and one loop. What differs between
them are five numba operators, registered per chromosome type in
:mod:`subtask_opt.ga.registry`, with these signatures:

``randomize(genes_out, data, aux, rng, best, best_len) -> length``
    A new individual for the initial population (``best_len == 0``) and for a
    restart (``best`` holds the best so far, which a restart may perturb).
``evaluate(genes, length, data, aux) -> cost``
    Cost to minimise (``inf`` for an infeasible individual).
``crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child) -> length``
    Writes one child into ``child``.
``mutate(genes, length, data, aux, rng, strength) -> length``
    In place; ``strength`` = generation / horizon, in [0, 1], for non-uniform
    mutation.
``improve(genes, length, data, aux) -> length``
    In-place local search (the identity for a plain GA).

``data`` (2-D float64) and ``aux`` (1-D float64) carry the problem; their
meaning belongs to the operators.

The loop is generational with elitism; it restarts the population (best +
fresh individuals) when it has converged, if configured to, which is the
micro-GA of Krishnakumar that the sequencing paper uses.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..errors import ParameterError, require_in_range, require_int, require_non_negative
from ..result import History
from ..stop import (
    Progress,
    StoppingCriterion,
    kernel_limits,
    run_in_chunks,
)
from . import registry as ops
from .registry import OperatorSet

# Layout of the float64 ``cfg`` array the kernel reads.
_CFG_ELITE, _CFG_PCROSS, _CFG_PMUT, _CFG_RESTART, _CFG_CONV_TOL, _CFG_TOURNAMENT, _CFG_HORIZON = (
    range(7))
_CFG_SIZE = 7

# Layout of the int64 ``counters`` array (the loop's state between chunks).
_GEN, _LAST_IMPROVE, _RESTARTS, _BEST_LEN = range(4)


@dataclass(frozen=True)
class GAConfig:
    """How the loop breeds.

    Attributes:
        population: number of individuals (5 for the micro-GA).
        elite: how many of the best pass unchanged to the next generation.
        crossover_rate: probability that a child comes from crossover rather
            than as a copy of its first parent.
        mutation_rate: probability that a child is mutated.
        restart_on_convergence: re-seed (best + fresh individuals) once the
            population has converged.
        convergence_tol: the population has converged when
            ``max(cost) - min(cost) <= convergence_tol * |min(cost)|``, or when
            its sorted costs are the same as in the previous generation.
        tournament: 0 picks each parent pair uniformly at random among
            distinct individuals; k >= 2 picks each parent by a k-tournament.
        mutation_horizon: generations over which non-uniform mutation shrinks
            (its ``strength`` argument is generation / horizon, capped at 1).
    """

    population: int = 5
    elite: int = 1
    crossover_rate: float = 1.0
    mutation_rate: float = 0.0
    restart_on_convergence: bool = True
    convergence_tol: float = 0.01
    tournament: int = 0
    mutation_horizon: int = 100

    def __post_init__(self) -> None:
        require_int("GAConfig", "population", self.population, 2)
        require_int("GAConfig", "elite", self.elite, 0)
        if self.elite >= self.population:
            raise ParameterError(
                f"GAConfig.elite must be < population ({self.population}), got {self.elite!r}")
        require_in_range("GAConfig", "crossover_rate", self.crossover_rate, 0.0, 1.0)
        require_in_range("GAConfig", "mutation_rate", self.mutation_rate, 0.0, 1.0)
        require_non_negative("GAConfig", "convergence_tol", self.convergence_tol)
        require_int("GAConfig", "tournament", self.tournament, 0)
        if self.tournament == 1 or self.tournament > self.population:
            raise ParameterError(
                f"GAConfig.tournament must be 0 or in [2, population], got {self.tournament!r}")
        require_int("GAConfig", "mutation_horizon", self.mutation_horizon, 1)

    def as_array(self) -> np.ndarray:
        cfg = np.zeros(_CFG_SIZE)
        cfg[_CFG_ELITE] = self.elite
        cfg[_CFG_PCROSS] = self.crossover_rate
        cfg[_CFG_PMUT] = self.mutation_rate
        cfg[_CFG_RESTART] = 1.0 if self.restart_on_convergence else 0.0
        cfg[_CFG_CONV_TOL] = self.convergence_tol
        cfg[_CFG_TOURNAMENT] = self.tournament
        cfg[_CFG_HORIZON] = self.mutation_horizon
        return cfg


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


@njit(cache=True)
def _pick_parent(costs, tournament, rng):
    n = costs.shape[0]
    best = rng.integers(0, n)
    for _ in range(tournament - 1):
        other = rng.integers(0, n)
        if costs[other] < costs[best]:
            best = other
    return best


@njit(cache=True)
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


@njit(cache=True)
def _population_converged(costs, previous_costs, tol):
    """Costs within ``tol`` of each other, or the population stopped changing.

    The second test matters: with greedy crossover and no mutation a population
    can settle on a fixed point whose costs still differ by more than ``tol``.
    """
    lo = np.min(costs)
    hi = np.max(costs)
    if math.isfinite(hi) and hi - lo <= tol * abs(lo):
        return True
    return np.array_equal(np.sort(costs), np.sort(previous_costs))


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
def evolve(kind, pop, lengths, costs, best, best_cost, counters, data, aux, cfg, rng,
           n_gens, stall_limit, target, hist_best, hist_mean, hist_restart):
    """Run up to ``n_gens`` generations in place; return how many ran.

    The first call (no best recorded yet) builds the initial population.
    Stops early when the best cost reaches ``target`` or when ``stall_limit``
    generations have passed without improvement. ``hist_*`` receive one entry
    per generation run (``hist_restart`` is 1 where a restart followed).
    """
    n_pop, max_genes = pop.shape
    n_elite = int(cfg[_CFG_ELITE])
    p_cross = cfg[_CFG_PCROSS]
    p_mut = cfg[_CFG_PMUT]
    restart = cfg[_CFG_RESTART] > 0.5
    conv_tol = cfg[_CFG_CONV_TOL]
    tournament = int(cfg[_CFG_TOURNAMENT])
    horizon = cfg[_CFG_HORIZON]
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
        order = np.argsort(costs)
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
    operators: OperatorSet,
    config: GAConfig,
    data: np.ndarray,
    aux: np.ndarray,
    *,
    max_genes: int,
    seed: int,
    criteria: list[StoppingCriterion],
    on_chunk: Callable[[Progress], None] | None = None,
) -> GAOutcome:
    """Run the GA until a stopping criterion holds (see :func:`run_in_chunks`).

    The stall limit and the target cost are enforced inside the kernel, so a
    seeded run stops at the same generation however it is chunked.
    """
    require_int("run_ga", "max_genes", max_genes, 1)
    rng = np.random.default_rng(seed)
    data = np.ascontiguousarray(data, dtype=np.float64)
    aux = np.ascontiguousarray(aux, dtype=np.float64)
    cfg = config.as_array()
    pop = np.zeros((config.population, max_genes), dtype=np.int64)
    lengths = np.zeros(config.population, dtype=np.int64)
    costs = np.zeros(config.population)
    best = np.zeros(max_genes, dtype=np.int64)
    best_cost = np.zeros(2)  # [best so far, best of the initial population]
    counters = np.zeros(4, dtype=np.int64)
    stall_limit, target = kernel_limits(criteria)

    start = time.perf_counter()
    hist_best: list[np.ndarray] = []
    hist_mean: list[np.ndarray] = []
    hist_restart: list[np.ndarray] = []

    def run_chunk(n_gens: int) -> int:
        hb, hm, hr = np.empty(n_gens), np.empty(n_gens), np.empty(n_gens, dtype=np.int64)
        ran = evolve(operators.kind, pop, lengths, costs, best, best_cost, counters, data,
                     aux, cfg, rng, n_gens, stall_limit, target, hb, hm, hr)
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

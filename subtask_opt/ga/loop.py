"""The one genetic-algorithm loop of subtask_opt, and the chunk driver it shares with PSO.

A chromosome is a row of an int64 matrix plus a length, so fixed-length
permutations (the sequencing TSP) and variable-length waypoint lists (the GA
path planner) share one representation and one loop. What differs between
them are five numba operators per chromosome :class:`~subtask_opt.ga.kinds.Kind`,
resolved by :mod:`subtask_opt.ga.dispatch` (signatures there).

The loop is generational with elitism; it restarts the population (best +
fresh individuals) when it has converged, if configured to, which is the
micro-GA of Krishnakumar that the sequencing paper uses; how parents are paired,
what "converged" means and where a permutation child starts are options
(:class:`~subtask_opt.ga.config.GAConfig`), the readings of that paper's
open choices (``benchmarks/paper_micro_ga.py``). Python drives the
kernel in chunks of generations (:func:`run_in_chunks`) and asks the stopping
criteria between chunks, because numba cannot call Python objects.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numba import njit

from subtask_opt._kernel_cache import compiling
from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.results import History
from subtask_opt.base.stop import (
    MaxRuntime,
    Progress,
    StoppingCriterion,
    kernel_limits,
)
from subtask_opt.ga import dispatch as ops
from subtask_opt.ga.config import (
    CONVERGENCE_TESTS,
    CROSSOVER_STARTS,
    PAIRINGS,
    GAConfig,
    LoopParams,
)
from subtask_opt.ga.genes import copy_run
from subtask_opt.ga.kinds import Kind, tag

# Layout of the int64 ``counters`` array (the loop's state between chunks).
_GEN, _LAST_IMPROVE, _RESTARTS, _BEST_LEN = range(4)
MAX_RUNS = 1000
"""Most independent runs one :func:`run_ga` call makes."""
CHUNK_S = 0.05
"""Seconds a chunk of generations grows towards (:func:`run_in_chunks`)."""


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
    runs: int = 1


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


@njit(cache=True, inline="always")
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


# --- readings of the sequencing paper's micro-GA (GAConfig.pairing, .convergence,
# .crossover_start, .distinct_mates): LoopParams carries the index of the choice
_PAIR_RANDOM, _PAIR_SHUFFLE = PAIRINGS.index("random"), PAIRINGS.index("shuffle")
_PAIR_REST, _PAIR_DOUBLE = PAIRINGS.index("rest"), PAIRINGS.index("double")
_CONV_COST = CONVERGENCE_TESTS.index("cost")
_CONV_ADJACENCY = CONVERGENCE_TESTS.index("adjacency")
_START_PARENT = CROSSOVER_STARTS.index("parent")
_START_FIRST = CROSSOVER_STARTS.index("first")


@njit(cache=True, inline="always")
def _same_string(pop, lengths, a, b):
    if lengths[a] != lengths[b]:
        return False
    for i in range(lengths[a]):
        if pop[a, i] != pop[b, i]:
            return False
    return True


@njit(cache=True)
def _other_mate(pop, lengths, a, b, rng):
    """A uniformly random string that differs from string ``a`` in content (``b`` when
    every string is the same as ``a``)."""
    n_other = 0
    for s in range(pop.shape[0]):
        n_other += not _same_string(pop, lengths, a, s)
    if n_other == 0:
        return b
    pick = rng.integers(0, n_other)
    for s in range(pop.shape[0]):
        if not _same_string(pop, lengths, a, s):
            if pick == 0:
                return s
            pick -= 1
    return b


@njit(cache=True, inline="always")
def _shuffled(indices, rng):
    """``indices`` in a random order (Fisher-Yates, in place) and returned."""
    for i in range(indices.shape[0] - 1, 0, -1):
        j = rng.integers(0, i + 1)
        indices[i], indices[j] = indices[j], indices[i]
    return indices


@njit(cache=True)
def _draw_mates(pairing, costs, order, n_elite, n_children, tournament, distinct, pop,
                lengths, rng, mates):
    """Parent indices of every child, ``mates[c] = (a, b)`` with ``a != b``, for the
    shuffle-based and doubled pairings (the plain random pairing draws per child)."""
    if pairing == _PAIR_SHUFFLE or pairing == _PAIR_REST:
        pool = order.copy() if pairing == _PAIR_SHUFFLE else order[n_elite:].copy()
        m = pool.shape[0]
        for c in range(n_children):
            if c % m == 0:  # a fresh random arrangement for every round of the pool
                _shuffled(pool, rng)
            a = pool[c % m]
            b = pool[(c + 1) % m] if m > 1 else order[0]
            if distinct and m > 2 and _same_string(pop, lengths, a, b):
                for k in range(2, m):  # the next string of the arrangement that differs
                    other = pool[(c + k) % m]
                    if not _same_string(pop, lengths, a, other):
                        b = other
                        break
            mates[c, 0] = a
            mates[c, 1] = b
        return
    for c in range(n_children):
        a, b = _pick_pair(costs, tournament, rng)
        if distinct and _same_string(pop, lengths, a, b):
            b = _other_mate(pop, lengths, a, b, rng)
        mates[c, 0] = a
        mates[c, 1] = b
    return


@njit(cache=True, inline="always")
def _rotate_to(genes, length, city, out):
    """The closed tour ``genes[:length]`` written into ``out`` starting at ``city``."""
    start = 0
    for i in range(length):
        if genes[i] == city:
            start = i
            break
    for i in range(length):
        out[i] = genes[(start + i) % length]


@njit(cache=True, inline="always")
def _edges_converged(pop, lengths, costs, tol, directed):
    """At most ``tol`` of the other strings' edges are not in the best string
    (closed tours over 0..n-1); ``directed`` compares successor entries, the
    adjacency strings of the sequencing paper, so a reversed tour differs."""
    n_pop = pop.shape[0]
    i_best = np.argmin(costs)
    n = lengths[i_best]
    succ_best = np.empty(n, dtype=np.int64)
    pred_best = np.empty(n, dtype=np.int64)
    for i in range(n):
        succ_best[pop[i_best, i]] = pop[i_best, (i + 1) % n]
        pred_best[pop[i_best, (i + 1) % n]] = pop[i_best, i]
    differ = 0
    for s in range(n_pop):
        if s == i_best:
            continue
        for i in range(n):
            u = pop[s, i]
            v = pop[s, (i + 1) % n]
            if directed:
                differ += succ_best[u] != v
            else:
                differ += succ_best[u] != v and pred_best[u] != v
    return differ <= tol * (n_pop - 1) * n


IMPROVEMENT_RTOL = 1e-9
"""A new best cost restarts the stall count only when it is this share below the old one
(the tolerance of :meth:`~subtask_opt.base.results.History.generation_of_best`): a tour
rotated or reversed sums its legs in another order, a few ulps apart."""


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
    pairing = params.pairing
    convergence = params.convergence
    start_rule = params.crossover_start
    distinct = params.distinct_mates
    n_kids = (n_pop - n_elite) * (2 if pairing == _PAIR_DOUBLE else 1)
    mates = np.empty((n_kids, 2), dtype=np.int64)
    kids = np.empty((n_kids if pairing == _PAIR_DOUBLE else 0, max_genes), dtype=pop.dtype)
    kid_lengths = np.empty(n_kids, dtype=lengths.dtype)
    kid_costs = np.empty(n_kids)
    rot_a = np.empty(max_genes, dtype=pop.dtype)
    rot_b = np.empty(max_genes, dtype=pop.dtype)
    # The initial population (first call) and every restart (after a generation that
    # converged) are built here, in one block of the loop itself: a helper kernel between
    # the loop and the restart operators would compile their code once more (CONTRIBUTING,
    # the cold start).
    initial = counters[_BEST_LEN] == 0
    reseed = initial
    ran = 0
    step = 0
    while True:
        if reseed:
            best_len = counters[_BEST_LEN]
            first = 0
            if best_len > 0:  # the best so far stays, in slot 0
                copy_run(pop[0], 0, best, 0, best_len)
                lengths[0] = best_len
                costs[0] = ops.evaluate(kind, pop[0], best_len, data, aux)
                first = 1
            for i in range(first, n_pop):
                lengths[i] = ops.randomize(kind, pop[i], data, aux, rng, best, best_len)
                lengths[i] = ops.improve(kind, pop[i], lengths[i], data, aux)
                costs[i] = ops.evaluate(kind, pop[i], lengths[i], data, aux)
            if initial:
                i_best = np.argmin(costs)
                counters[_BEST_LEN] = lengths[i_best]
                copy_run(best, 0, pop[i_best], 0, lengths[i_best])
                best_cost[0] = costs[i_best]
                best_cost[1] = costs[i_best]  # kept: the best of the initial population
                initial = False
            else:
                counters[_RESTARTS] += 1
                hist_restart[step - 1] = 1
            reseed = False
        if step >= n_gens or best_cost[0] <= target or (
                counters[_GEN] - counters[_LAST_IMPROVE] >= stall_limit):
            break
        order = _stable_argsort(costs)
        for e in range(n_elite):
            src = order[e]
            copy_run(new_pop[e], 0, pop[src], 0, lengths[src])
            new_lengths[e] = lengths[src]
            new_costs[e] = costs[src]
        strength = min(counters[_GEN] / horizon, 1.0)
        if pairing != _PAIR_RANDOM:
            _draw_mates(pairing, costs, order, n_elite, n_kids, tournament, distinct, pop,
                        lengths, rng, mates)
        for c in range(n_kids):
            if pairing == _PAIR_RANDOM:
                a, b = _pick_pair(costs, tournament, rng)
                if distinct and _same_string(pop, lengths, a, b):
                    b = _other_mate(pop, lengths, a, b, rng)
            else:
                a, b = mates[c, 0], mates[c, 1]
            child = new_pop[n_elite + c] if pairing != _PAIR_DOUBLE else kids[c]
            parent_a = pop[a]
            parent_b = pop[b]
            if start_rule != _START_PARENT:  # closed tours: rotate both to one start city
                city = 0 if start_rule == _START_FIRST else rng.integers(0, lengths[a])
                _rotate_to(pop[a], lengths[a], city, rot_a)
                _rotate_to(pop[b], lengths[b], city, rot_b)
                parent_a = rot_a
                parent_b = rot_b
            if p_cross >= 1.0 or rng.random() < p_cross:
                length = ops.crossover(kind, parent_a, lengths[a], parent_b, lengths[b], data,
                                       aux, rng, child)
            else:
                copy_run(child, 0, pop[a], 0, lengths[a])
                length = lengths[a]
            if p_mut > 0.0 and rng.random() < p_mut:
                length = ops.mutate(kind, child, length, data, aux, rng, strength)
            length = ops.improve(kind, child, length, data, aux)
            if pairing == _PAIR_DOUBLE:
                kid_lengths[c] = length
                kid_costs[c] = ops.evaluate(kind, child, length, data, aux)
            else:
                new_lengths[n_elite + c] = length
                new_costs[n_elite + c] = ops.evaluate(kind, child, length, data, aux)
        if pairing == _PAIR_DOUBLE:  # the better half of the children survives
            kept = _stable_argsort(kid_costs)
            for c in range(n_pop - n_elite):
                k = kept[c]
                copy_run(new_pop[n_elite + c], 0, kids[k], 0, kid_lengths[k])
                new_lengths[n_elite + c] = kid_lengths[k]
                new_costs[n_elite + c] = kid_costs[k]
        if not restart:
            converged = False
        elif convergence != _CONV_COST:
            # a population that stopped changing has converged too (see the cost test)
            converged = _edges_converged(new_pop, new_lengths, new_costs, conv_tol,
                                         convergence == _CONV_ADJACENCY) or _same_multiset(
                                             new_costs, costs)
        else:
            converged = _population_converged(new_costs, costs, conv_tol)
        for i in range(pop.shape[0]):
            copy_run(pop[i], 0, new_pop[i], 0, pop.shape[1])
        copy_run(lengths, 0, new_lengths, 0, lengths.shape[0])
        copy_run(costs, 0, new_costs, 0, costs.shape[0])
        counters[_GEN] += 1
        i_best = np.argmin(costs)
        if costs[i_best] < best_cost[0]:
            # a stall counts generations without a real improvement: the same tour summed
            # from another start can come out an ulp shorter (IMPROVEMENT_RTOL)
            if costs[i_best] < best_cost[0] - IMPROVEMENT_RTOL * abs(best_cost[0]):
                counters[_LAST_IMPROVE] = counters[_GEN]
            best_cost[0] = costs[i_best]
            counters[_BEST_LEN] = lengths[i_best]
            copy_run(best, 0, pop[i_best], 0, lengths[i_best])
        hist_best[step] = best_cost[0]
        hist_mean[step] = np.mean(costs)
        hist_restart[step] = 0
        reseed = converged
        ran += 1
        step += 1
    return ran


@njit(cache=True)
def evaluate_rows(kind, pop, lengths, costs, best, best_cost, counters, data, aux):
    """Every individual's cost and the best's again (``data`` changed in place between
    generations); the best becomes the cheapest of them (:func:`run_ga`'s ``on_best``).
    Nothing before the first population (the compiling call)."""
    if counters[_BEST_LEN] == 0:
        return
    for i in range(pop.shape[0]):
        costs[i] = ops.evaluate(kind, pop[i], lengths[i], data, aux)
    best_cost[0] = ops.evaluate(kind, best, counters[_BEST_LEN], data, aux)
    i_best = np.argmin(costs)
    if costs[i_best] < best_cost[0]:
        best_cost[0] = costs[i_best]
        counters[_BEST_LEN] = lengths[i_best]
        copy_run(best, 0, pop[i_best], 0, lengths[i_best])


MAX_BEST_CHECKS = 10_000
"""Most times :func:`run_ga` shows ``on_best`` a best after one generation (each call that
changes costs may make another individual the best)."""


def compiled_entry(kernel: Any, args: tuple[Any, ...]) -> Any:
    """The machine-code entry point ``kernel`` was compiled to for arguments typed as
    ``args`` (call it once with them first), or ``kernel`` itself when there is none
    (``NUMBA_DISABLE_JIT``). Calling the entry point skips numba's dispatch, which
    derives the type of every ``NamedTuple`` argument again in Python on every call:
    about 50 us per call of :func:`evolve` on an idle machine, where the kernel
    itself may run a whole 30-node generation in 80 us. Later calls must pass
    arguments of the same types (the arrays' dtypes, dimensions and layouts)."""
    try:
        types = tuple(kernel.typeof_pyval(a) for a in args)
        return kernel.overloads[types].entry_point
    except (AttributeError, KeyError):
        return kernel


def _types_key(kernel: Any, args: tuple[Any, ...]) -> str:
    """A short name of the numba types of ``args`` ("" when the kernels run as Python)."""
    try:
        text = ",".join(str(kernel.typeof_pyval(a)) for a in args)
    except AttributeError:
        return ""
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def run_ga(
    kind: Kind,
    config: GAConfig,
    data: np.ndarray | tuple[object, ...],
    aux: Any,
    *,
    max_genes: int,
    seed: int,
    criteria: list[StoppingCriterion],
    on_chunk: Callable[[Progress], None] | None = None,
    runs: int = 1,
    on_best: Callable[[np.ndarray], bool] | None = None,
) -> GAOutcome:
    """Run the GA until a stopping criterion holds (see :func:`run_in_chunks`).

    The stall limit and the target cost are enforced inside the kernel, so a
    seeded run stops at the same generation however it is chunked. The kernel
    is compiled (or loaded from the cache) before the clock starts, so
    ``runtime_s`` never includes compilation.

    ``runs`` independent runs (the first from ``seed``, run r from the seed
    sequence ``[seed, r]``), each from a fresh population until the criteria
    hold; the best answer is kept. Generation-based criteria apply to each run;
    a :class:`~subtask_opt.base.stop.MaxRuntime` budget and a reached target
    end them all. The history runs on through the runs (a new run counts as a
    restart), and so do ``generations`` and ``restarts``; ``GAOutcome.runs`` is how
    many ran.

    ``on_best(genes)`` (a lazy cost check) is shown every new best chromosome, after each
    generation (the GA then runs one generation per kernel call, so a seeded run does not
    depend on the machine's speed). It returns True when it changed costs in ``data`` in
    place (say, a leg of that tour found blocked): the population and the best are then
    evaluated again (:func:`evaluate_rows`) and the best, which may be another individual
    now, is shown in turn, until it returns False. The kept best of several runs is
    compared on the costs of its own run.
    """
    if ops.registered(kind) is None:
        raise ParameterError(f"run_ga: no operators are registered for {kind!r}")
    require_int("run_ga", "max_genes", max_genes, 1)
    require_int("run_ga", "runs", runs, 1, MAX_RUNS)
    rng = np.random.default_rng(seed)
    # a kind's data and parameters may also be NamedTuples of arrays
    if isinstance(data, np.ndarray):
        data = np.ascontiguousarray(data, dtype=np.float64)
    if isinstance(aux, np.ndarray):
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
    probe = (code, pop, lengths, costs, best, best_cost, counters, data, aux, params, rng, 0,
             stall_limit, target, np.empty(0), np.empty(0), np.empty(0, dtype=np.int64))
    # the loop compiles once per kind and data/aux types: one compile group (and lock) each
    with compiling(f"ga-{kind.name.lower()}-{_types_key(evolve, (data, aux))}",
                   "the genetic algorithm"):  # before the clock
        evolve(*probe)
        if on_best is not None:
            evaluate_rows(code, pop, lengths, costs, best, best_cost, counters, data, aux)
    kernel = compiled_entry(evolve, probe)
    shown = [math.inf]  # the cost of the last best on_best accepted

    def show_best() -> None:
        assert on_best is not None
        if best_cost[0] >= shown[0]:
            return
        for _ in range(MAX_BEST_CHECKS):
            if not on_best(best[:counters[_BEST_LEN]].copy()):
                break
            evaluate_rows(code, pop, lengths, costs, best, best_cost, counters, data, aux)
        shown[0] = best_cost[0]

    start = time.perf_counter()
    hist_best: list[np.ndarray] = []
    hist_mean: list[np.ndarray] = []
    hist_restart: list[np.ndarray] = []

    def run_chunk(n_gens: int) -> int:
        hb, hm, hr = np.empty(n_gens), np.empty(n_gens), np.empty(n_gens, dtype=np.int64)
        if on_best is None:
            ran = kernel(code, pop, lengths, costs, best, best_cost, counters, data,
                         aux, params, rng, n_gens, stall_limit, target, hb, hm, hr)
        else:  # one generation at a time, each new best shown
            ran = 0
            while ran < n_gens:
                step = kernel(code, pop, lengths, costs, best, best_cost, counters, data,
                              aux, params, rng, 1, stall_limit, target, hb[ran:], hm[ran:],
                              hr[ran:])
                show_best()
                if step == 0:
                    break
                ran += step
        hist_best.append(hb[:ran])
        hist_mean.append(hm[:ran])
        hist_restart.append(hr[:ran])
        return ran

    kept = np.zeros(max_genes, dtype=np.int64)  # the best of the runs so far
    kept_len, kept_cost, initial_best = 0, math.inf, math.inf
    generations = restarts = 0
    run_starts = []  # generations before each run after the first

    def report(p: Progress) -> None:  # progress counted through the runs
        if on_chunk is not None:
            on_chunk(replace(p, generation=generations + p.generation))

    for run in range(runs):
        if run > 0:
            if kept_cost <= target or any(isinstance(c, MaxRuntime) and c(_progress(
                    counters, best_cost, start)) for c in criteria):
                break
            rng = np.random.default_rng([seed, run])
            counters[:] = 0  # a fresh population: the kernel initialises it
            shown[0] = math.inf
            run_starts.append(generations)
        run_in_chunks(run_chunk, lambda: _progress(counters, best_cost, start), criteria,
                      report)
        if run == 0:
            initial_best = float(best_cost[1])
        generations += int(counters[_GEN])
        restarts += int(counters[_RESTARTS])
        if best_cost[0] < kept_cost:
            kept_cost, kept_len = float(best_cost[0]), int(counters[_BEST_LEN])
            kept[:kept_len] = best[:kept_len]
    runtime = time.perf_counter() - start

    restart_flags = np.concatenate(hist_restart) if hist_restart else np.zeros(0, np.int64)
    for g in run_starts:  # a new run re-seeds the population after generation g
        if g > 0 and not restart_flags[g - 1]:  # (unless the last one just had)
            restart_flags[g - 1] = 1
            restarts += 1
    history = History(
        initial_best=initial_best,
        best_cost=np.minimum.accumulate(np.concatenate(hist_best)) if hist_best else np.zeros(0),
        mean_cost=np.concatenate(hist_mean) if hist_mean else np.zeros(0),
        restarts=np.flatnonzero(restart_flags) + 1,
    )
    return GAOutcome(
        genes=kept[:kept_len].copy(),
        cost=kept_cost,
        generations=generations,
        restarts=restarts,
        history=history,
        runtime_s=runtime,
        seed=seed,
        runs=len(run_starts) + 1,
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
    they start at one generation and, while a chunk takes under :data:`CHUNK_S`, grow
    towards a chunk of that length at the rate measured (at most 64x at once, at
    least 2x), so time-based criteria are checked often even when a generation is
    slow, and a quick run takes a few calls rather than one per doubling (each call
    costs tens of microseconds in numba's dispatch: a 30-node solve of 20 generations
    made five of them, now two).
    ``on_chunk`` (a progress bar, say) is called after each chunk. The
    criteria are first asked after the first chunk, which also initialises.
    """
    chunk_cap = 1
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
        elapsed = time.perf_counter() - t0
        if elapsed < CHUNK_S:
            growth = min(64.0, CHUNK_S / max(elapsed, 1e-9))
            chunk_cap = min(max(2 * chunk_cap, int(chunk_cap * growth)), 1 << 20)
        if on_chunk is not None:
            on_chunk(progress())
        if ran < n or n == 0:  # the kernel met its own limit, or nothing was left to run
            return

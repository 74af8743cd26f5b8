"""Permutation chromosomes for the travelling-salesman problem of sequencing.

``data`` is the N x N travel-time matrix (any, not necessarily symmetric);
a chromosome is a closed tour, a permutation of 0..N-1. ``aux[0]`` selects the
greedy-crossover fallback when both parents' next cities are already used:
0 picks an unvisited city at random (the paper), 1 the nearest one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .core import Operators

FALLBACK_RANDOM = 0.0
FALLBACK_NEAREST = 1.0


@njit(cache=True)
def tour_cost(genes, length, data, aux):
    """Cost of the closed tour genes[0] -> ... -> genes[length-1] -> genes[0]."""
    total = 0.0
    for i in range(length - 1):
        total += data[genes[i], genes[i + 1]]
    total += data[genes[length - 1], genes[0]]
    return total


@njit(cache=True)
def random_tour(genes, data, aux, rng, best, best_len):
    """A uniformly random permutation (initial population and paper restarts)."""
    n = data.shape[0]
    perm = rng.permutation(n)
    for i in range(n):
        genes[i] = perm[i]
    return n


@njit(cache=True)
def nearest_neighbour_tour(genes, data, rng):
    """Nearest-neighbour tour from a random first city."""
    n = data.shape[0]
    used = np.zeros(n, dtype=np.bool_)
    current = rng.integers(0, n)
    genes[0] = current
    used[current] = True
    for k in range(1, n):
        nxt = -1
        best_d = np.inf
        for c in range(n):
            if not used[c] and data[current, c] < best_d:
                best_d = data[current, c]
                nxt = c
        genes[k] = nxt
        used[nxt] = True
        current = nxt
    return n


@njit(cache=True)
def kicked_best(genes, data, aux, rng, best, best_len):
    """A double-bridge kick of the best tour (a nearest-neighbour tour before any best).

    The kick moves three random segments, a change that 2-opt and Or-opt cannot
    undo in one step, so a restart explores a new basin near a good tour.
    """
    n = data.shape[0]
    if best_len == 0:
        return nearest_neighbour_tour(genes, data, rng)
    if n < 8:
        return random_tour(genes, data, aux, rng, best, best_len)
    # three distinct cut points in 1..n-1, sorted
    p1 = rng.integers(1, n - 2)
    p2 = rng.integers(p1 + 1, n - 1)
    p3 = rng.integers(p2 + 1, n)
    k = 0
    for i in range(0, p1):
        genes[k] = best[i]
        k += 1
    for i in range(p2, p3):
        genes[k] = best[i]
        k += 1
    for i in range(p1, p2):
        genes[k] = best[i]
        k += 1
    for i in range(p3, n):
        genes[k] = best[i]
        k += 1
    return n


@njit(cache=True)
def greedy_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """Greedy crossover: one child that follows the shorter parental edge.

    Start at the first city of a randomly chosen parent; from the current city
    take the cheaper of the two edges to its successors in the parents; if one
    successor is already in the child take the other; if both are, take an
    unvisited city, at random or the nearest (``aux[0]``).
    """
    n = len_a
    succ_a = np.empty(n, dtype=np.int64)
    succ_b = np.empty(n, dtype=np.int64)
    for i in range(n):
        succ_a[genes_a[i]] = genes_a[(i + 1) % n]
        succ_b[genes_b[i]] = genes_b[(i + 1) % n]
    used = np.zeros(n, dtype=np.bool_)
    current = genes_a[0] if rng.random() < 0.5 else genes_b[0]
    child[0] = current
    used[current] = True
    nearest = aux[0] > 0.5
    for k in range(1, n):
        na = succ_a[current]
        nb = succ_b[current]
        if not used[na] and not used[nb]:
            nxt = na if data[current, na] <= data[current, nb] else nb
        elif not used[na]:
            nxt = na
        elif not used[nb]:
            nxt = nb
        elif nearest:
            nxt = -1
            best_d = np.inf
            for c in range(n):
                if not used[c] and data[current, c] < best_d:
                    best_d = data[current, c]
                    nxt = c
        else:
            pick = rng.integers(0, n - k)
            nxt = -1
            for c in range(n):
                if not used[c]:
                    if pick == 0:
                        nxt = c
                        break
                    pick -= 1
        child[k] = nxt
        used[nxt] = True
        current = nxt
    return n


@njit(cache=True)
def no_mutation(genes, length, data, aux, rng, strength):
    return length


@njit(cache=True)
def no_improvement(genes, length, data, aux):
    return length


@njit(cache=True)
def _prefix_costs(tour, n, data, fwd, bwd):
    """fwd[i] = cost of tour[0] -> ... -> tour[i]; bwd the same path walked backwards."""
    fwd[0] = 0.0
    bwd[0] = 0.0
    for i in range(1, n):
        fwd[i] = fwd[i - 1] + data[tour[i - 1], tour[i]]
        bwd[i] = bwd[i - 1] + data[tour[i], tour[i - 1]]


@njit(cache=True)
def _two_opt_pass(tour, n, data, fwd, bwd):
    """One sweep of first-improvement 2-opt, exact for asymmetric costs.

    After a move the sweep goes on from the same position (prefix costs
    refreshed) rather than starting over. True if anything moved.
    """
    eps = 1e-12
    moved = False
    for i in range(n - 2):
        j = i + 2
        while j < (n if i > 0 else n - 1):
            a, b = tour[i], tour[i + 1]
            c, d = tour[j], tour[(j + 1) % n]
            # reverse tour[i+1 .. j]
            old = data[a, b] + data[c, d] + (fwd[j] - fwd[i + 1])
            new = data[a, c] + data[b, d] + (bwd[j] - bwd[i + 1])
            if new < old - eps:
                lo, hi = i + 1, j
                while lo < hi:
                    tour[lo], tour[hi] = tour[hi], tour[lo]
                    lo += 1
                    hi -= 1
                _prefix_costs(tour, n, data, fwd, bwd)
                moved = True
            j += 1
    return moved


@njit(cache=True)
def _or_opt_pass(tour, n, data, fwd, bwd, scratch):
    """First-improvement Or-opt: move a run of 1-3 cities elsewhere, either way round."""
    eps = 1e-12
    for seg in range(1, 4):
        if seg > n - 3:
            break
        for i in range(n):
            # the run is tour[i .. i+seg-1] (indices mod n); p before it, q after it
            p = tour[(i - 1) % n]
            s0 = tour[i]
            s1 = tour[(i + seg - 1) % n]
            q = tour[(i + seg) % n]
            if i + seg <= n:
                inner_f = fwd[i + seg - 1] - fwd[i]
                inner_b = bwd[i + seg - 1] - bwd[i]
            else:  # the run wraps round the end of the array; sum it directly
                inner_f = 0.0
                inner_b = 0.0
                for k in range(seg - 1):
                    u = tour[(i + k) % n]
                    v = tour[(i + k + 1) % n]
                    inner_f += data[u, v]
                    inner_b += data[v, u]
            removed = data[p, s0] + data[s1, q] - data[p, q]
            for k in range(n - seg - 1):
                # insert between x and y, the k-th edge after q
                x = tour[(i + seg + k) % n]
                y = tour[(i + seg + k + 1) % n]
                base = removed + data[x, y]
                gain_f = base - data[x, s0] - data[s1, y]
                gain_r = base - data[x, s1] - data[s0, y] - (inner_b - inner_f)
                if gain_f > eps or gain_r > eps:
                    reverse = gain_r > gain_f
                    # rebuild: the cities after the run up to x, then the run, then the rest
                    m = 0
                    for t in range(k + 1):
                        scratch[m] = tour[(i + seg + t) % n]
                        m += 1
                    for t in range(seg):
                        scratch[m] = tour[(i + (seg - 1 - t if reverse else t)) % n]
                        m += 1
                    for t in range(k + 1, n - seg):
                        scratch[m] = tour[(i + seg + t) % n]
                        m += 1
                    tour[:n] = scratch[:n]
                    return True
    return False


@njit(cache=True)
def local_search(genes, length, data, aux):
    """2-opt and Or-opt to a local optimum (costs may be asymmetric)."""
    n = length
    if n < 4:
        return n
    fwd = np.empty(n)
    bwd = np.empty(n)
    scratch = np.empty(n, dtype=genes.dtype)
    while True:
        _prefix_costs(genes, n, data, fwd, bwd)
        if _two_opt_pass(genes, n, data, fwd, bwd):
            continue
        if _or_opt_pass(genes, n, data, fwd, bwd, scratch):
            continue
        return n


PAPER_OPERATORS = Operators(
    randomize=random_tour,
    evaluate=tour_cost,
    crossover=greedy_crossover,
    mutate=no_mutation,
    improve=no_improvement,
)
"""The paper's micro-GA: random restarts, greedy crossover, nothing else."""

MEMETIC_OPERATORS = Operators(
    randomize=kicked_best,
    evaluate=tour_cost,
    crossover=greedy_crossover,
    mutate=no_mutation,
    improve=local_search,
)
"""Our default: greedy crossover + 2-opt/Or-opt polish, restarts kick the best tour."""

"""Tours with a configuration per subtask: the generalised TSP of elbow branches.

Each subtask can be visited in one of two configurations (elbow-down 0,
elbow-up 1); the time of a leg depends on both ends' configurations. A
chromosome is still a permutation (the order); its configurations are not
genes but are *decoded* exactly: for a fixed cyclic order, the best choice of
one configuration per subtask is a shortest path through a 2-state-per-step
chain, solved by dynamic programming in O(8 N) for each of the two
configurations of the first subtask.

``data`` is (N, 5 N) float64:

* ``data[:, :N]`` - the cheapest time of each leg over its four configuration
  pairs, which the permutation operators of :mod:`subtask_opt.ga.permutation`
  (greedy crossover, nearest-neighbour construction) use as their distances;
* ``data[i, N + (2 ci + cj) N + j]`` - the time from subtask i in configuration
  ci to subtask j in configuration cj (a large finite penalty where that is
  impossible).

``aux`` is the permutation ``aux`` (:func:`subtask_opt.ga.permutation.make_aux`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from subtask_opt.ga import permutation as tsp
from subtask_opt.ga.dispatch import OperatorSet, register
from subtask_opt.ga.kinds import Kind


@njit(cache=True)
def leg(data, i, ci, j, cj):
    """Time from subtask i in configuration ci to subtask j in configuration cj."""
    n = data.shape[0]
    return data[i, n + (2 * ci + cj) * n + j]


@njit(cache=True)
def decode(genes, length, data, configs):
    """Best configurations for the cyclic order ``genes[:length]``; returns the tour time.

    ``configs`` (indexed by subtask) receives the chosen configurations.
    """
    n = length
    pred = np.zeros((n, 2), dtype=np.int64)
    best_total = np.inf
    for c0 in range(2):
        cost0 = 0.0 if c0 == 0 else np.inf
        cost1 = 0.0 if c0 == 1 else np.inf
        for k in range(1, n):
            a = genes[k - 1]
            b = genes[k]
            # from configuration 0 or 1 of a into configuration 0 and 1 of b
            a00 = cost0 + leg(data, a, 0, b, 0)
            a10 = cost1 + leg(data, a, 1, b, 0)
            a01 = cost0 + leg(data, a, 0, b, 1)
            a11 = cost1 + leg(data, a, 1, b, 1)
            pred[k, 0] = 0 if a00 <= a10 else 1
            pred[k, 1] = 0 if a01 <= a11 else 1
            cost0 = min(a00, a10)
            cost1 = min(a01, a11)
        last = genes[n - 1]
        tot0 = cost0 + leg(data, last, 0, genes[0], c0)
        tot1 = cost1 + leg(data, last, 1, genes[0], c0)
        c_last = 0 if tot0 <= tot1 else 1
        total = min(tot0, tot1)
        if total < best_total:
            best_total = total
            c = c_last
            for k in range(n - 1, 0, -1):
                configs[genes[k]] = c
                c = pred[k, c]
            configs[genes[0]] = c0
    return best_total


@njit(cache=True)
def tour_cost(genes, length, data, aux):
    """Tour time with the best configurations (the ``evaluate`` operator)."""
    configs = np.empty(data.shape[0], dtype=np.int64)
    return decode(genes, length, data, configs)


@njit(cache=True)
def induced_matrix(data, configs):
    """(N, N) leg times for fixed configurations."""
    n = data.shape[0]
    out = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            out[i, j] = leg(data, i, configs[i], j, configs[j])
    return out


@njit(cache=True)
def local_search(genes, length, data, aux):
    """Alternate exact decoding and 2-opt/Or-opt on the decoded configurations.

    Each round fixes the configurations the decoder chose, improves the order
    on that (N, N) matrix to a local optimum, and decodes again; the tour time
    never increases, and the loop ends when a round gains nothing.
    """
    n = length
    configs = np.empty(data.shape[0], dtype=np.int64)
    cost = decode(genes, n, data, configs)
    for _ in range(100):  # bounded; a round that gains nothing ends it earlier
        fixed = induced_matrix(data, configs)
        tsp.exact_local_search(genes, n, fixed, aux)
        new_cost = decode(genes, n, data, configs)
        if new_cost >= cost - 1e-12 * max(1.0, abs(cost)):
            break
        cost = new_cost
    return n


@njit(cache=True)
def randomize(genes, data, aux, rng, best, best_len):
    """Random tours for the paper's search, kicks of the best otherwise."""
    if aux[tsp.AUX_SEARCH] == tsp.SEARCH_PAPER:
        return tsp.random_tour(genes, data, aux, rng, best, best_len)
    return tsp.kicked_best(genes, data, aux, rng, best, best_len)


@njit(cache=True)
def improve(genes, length, data, aux):
    """Alternating decoding and local search, except for the paper's search."""
    if aux[tsp.AUX_SEARCH] == tsp.SEARCH_PAPER:
        return length
    return local_search(genes, length, data, aux)


register(Kind.CONFIGURED_PERMUTATION,
         OperatorSet(randomize, tour_cost, tsp.greedy_crossover, tsp.no_mutation, improve))

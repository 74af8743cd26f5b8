"""Pinned clustered permutations: precedence and pins with one node of every cluster
chosen exactly during the search (a GA chromosome kind: the precedence-constrained
generalised TSP, PCGTSP).

The chromosome is the canonical pinned permutation of :mod:`subtask_opt.tour.precedence`
(first node pinned, maybe the last, precedence pairs ``a`` before ``b``), and every
operator keeps it feasible; its cost is that order at its best nodes (configurations,
vertices), the layered shortest path of :func:`subtask_opt.tour.clustered.decode`. So
order and nodes are searched together, where the pinned kind alone searches the order on
the cheapest costs between clusters and leaves the nodes to a decode afterwards.

* Construction, crossover and restart kicks are the pinned kind's (on the cheapest costs
  between clusters, ``data.dist``), each followed by :func:`local_search`.
* :func:`local_search` alternates the exact decode, the pinned kind's 2-opt / Or-opt /
  exchange search on the costs at the decoded nodes, and node-choosing relocations: every
  cluster taken out and put back at its cheapest place and node among the places its
  precedence allows (GLNS's unified insertion), until a round gains nothing.
* ``data.lns > 0`` (the GTSPLIB sets): annealed large-neighbourhood steps after GLNS
  (remove 1 to a quarter of the movable clusters at random, as a segment or the most
  expensive; insert each back at its cheapest feasible place and node; polish).

Why the insertions always find a place: the precedence lists (``aux``) hold the
transitive closure of the pairs (:func:`make_pinned_clustered_aux`), so in a partial tour
that keeps every pair among its clusters, all predecessors of a missing cluster come
before all its successors.

``data`` is a :class:`PinnedClusteredData`: the canonical nodes' cheapest costs, the
:class:`~subtask_opt.tour.clustered.ConfiguredData` of the clusters, and, for a serial arm,
the home (the canonical node that is no cluster: its legs are the layers' ``home_out`` and
``home_in``; it is the pinned first node).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.ga.dispatch import OperatorSet
from subtask_opt.tour import clustered as _gc
from subtask_opt.tour import precedence as _pc
from subtask_opt.tour.clustered import (
    LNS_POLISH_SLACK,
    LNS_REMOVE_SHARE,
    LNS_TEMPERATURE,
    ConfiguredData,
)
from subtask_opt.tour.precedence import PinnedAux, make_pinned_aux


class PinnedClusteredData(NamedTuple):
    """What the pinned clustered operators read (the GA's ``data``).

    Attributes:
        dist: (n, n) cheapest cost between the canonical nodes (over their node pairs;
            the home's row and column its cheapest legs): the constructions' costs.
        layers: the clusters' nodes and legs (:class:`ConfiguredData`); with a home,
            ``home_out``/``home_in`` hold its legs and the clusters are nodes 0..n-2.
        home: the canonical node that is the home (n - 1, pinned first), or -1.
        lns: large-neighbourhood steps every restart individual and child gets (0: none).
    """

    dist: np.ndarray
    layers: ConfiguredData
    home: int
    lns: int


def precedence_closure(n: int, pairs: np.ndarray) -> np.ndarray:
    """(P', 2) int64: every pair ``a`` before ``b`` the ``pairs`` imply (transitively),
    over the nodes that appear in a pair (acyclic pairs; Warshall on those nodes)."""
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if p.shape[0] == 0:
        return p
    nodes = np.unique(p)
    index = np.full(n, -1, dtype=np.int64)
    index[nodes] = np.arange(nodes.size)
    before = np.zeros((nodes.size, nodes.size), dtype=bool)
    before[index[p[:, 0]], index[p[:, 1]]] = True
    for k in range(nodes.size):
        before |= before[:, k:k + 1] & before[k:k + 1, :]
    a, b = np.nonzero(before)
    return np.stack([nodes[a], nodes[b]], axis=1).astype(np.int64)


def make_pinned_clustered_aux(n: int, first: int, last: int, pairs: np.ndarray) -> PinnedAux:
    """The ``aux`` of this kind: the pinned kind's, over the closure of ``pairs``."""
    return make_pinned_aux(n, first, last, precedence_closure(n, pairs))


def make_data(dist: np.ndarray, layers: ConfiguredData, *, home: int = -1,
              lns: int = 0) -> PinnedClusteredData:
    """The ``data`` of this kind (``home``: the canonical node n - 1 of a serial arm's home,
    whose legs are ``layers.home_out``/``home_in``)."""
    return PinnedClusteredData(np.ascontiguousarray(dist, dtype=np.float64), layers,
                               int(home), int(lns))


# --- the decode --------------------------------------------------------------------------

@njit(cache=True)
def decode(genes, n, data, configs, work):
    """Cost of the closed canonical tour ``genes[:n]`` at its best nodes; ``configs``
    (by cluster) receives each cluster's node as an index within it. Without a home the
    layered shortest path starts at the smallest cluster (exact whatever the start)."""
    lay = data.layers
    if data.home >= 0:
        return _gc.decode(genes[1:n], n - 1, lay, configs)  # genes[0] is the home
    off = lay.offsets
    s0 = 0
    for k in range(1, n):
        if off[genes[k] + 1] - off[genes[k]] < off[genes[s0] + 1] - off[genes[s0]]:
            s0 = k
    for k in range(n):
        work[k] = genes[(s0 + k) % n]
    return _gc.decode(work, n, lay, configs)


@njit(cache=True, inline="always")
def _arc(lay, a, b):
    """Cost from node row ``a`` to node row ``b`` (-1: the home)."""
    if a < 0:
        return lay.home_out[b]
    if b < 0:
        return lay.home_in[a]
    return lay.legs[a, b]


@njit(cache=True)
def _rows(genes, n, data, configs, rows):
    """``rows[k]``: the node row visited at position k (-1 at the home)."""
    off = data.layers.offsets
    for k in range(n):
        g = genes[k]
        rows[k] = -1 if g == data.home else off[g] + configs[g]


@njit(cache=True)
def _fill_fixed(genes, n, data, rows, fixed):
    """``fixed[u, v]``: the cost between canonical nodes u and v at the nodes ``rows``
    (by position of ``genes``)."""
    lay = data.layers
    node_row = np.empty(n, dtype=np.int64)
    for k in range(n):
        node_row[genes[k]] = rows[k]
    for u in range(n):
        for v in range(n):
            fixed[u, v] = 0.0 if u == v else _arc(lay, node_row[u], node_row[v])


@njit(cache=True)
def tour_cost(genes, length, data, aux):
    """The tour's cost at its best nodes; ``inf`` if it breaks a pin or a pair."""
    if not _pc.feasible(genes[:length], aux):
        return np.inf
    configs = np.empty(data.layers.offsets.shape[0] - 1, dtype=np.int64)
    work = np.empty(length, dtype=np.int64)
    return decode(genes, length, data, configs, work)


# --- node-choosing relocations under precedence ------------------------------------------

@njit(cache=True)
def _window(v, pos, a, lo0, hi0):
    """The positions ``j`` after which ``v`` may go: its predecessors at or before j, its
    successors after j (``pos`` -1: not in the tour), within [lo0, hi0]."""
    lo = lo0
    hi = hi0
    for q in range(a.pred_ptr[v], a.pred_ptr[v + 1]):
        p = pos[a.pred_idx[q]]
        if p > lo:
            lo = p
    for q in range(a.succ_ptr[v], a.succ_ptr[v + 1]):
        p = pos[a.succ_idx[q]]
        if p >= 0 and p - 1 < hi:
            hi = p - 1
    return lo, hi


@njit(cache=True)
def relocate_pass(t, rows, n, data, a):
    """One sweep: every movable cluster taken out and put back at its cheapest feasible
    place and node (the others keep theirs), if that shortens the tour. Returns the gain."""
    lay = data.layers
    off = lay.offsets
    pos = np.empty(n, dtype=np.int64)
    for k in range(n):
        pos[t[k]] = k
    top = n - 1 if a.last < 0 else n - 2  # the last position a move may put a node after
    gain = 0.0
    for v in range(n):
        i = pos[v]
        if v == a.first or v == a.last or i == 0:
            continue
        ra = rows[i - 1]
        rv = rows[i]
        rb = rows[(i + 1) % n]
        saved = _arc(lay, ra, rv) + _arc(lay, rv, rb) - _arc(lay, ra, rb)
        best = saved - 1e-9 * max(1.0, abs(saved))
        best_j = -1
        best_r = -1
        lo, hi = _window(v, pos, a, 0, top)
        for j in range(lo, hi + 1):
            if j == i:
                continue  # the place after v is v's own (j = i - 1)
            if j == i - 1:
                x = ra
                y = rb
            else:
                x = rows[j]
                y = rows[(j + 1) % n]
            xy = _arc(lay, x, y)
            for r in range(off[v], off[v + 1]):
                d = _arc(lay, x, r) + _arc(lay, r, y) - xy
                if d < best:
                    best = d
                    best_j = j
                    best_r = r
        if best_j < 0:
            continue
        gain += saved - best
        # v from position i to just after position best_j
        if best_j == i - 1:
            rows[i] = best_r
            continue
        if best_j > i:
            for q in range(i, best_j):
                t[q] = t[q + 1]
                rows[q] = rows[q + 1]
                pos[t[q]] = q
            t[best_j] = v
            rows[best_j] = best_r
            pos[v] = best_j
        else:
            for q in range(i, best_j + 1, -1):
                t[q] = t[q - 1]
                rows[q] = rows[q - 1]
                pos[t[q]] = q
            t[best_j + 1] = v
            rows[best_j + 1] = best_r
            pos[v] = best_j + 1
    return gain


@njit(cache=True)
def local_search(genes, length, data, aux):
    """Decode, the pinned search on the decoded nodes' costs and node-choosing
    relocations, alternated until a round gains nothing (the tour never gets longer).
    Returns the cost."""
    n = length
    t = genes[:n]
    configs = np.empty(data.layers.offsets.shape[0] - 1, dtype=np.int64)
    work = np.empty(n, dtype=np.int64)
    rows = np.empty(n, dtype=np.int64)
    fixed = np.empty((n, n))
    cost = decode(t, n, data, configs, work)
    for _ in range(100):  # bounded; a round that gains nothing ends it earlier
        _rows(t, n, data, configs, rows)
        _fill_fixed(t, n, data, rows, fixed)
        _pc.local_search(t, n, fixed, aux)
        _rows(t, n, data, configs, rows)
        for _ in range(20):
            if relocate_pass(t, rows, n, data, aux) <= 0.0:
                break
        new = decode(t, n, data, configs, work)
        if new >= cost - 1e-12 * max(1.0, abs(cost)):
            return min(cost, new)
        cost = new
    return cost


# --- large-neighbourhood steps ------------------------------------------------------------

@njit(cache=True)
def _cycle(rows, n, lay):
    total = 0.0
    for k in range(n):
        total += _arc(lay, rows[k], rows[(k + 1) % n])
    return total


@njit(cache=True)
def _remove(t, rows, n, k, data, a, rng, removed):
    """Take ``k`` movable clusters out of ``t[:n]`` (at random, a segment of the movable
    run, or the most expensive, randomised) into ``removed``; returns the tour's length."""
    lay = data.layers
    lo = 1
    hi = n - 1 if a.last < 0 else n - 2  # movable positions lo..hi
    span = hi - lo + 1
    take = np.zeros(n, dtype=np.bool_)
    rule = rng.integers(0, 3)
    if rule == 0:
        chosen = 0
        while chosen < k:
            p = lo + rng.integers(0, span)
            if not take[p]:
                take[p] = True
                chosen += 1
    elif rule == 1:
        p = lo + rng.integers(0, span - k + 1)
        for q in range(k):
            take[p + q] = True
    else:
        score = np.full(n, np.inf)
        for p in range(lo, hi + 1):
            x = rows[p - 1]
            r = rows[p]
            y = rows[(p + 1) % n]
            score[p] = -(_arc(lay, x, r) + _arc(lay, r, y) - _arc(lay, x, y)) * (
                rng.random() ** 2)
        idx = np.argsort(score)
        for q in range(k):
            take[idx[q]] = True
    m = 0
    out = 0
    for p in range(n):
        if take[p]:
            removed[out] = t[p]
            out += 1
        else:
            t[m] = t[p]
            rows[m] = rows[p]
            m += 1
    return m


@njit(cache=True)
def _insert_all(t, rows, m, removed, n_removed, n, data, a, rng, noise):
    """Insert ``removed[:n_removed]`` in random order, each at its cheapest feasible place
    and node (``noise``: a share of random spread on the costs); returns the length."""
    lay = data.layers
    off = lay.offsets
    for i in range(n_removed - 1, 0, -1):
        j = rng.integers(0, i + 1)
        removed[i], removed[j] = removed[j], removed[i]
    pos = np.full(n, -1, dtype=np.int64)
    for k in range(m):
        pos[t[k]] = k
    for i in range(n_removed):
        s = removed[i]
        top = m - 1 if a.last < 0 else m - 2
        lo, hi = _window(s, pos, a, 0, top)
        best = np.inf
        best_p = lo
        best_r = off[s]
        for p in range(lo, hi + 1):
            x = rows[p]
            y = rows[(p + 1) % m]
            xy = _arc(lay, x, y)
            for r in range(off[s], off[s + 1]):
                d = _arc(lay, x, r) + _arc(lay, r, y) - xy
                if noise > 0.0:
                    d *= 1.0 + noise * rng.random()
                if d < best:
                    best = d
                    best_p = p
                    best_r = r
        for q in range(m, best_p + 1, -1):
            t[q] = t[q - 1]
            rows[q] = rows[q - 1]
            pos[t[q]] = q
        t[best_p + 1] = s
        rows[best_p + 1] = best_r
        pos[s] = best_p + 1
        m += 1
    return m


@njit(cache=True)
def large_neighbourhood_search(genes, n, data, aux, rng, steps):
    """``steps`` annealed remove-and-insert steps from ``genes[:n]`` (polished by
    :func:`local_search` when within :data:`LNS_POLISH_SLACK` of the current tour);
    ``genes`` receives the best tour found. Returns its cost."""
    lay = data.layers
    movable = n - 1 if aux.last < 0 else n - 2
    cost = local_search(genes, n, data, aux)
    if movable < 2 or steps <= 0:
        return cost
    configs = np.empty(lay.offsets.shape[0] - 1, dtype=np.int64)
    work = np.empty(n, dtype=np.int64)
    rows = np.empty(n, dtype=np.int64)
    removed = np.empty(n, dtype=np.int64)
    cur = genes[:n].copy()
    trial = np.empty(n, dtype=np.int64)
    best = cost
    t0 = LNS_TEMPERATURE * cost
    most = max(1, min(movable - 1, int(LNS_REMOVE_SHARE * movable)))
    for step in range(steps):
        temperature = t0 * 0.01 ** (step / max(1, steps - 1))
        trial[:] = cur
        decode(trial, n, data, configs, work)
        _rows(trial, n, data, configs, rows)
        k = 1 + rng.integers(0, most)
        m = _remove(trial, rows, n, k, data, aux, rng, removed)
        _insert_all(trial, rows, m, removed, n - m, n, data, aux, rng,
                    0.0 if rng.random() < 0.5 else 0.1)
        new = _cycle(rows, n, lay)
        if new < cost * (1.0 + LNS_POLISH_SLACK):
            new = local_search(trial, n, data, aux)
        if new < cost - 1e-9 * max(1.0, cost) or rng.random() < np.exp(
                -(new - cost) / max(temperature, 1e-300)):
            cost = new
            cur[:] = trial
            if new < best - 1e-9 * max(1.0, best):
                best = new
                genes[:n] = trial
    return best


# --- the operators -----------------------------------------------------------------------

@njit(cache=True)
def randomize(genes, data, aux, rng, best, best_len):
    """The pinned kind's construction or repaired kick of ``best`` on the cheapest costs,
    then :func:`local_search` (and the large-neighbourhood steps, if any)."""
    n = _pc.randomize(genes, data.dist, aux, rng, best, best_len)
    if data.lns > 0:
        large_neighbourhood_search(genes, n, data, aux, rng, data.lns)
    else:
        local_search(genes, n, data, aux)
    return n


@njit(cache=True)
def crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """The pinned kind's greedy crossover on the cheapest costs, then
    :func:`local_search` (and the large-neighbourhood steps, if any)."""
    n = _pc.crossover(genes_a, len_a, genes_b, len_b, data.dist, aux, rng, child)
    if data.lns > 0:
        large_neighbourhood_search(child, n, data, aux, rng, data.lns)
    else:
        local_search(child, n, data, aux)
    return n


@njit(cache=True, inline="always")
def no_mutation(genes, length, data, aux, rng, strength):
    return length


@njit(cache=True, inline="always")
def no_improvement(genes, length, data, aux):
    """Nothing: randomize and crossover end with the local search themselves."""
    return length


OPERATORS = OperatorSet(randomize, tour_cost, crossover, no_mutation, no_improvement)
"""The pinned clustered kind's operators (registered by :mod:`subtask_opt.chromosomes`)."""

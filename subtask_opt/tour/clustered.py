"""Tours with a configuration per target: the generalised TSP (GTSP) decode.

Each target ``i`` can be visited in one of ``K_i`` configurations (2 elbow
branches of a planar 2R arm; every IK solution of a serial arm); the time of a
leg depends on both ends' configurations. The configurations of all targets
form one flat list, target ``i`` owning the entries
``offsets[i] .. offsets[i + 1] - 1``. A chromosome is still a permutation of
the targets (the order); the configurations are not genes but are *decoded*
exactly: for a fixed order the best choice of one configuration per target is
a shortest path through the layers of configurations, a dynamic programme of
O(sum_k K_k K_(k+1)) = O(N K^2) per decode.

Two tour shapes:

* **with a home configuration** (``home_out``/``home_in`` non-empty): home ->
  targets in gene order -> home, one layered shortest path;
* **closed tour without home** (the planar problems): one layered shortest
  path per configuration of the first target, O(N K^3), linear in N (the 2R
  arm: 2 passes, exactly today's answers and tie-breaking: the lowest
  configuration index wins a tie).

The permutation operators of :mod:`subtask_opt.tour.permutation` (greedy
crossover, nearest-neighbour construction, kicks) see ``data.dist``, the
cheapest time of each target-to-target leg over its configuration pairs.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.ga.dispatch import OperatorSet
from subtask_opt.tour import permutation as tsp


class ConfiguredData(NamedTuple):
    """What the configured-permutation operators read (the GA's ``data``).

    Attributes:
        dist: (N, N) cheapest leg time between targets over their configuration
            pairs, zero diagonal (the permutation operators' distances).
        offsets: (N + 1,) int64; target i owns configurations offsets[i]..offsets[i+1]-1.
        legs: (M, M) leg time between configurations (a large finite penalty
            where a leg is impossible).
        home_out: (M,) time home -> each configuration; empty (0,) for a closed
            tour without home.
        home_in: (M,) time each configuration -> home; empty likewise.
        search: how the operators search, :data:`subtask_opt.tour.permutation.SEARCH_PAPER`
            (random restarts, no local search) or another mode (kicked restarts and
            alternating decode + local search).
        near: neighbour lists for *symmetric* legs (``legs == legs.T``, and
            ``home_out == home_in`` with a home): (N + 1, k) int64 over the targets and
            home (node N), or (N, k) over the targets of a closed tour without home. The
            local search then uses the neighbour-list moves of
            :func:`subtask_opt.tour.permutation.local_search`, configuration-choosing
            relocations and kicks; empty (0, 0): the exact full-sweep search, any costs.
        cheapest: (N, M), read with ``near`` only: the cheapest leg between any
            configuration of target v and configuration c, ``cheapest[v, c]``; the
            relocations' lower bound, which skips most places unread when targets have
            many configurations (legs blocked later only raise legs, so it stays a
            bound). Empty (0, 0): the looser bound from ``dist``.
        lns: 0, or the large-neighbourhood steps every restart individual and child gets
            (:func:`large_neighbourhood_search`, the search of sets with many vertices,
            symmetric legs or not) after the local search.
    """

    dist: np.ndarray
    offsets: np.ndarray
    legs: np.ndarray
    home_out: np.ndarray
    home_in: np.ndarray
    search: float
    near: np.ndarray = np.zeros((0, 0), dtype=np.int64)
    cheapest: np.ndarray = np.zeros((0, 0))
    lns: int = 0


@njit(cache=True)
def decode(genes, length, data, configs):
    """Best configurations for the order ``genes[:length]``; returns the tour time.

    ``configs`` (indexed by target) receives the chosen configuration of each
    target as an index *within* the target (0 .. K_i - 1).
    """
    n = length
    off = data.offsets
    legs = data.legs
    kmax = 1
    for i in range(off.shape[0] - 1):
        kmax = max(kmax, off[i + 1] - off[i])
    pred = np.zeros((n, kmax), dtype=np.int64)
    cost = np.empty(kmax)
    new = np.empty(kmax)
    has_home = data.home_out.shape[0] > 0
    first = genes[0]
    k_first = off[first + 1] - off[first]
    n_starts = 1 if has_home else k_first
    best_total = np.inf
    for c0 in range(n_starts):
        for c in range(k_first):
            if has_home:
                cost[c] = data.home_out[off[first] + c]
            else:
                cost[c] = 0.0 if c == c0 else np.inf
        for k in range(1, n):
            a = genes[k - 1]
            b = genes[k]
            ka = off[a + 1] - off[a]
            kb = off[b + 1] - off[b]
            # row by row (legs is row-major: a column walk misses the cache at every
            # read of a large M x M matrix); the lowest ca still wins a tie
            row = legs[off[a], off[b]:off[b] + kb]
            c0_cost = cost[0]
            for cb in range(kb):
                new[cb] = c0_cost + row[cb]
                pred[k, cb] = 0
            for ca in range(1, ka):
                row = legs[off[a] + ca, off[b]:off[b] + kb]
                c_ca = cost[ca]
                for cb in range(kb):
                    v = c_ca + row[cb]
                    if v < new[cb]:
                        new[cb] = v
                        pred[k, cb] = ca
            for cb in range(kb):
                cost[cb] = new[cb]
        last = genes[n - 1]
        k_last = off[last + 1] - off[last]
        if has_home:
            total = cost[0] + data.home_in[off[last]]
            c_last = 0
            for c in range(1, k_last):
                v = cost[c] + data.home_in[off[last] + c]
                if v < total:
                    total = v
                    c_last = c
        else:
            total = cost[0] + legs[off[last], off[first] + c0]
            c_last = 0
            for c in range(1, k_last):
                v = cost[c] + legs[off[last] + c, off[first] + c0]
                if v < total:
                    total = v
                    c_last = c
        if total < best_total:
            best_total = total
            c = c_last
            for k in range(n - 1, 0, -1):
                configs[genes[k]] = c
                c = pred[k, c]
            configs[genes[0]] = c if has_home else c0
    return best_total


@njit(cache=True, inline="always")
def tour_cost(genes, length, data, aux):
    """Tour time with the best configurations (the ``evaluate`` operator)."""
    configs = np.empty(data.dist.shape[0], dtype=np.int64)
    return decode(genes, length, data, configs)


@njit(cache=True)
def induced_matrix(data, configs):
    """(N, N) leg times for fixed configurations (per-target indices)."""
    n = data.dist.shape[0]
    off = data.offsets
    out = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            out[i, j] = data.legs[off[i] + configs[i], off[j] + configs[j]]
    return out


@njit(cache=True, inline="always")
def _induced_with_home(data, configs):
    """(N + 1, N + 1) leg times for fixed configurations, node N being home."""
    n = data.dist.shape[0]
    off = data.offsets
    out = np.zeros((n + 1, n + 1))
    for i in range(n):
        for j in range(n):
            out[i, j] = data.legs[off[i] + configs[i], off[j] + configs[j]]
        out[n, i] = data.home_out[off[i] + configs[i]]
        out[i, n] = data.home_in[off[i] + configs[i]]
    return out


@njit(cache=True)
def block_minima(legs, offsets):
    """(N, N) cheapest leg between each pair of targets (zero diagonal), (N, M) cheapest
    leg from each configuration to each target (``cheapest[b, r]``: from configuration r
    to any of target b's; :class:`ConfiguredData`'s ``cheapest`` for symmetric legs) and
    the largest leg, one pass over the (M, M) legs."""
    n = offsets.shape[0] - 1
    dist = np.full((n, n), np.inf)
    cheapest = np.empty((n, legs.shape[0]))
    top = 0.0
    for a in range(n):
        for r in range(offsets[a], offsets[a + 1]):
            for b in range(n):
                best = np.inf
                for c in range(offsets[b], offsets[b + 1]):
                    v = legs[r, c]
                    if v < best:
                        best = v
                    if v > top:
                        top = v
                cheapest[b, r] = best
                if best < dist[a, b]:
                    dist[a, b] = best
        dist[a, a] = 0.0
    return dist, cheapest, top


@njit(cache=True, inline="always")
def _leg(data, u, cu, v, cv, home):
    """Time from node u in its configuration cu to node v in cv; node ``home`` is home."""
    off = data.offsets
    if u == home:
        return data.home_out[off[v] + cv]
    if v == home:
        return data.home_in[off[u] + cu]
    return data.legs[off[u] + cu, off[v] + cv]


@njit(cache=True)
def relocate_pass(ext, data, configs, home):
    """One sweep of configuration-choosing relocations on the closed tour ``ext``.

    ``ext`` is the closed tour over the targets and, if ``home`` is N, home (node N):
    (N + 1,); with ``home`` -1 a closed tour of the N targets without home, (N,). The
    targets have the configurations ``configs``. Each target in turn is taken out and put
    back where it was or between two consecutive nodes next to one of its ``data.near``
    neighbours, in whichever of its configurations is cheapest there (the other targets keep
    theirs: O(K) per place, GLNS-style); the best place that shortens the tour is
    taken. Symmetric legs (``data.near``'s contract). Returns the total gain.
    """
    m = ext.shape[0]
    n_targets = m - 1 if home >= 0 else m
    off = data.offsets
    near = data.near
    cheapest = data.cheapest
    tight = cheapest.shape[0] > 0
    pos = np.empty(m, dtype=np.int64)
    for i in range(m):
        pos[ext[i]] = i
    gain_total = 0.0
    for v in range(n_targets):
        i = pos[v]
        p = ext[(i - 1) % m]
        s = ext[(i + 1) % m]
        cp = configs[p] if p != home else 0
        cs = configs[s] if s != home else 0
        cv = configs[v]
        removed = (_leg(data, p, cp, v, cv, home) + _leg(data, v, cv, s, cs, home)
                   - _leg(data, p, cp, s, cs, home))
        eps = 1e-12 * max(1.0, removed)
        best = -eps
        best_a = -1
        best_k = -1
        kv = off[v + 1] - off[v]
        for t in range(-1, near.shape[1]):  # -1: back between p and s, another configuration
            u = near[v, max(t, 0)]
            j = pos[u]
            for side in range(2):
                if t < 0:
                    if side == 1:
                        break
                    a, b = p, s
                else:
                    a = u if side == 0 else ext[(j - 1) % m]
                    b = ext[(j + 1) % m] if side == 0 else u
                    if a == v or b == v:
                        continue  # an edge of v: the place between p and s, tried first
                ca = configs[a] if a != home else 0
                cb = configs[b] if b != home else 0
                base = _leg(data, a, ca, b, cb, home) + removed
                # a lower bound from the cheapest legs skips most places unread
                if tight:
                    bound = ((cheapest[v, off[a] + ca] if a != home else 0.0)
                             + (cheapest[v, off[b] + cb] if b != home else 0.0))
                else:
                    bound = ((data.dist[a, v] if a != home else 0.0)
                             + (data.dist[v, b] if b != home else 0.0))
                if bound - base >= best:
                    continue
                # symmetric legs: both legs read along a row (leg v -> b = leg b -> v)
                for k in range(kv):
                    delta = (_leg(data, a, ca, v, k, home) + _leg(data, b, cb, v, k, home)
                             - base)
                    if delta < best:
                        best = delta
                        best_a = a
                        best_k = k
        if best_a < 0:
            continue
        # move v from position i to just after best_a, shifting the nodes between
        ja = pos[best_a]
        if ja > i:
            for q in range(i, ja):
                ext[q] = ext[q + 1]
                pos[ext[q]] = q
            ext[ja] = v
            pos[v] = ja
        else:
            for q in range(i, ja + 1, -1):
                ext[q] = ext[q - 1]
                pos[ext[q]] = q
            ext[ja + 1] = v
            pos[v] = ja + 1
        configs[v] = best_k
        gain_total -= best
    return gain_total


@njit(cache=True, inline="always")
def _has_near(data, n):
    """Whether ``data.near`` holds the neighbour lists of symmetric legs (one row per node)."""
    rows = n + 1 if data.home_out.shape[0] > 0 else n
    return data.near.shape[0] == rows


@njit(cache=True, inline="always")
def _fixed_matrix(data, configs):
    """Leg times for fixed configurations over the tour's nodes (with home: node N)."""
    if data.home_out.shape[0] > 0:
        return _induced_with_home(data, configs)
    return induced_matrix(data, configs)


@njit(cache=True)
def symmetric_fixed_matrix(data, configs):
    """:func:`_fixed_matrix` for symmetric legs (``data.near``'s contract): each leg read
    once, along its configuration's row, and mirrored (the same values: half the scattered
    reads of a large leg matrix)."""
    n = data.dist.shape[0]
    off = data.offsets
    has_home = data.home_out.shape[0] > 0
    out = np.zeros((n + 1, n + 1) if has_home else (n, n))
    rows = np.empty(n, dtype=np.int64)
    for i in range(n):
        rows[i] = off[i] + configs[i]
    for i in range(n):
        legs = data.legs[rows[i]]
        out[i, i] = legs[rows[i]]
        for j in range(i + 1, n):
            v = legs[rows[j]]
            out[i, j] = v
            out[j, i] = v
        if has_home:
            out[n, i] = data.home_out[rows[i]]
            out[i, n] = data.home_in[rows[i]]
    return out


@njit(cache=True)
def _symmetric_round(genes, n, data, aux, configs, ext, fixed, fixed_configs):
    """Neighbour-list local search of the order on the decoded configurations, then
    configuration-choosing relocations, until neither improves (symmetric legs).

    ``fixed`` holds the legs at ``fixed_configs`` (:func:`symmetric_fixed_matrix`); it is
    brought to ``configs`` first and left at the configurations the round ends with.
    Without home the closed tour is searched as it is; the relocations keep the other
    targets' configurations, so re-decoding afterwards (all start configurations) can
    only shorten it further."""
    near_aux = _near_aux(data, aux)
    has_home = data.home_out.shape[0] > 0
    m = _to_ext(genes, n, ext, has_home)
    home = n if has_home else -1
    refresh_fixed(fixed, data, configs, fixed_configs)
    for _ in range(100):  # bounded; a pass that gains nothing ends it earlier
        tsp.local_search(ext, m, fixed, near_aux)
        if relocate_pass(ext[:m], data, configs, home) <= 0.0:
            break
        refresh_fixed(fixed, data, configs, fixed_configs)
    _from_ext(ext, n, genes, has_home)


@njit(cache=True, inline="always")
def refresh_fixed(fixed, data, configs, fixed_configs):
    """Bring ``fixed`` (:func:`symmetric_fixed_matrix` of ``fixed_configs``) to ``configs``:
    only the rows and columns of targets whose configuration changed, O(N) each where
    rebuilding is O(N^2), read along rows (symmetric legs); ``fixed_configs`` receives
    ``configs``."""
    n = data.dist.shape[0]
    off = data.offsets
    with_home = fixed.shape[0] > n
    for v in range(n):
        if configs[v] == fixed_configs[v]:
            continue
        fixed_configs[v] = configs[v]
        row = off[v] + configs[v]
        legs = data.legs[row]
        for j in range(n):
            x = legs[off[j] + configs[j]]
            fixed[v, j] = x
            fixed[j, v] = x
        if with_home:
            fixed[n, v] = data.home_out[row]
            fixed[v, n] = data.home_in[row]


@njit(cache=True)
def local_search(genes, length, data, aux):
    """Alternate exact decoding and a local search on the decoded configurations.

    Each round fixes the configurations the decoder chose, improves the order
    on that matrix (with home as an extra node when the tour has one) to a
    local optimum, and decodes again; the tour time never increases, and the
    loop ends when a round gains nothing. With ``data.near`` (symmetric legs, with or
    without home) the order search is the neighbour-list one plus configuration-choosing relocations
    (:func:`relocate_pass`); otherwise the exact full-sweep 2-opt/Or-opt.
    """
    n = length
    configs = np.empty(data.dist.shape[0], dtype=np.int64)
    cost = decode(genes, n, data, configs)
    has_home = data.home_out.shape[0] > 0
    ext = np.empty(n + 1, dtype=genes.dtype)
    symmetric = _has_near(data, n)
    # with symmetric legs the fixed-configuration legs are kept up to date across rounds
    fixed = symmetric_fixed_matrix(data, configs) if symmetric else np.zeros((0, 0))
    fixed_configs = configs.copy()
    kept_genes = genes[:n].copy()
    kept_configs = configs.copy()
    for _ in range(100):  # bounded; a round that gains nothing ends it earlier
        if symmetric:
            tsp.copy_run(kept_genes, 0, genes, 0, n)
            tsp.copy_run(kept_configs, 0, configs, 0, n)
            _symmetric_round(genes, n, data, aux, configs, ext, fixed, fixed_configs)
            if _same(genes, kept_genes, n) and _same(configs, kept_configs, n):
                break  # nothing moved: the decode would give this tour again
        else:
            m = _to_ext(genes, n, ext, has_home)
            tsp.exact_local_search(ext, m, _fixed_matrix(data, configs), aux)
            _from_ext(ext, n, genes, has_home)
        new_cost = decode(genes, n, data, configs)
        if new_cost >= cost - 1e-12 * max(1.0, abs(cost)):
            break
        cost = new_cost
    return n


@njit(cache=True, inline="always")
def _same(a, b, n):
    for i in range(n):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True, inline="always")
def _near_aux(data, aux):
    """``aux`` with the neighbour lists over targets + home."""
    return tsp.PermutationAux(aux.search, aux.fallback, aux.grasp_share, aux.max_segment,
                              aux.kicks, data.near)


@njit(cache=True, inline="always")
def _to_ext(genes, n, ext, has_home):
    """The tour's nodes into ``ext``: home (node N) then the targets, or the targets
    alone without home; returns their number."""
    if not has_home:
        tsp.copy_run(ext, 0, genes, 0, n)
        return n
    ext[0] = n  # home
    tsp.copy_run(ext, 1, genes, 0, n)
    return n + 1


@njit(cache=True, inline="always")
def _from_ext(ext, n, genes, has_home):
    if not has_home:
        tsp.copy_run(genes, 0, ext, 0, n)
        return
    h = 0
    while ext[h] != n:
        h += 1
    for k in range(n):
        genes[k] = ext[(h + 1 + k) % (n + 1)]


CONFIGURATION_KICKS_MAX = 16
"""Most configuration kicks after an iterated search (:func:`configuration_kick_count`)."""


@njit(cache=True, inline="always")
def configuration_kick_count(kicks):
    """Configuration kicks after an iterated search of ``kicks`` double-bridge kicks:
    two per kick (on the held-out planar sets of benchmarks/heldout.py one missed 23 of
    260 joint-model runs, two 6, at about 1.5x the time), at most
    :data:`CONFIGURATION_KICKS_MAX`. Each runs a local search of the whole tour: N/5 of
    them per child made 200 elbow-choosing subtasks take 17-41 s of CPU and 500 about
    6 minutes; 16 took 8-12 s and 12-30 s, with answers within the spread of the seeds
    (benchmarks/elbows.py: 3 seeds on sets of 100, 200 and 500 subtasks, both planar arms)."""
    return min(2 * kicks, CONFIGURATION_KICKS_MAX)


@njit(cache=True)
def iterated_configured_search(genes, n, data, aux, rng, kicks):
    """``kicks`` local double-bridge kicks of the tour (with home, if any) on the decoded
    configurations of ``genes[:n]``, each polished and kept unless longer
    (:func:`subtask_opt.tour.permutation.iterated_local_search`); symmetric legs."""
    configs = np.empty(n, dtype=np.int64)
    decode(genes, n, data, configs)
    has_home = data.home_out.shape[0] > 0
    ext = np.empty(n + 1, dtype=genes.dtype)
    m = _to_ext(genes, n, ext, has_home)
    tsp.iterated_local_search(ext, m, symmetric_fixed_matrix(data, configs), _near_aux(data, aux),
                              rng, kicks)
    _from_ext(ext, n, genes, has_home)
    if not has_home:
        configuration_kicks(genes, n, data, aux, rng, configuration_kick_count(kicks))
    return n


BALL_SHARE = 0.5
"""Share of configuration kicks that switch the targets around a random one (the others
move both ends of a run of one configuration)."""
WALK_SLACK = 0.003
"""Configuration kicks walk on from a result up to this share longer than the last one."""


@njit(cache=True, inline="always")
def configuration_kicks(genes, n, data, aux, rng, kicks):
    """``kicks`` rounds of: switch a set of targets to another configuration, let the
    order adapt to those configurations (neighbour-list search and relocations,
    :func:`_symmetric_round`), then decode and search as usual (:func:`local_search`).
    Order moves that keep the configurations rarely move many targets across a change
    of elbow at once; these kicks do. The set is either the targets around a random
    one, or, at two changes of configuration along the tour drawn at random (possibly
    the same one twice), the targets between the change and a point up to a quarter of
    the tour away (a run of one configuration grows or shrinks at both ends). Tours in
    the basins of different optima of the held-out planar sets differ in such sets.

    The kicks walk: each starts from the last result unless that was more than
    :data:`WALK_SLACK` longer, so two kicks can cross a slightly worse tour. ``genes``
    receives the shortest tour seen. Returns its time."""
    configs = np.empty(n, dtype=np.int64)
    cost = decode(genes, n, data, configs)
    trial = np.empty(n, dtype=genes.dtype)
    ext = np.empty(n + 1, dtype=genes.dtype)
    off = data.offsets
    switches = np.empty(n, dtype=np.int64)
    walk = genes[:n].copy()
    walk_cost = cost
    fixed = symmetric_fixed_matrix(data, configs)
    fixed_configs = configs.copy()
    for _ in range(kicks):
        tsp.copy_run(trial, 0, walk, 0, n)
        decode(trial, n, data, configs)
        if rng.random() < BALL_SHARE:
            # the targets around a random one, out to the nearer of two random others
            # (a third of the targets on average; no sort to compile)
            c = trial[rng.integers(0, n)]
            radius = min(data.dist[c, rng.integers(0, n)], data.dist[c, rng.integers(0, n)])
            for v in range(n):
                if data.dist[c, v] <= radius:
                    _flip(v, configs, off, rng)
        else:
            # two ends of runs of one configuration move, by up to a quarter of the tour
            n_switch = 0
            for k in range(n):
                if configs[trial[k]] != configs[trial[k - 1]]:
                    switches[n_switch] = k
                    n_switch += 1
            for _ in range(2):
                k = switches[rng.integers(0, n_switch)] if n_switch > 0 else rng.integers(0, n)
                shift = rng.integers(-(n // 4), n // 4 + 1)
                for q in range(min(0, shift), max(0, shift)):
                    _flip(trial[(k + q) % n], configs, off, rng)
        _symmetric_round(trial, n, data, aux, configs, ext, fixed, fixed_configs)
        local_search(trial, n, data, aux)
        new = decode(trial, n, data, configs)
        if new < cost - 1e-12 * max(1.0, cost):
            cost = new
            tsp.copy_run(genes, 0, trial, 0, n)
        if new < walk_cost * (1.0 + WALK_SLACK):
            walk_cost = new
            tsp.copy_run(walk, 0, trial, 0, n)
    return cost


@njit(cache=True, inline="always")
def _flip(v, configs, off, rng):
    """Target ``v`` to a random other one of its configurations (if it has another)."""
    kv = off[v + 1] - off[v]
    if kv > 1:
        configs[v] = (configs[v] + 1 + rng.integers(0, kv - 1)) % kv


@njit(cache=True, inline="always")
def randomize(genes, data, aux, rng, best, best_len):
    """Random tours for the paper's search, kicks of the best otherwise: with symmetric
    legs (``data.near``) an iterated local search from the best tour's configurations,
    except for a ``grasp_share`` of randomised nearest-neighbour tours; then (except for
    the paper's search) alternating decoding and local search (:func:`local_search`)."""
    n = data.dist.shape[0]
    if data.search == tsp.SEARCH_PAPER:
        tsp.random_tour(genes, data.dist, aux, rng, best, best_len)
    elif (best_len == 0 or not _has_near(data, n) or n < 8
            or rng.random() < aux.grasp_share):
        tsp.kicked_best(genes, data.dist, aux, rng, best, best_len)
        local_search(genes, n, data, aux)
    else:
        tsp.copy_run(genes, 0, best, 0, n)
        iterated_configured_search(genes, n, data, aux, rng, max(1, aux.kicks))
        local_search(genes, n, data, aux)
    if data.lns > 0:
        large_neighbourhood_search(genes, n, data, aux, rng, data.lns)
    return n


@njit(cache=True, inline="always")
def crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """Greedy crossover on the cheapest target-to-target times; then, except for the
    paper's search, alternating decoding and local search (:func:`local_search`), with
    symmetric legs (``data.near``) after an iterated search of ``aux.kicks`` kicks, at
    least one without home (:func:`iterated_configured_search`)."""
    n = tsp.greedy_crossover(genes_a, len_a, genes_b, len_b, data.dist, aux, rng, child)
    # without home at least one kick: the configuration kicks are what moves the elbow split
    kicks = aux.kicks if data.home_out.shape[0] > 0 else max(1, aux.kicks)
    if data.search != tsp.SEARCH_PAPER:
        if _has_near(data, n) and n >= 8 and kicks > 0:
            local_search(child, n, data, aux)
            iterated_configured_search(child, n, data, aux, rng, kicks)
        local_search(child, n, data, aux)
    if data.lns > 0:
        large_neighbourhood_search(child, n, data, aux, rng, data.lns)
    return n


@njit(cache=True, inline="always")
def no_mutation(genes, length, data, aux, rng, strength):
    return length


@njit(cache=True, inline="always")
def no_improvement(genes, length, data, aux):
    """Nothing: randomize and crossover end with the local search themselves, so the
    loop's improve step compiles no search of its own (CONTRIBUTING, the cold start)."""
    return length


OPERATORS = OperatorSet(randomize, tour_cost, crossover, no_mutation, no_improvement)
"""The clustered (configured) permutation kind's operators (registered by
:mod:`subtask_opt.chromosomes`)."""


# --------------------------------------------------------------------------- large sets
#
# The GTSPLIB search (data.lns > 0): sets of many vertices, symmetric or not. Every operator
# ends in a large-neighbourhood search after GLNS (Smith and Imeson 2017): remove a random
# number of sets (at random, a segment of the tour, the most expensive ones, or a set and
# its nearest), put each back at its cheapest place in its cheapest vertex (the unified
# insertion), re-choose every vertex for the new order (the layered shortest path) and
# move single sets to their best place until none improves; a simulated-annealing test
# keeps the change or not. The tour is a list of sets with a vertex (a row of data.legs)
# each.

LNS_REMOVE_SHARE = 0.25
"""Most sets one large-neighbourhood step removes, as a share of the tour (GLNS: 30%)."""
LNS_POLISH_SLACK = 0.005
"""A changed tour up to this share longer than the current one is polished; the others
are rejected as they are."""
LNS_TEMPERATURE = 0.003
"""Initial annealing temperature of each search, as a share of the start tour's cost (a worse
tour is kept with probability exp(-excess / T)); it cools geometrically to 1/100 of that."""


@njit(cache=True)
def _sp_tour(sets, n, data, vert, work):
    """Best vertex of every set for the cyclic order ``sets[:n]`` (``vert[k]`` receives the
    leg row of set ``sets[k]``'s vertex); returns the tour's cost. The layered shortest path
    of :func:`decode` from the smallest set (exact whatever the start)."""
    off = data.offsets
    s0 = 0
    for k in range(1, n):
        if off[sets[k] + 1] - off[sets[k]] < off[sets[s0] + 1] - off[sets[s0]]:
            s0 = k
    for k in range(n):
        work[k] = sets[(s0 + k) % n]
    configs = np.empty(data.dist.shape[0], dtype=np.int64)
    cost = decode(work, n, data, configs)
    for k in range(n):
        vert[k] = off[sets[k]] + configs[sets[k]]
    return cost


@njit(cache=True, inline="always")
def _cycle_cost(vert, n, legs):
    total = 0.0
    for k in range(n):
        total += legs[vert[k], vert[(k + 1) % n]]
    return total


@njit(cache=True)
def _best_insertion(s, sets, vert, m, data):
    """Cheapest (extra cost, position, vertex row) to put set ``s`` into the cyclic tour
    ``sets[:m]`` (between position p and p + 1), over every place and vertex of ``s``."""
    off = data.offsets
    legs = data.legs
    best = np.inf
    best_p = 0
    best_r = off[s]
    for p in range(m):
        a = vert[p]
        b = vert[(p + 1) % m]
        ab = legs[a, b]
        for r in range(off[s], off[s + 1]):
            d = legs[a, r] + legs[r, b] - ab
            if d < best:
                best = d
                best_p = p
                best_r = r
    return best, best_p, best_r


@njit(cache=True, inline="always")
def _insert_at(sets, vert, m, p, s, r):
    """Put set ``s`` (vertex row ``r``) at index ``p + 1`` of ``sets[:m]`` (after
    position p)."""
    for q in range(m, p + 1, -1):
        sets[q] = sets[q - 1]
        vert[q] = vert[q - 1]
    sets[p + 1] = s
    vert[p + 1] = r


@njit(cache=True, inline="always")
def _remove_at(sets, vert, m, p):
    for q in range(p, m - 1):
        sets[q] = sets[q + 1]
        vert[q] = vert[q + 1]


@njit(cache=True)
def _insert_all(sets, vert, m, removed, n_removed, data, rng, noise):
    """Insert the sets ``removed[:n_removed]`` in random order, each at its cheapest place
    and vertex (a ``noise`` share of random spread on the insertion costs); returns m."""
    for i in range(n_removed - 1, 0, -1):
        j = rng.integers(0, i + 1)
        removed[i], removed[j] = removed[j], removed[i]
    off = data.offsets
    legs = data.legs
    for i in range(n_removed):
        s = removed[i]
        if m == 0:
            sets[0] = s
            vert[0] = off[s] + rng.integers(0, off[s + 1] - off[s])
            m = 1
            continue
        if noise > 0.0:
            best = np.inf
            best_p = 0
            best_r = off[s]
            for p in range(m):
                a = vert[p]
                b = vert[(p + 1) % m]
                ab = legs[a, b]
                for r in range(off[s], off[s + 1]):
                    d = (legs[a, r] + legs[r, b] - ab) * (1.0 + noise * rng.random())
                    if d < best:
                        best = d
                        best_p = p
                        best_r = r
        else:
            _, best_p, best_r = _best_insertion(s, sets, vert, m, data)
        _insert_at(sets, vert, m, best_p, s, best_r)
        m += 1
    return m


@njit(cache=True)
def _move_opt(sets, vert, n, data):
    """Take every set out in turn and put it back at its cheapest place and vertex
    (GLNS's moveopt), until a sweep gains nothing; returns the gain."""
    legs = data.legs
    gain = 0.0
    for _ in range(50):
        swept = 0.0
        for v in range(n):
            # find set v's position
            p = 0
            for k in range(n):
                if sets[k] == v:
                    p = k
                    break
            a = vert[(p - 1) % n]
            r = vert[p]
            b = vert[(p + 1) % n]
            saved = legs[a, r] + legs[r, b] - legs[a, b]
            _remove_at(sets, vert, n, p)
            extra, q, rr = _best_insertion(v, sets, vert, n - 1, data)
            if extra < saved - 1e-9 * max(1.0, saved):
                _insert_at(sets, vert, n - 1, q, v, rr)
                swept += saved - extra
            else:  # back where it was
                _insert_at(sets, vert, n - 1, p - 1, v, r)
        gain += swept
        if swept <= 0.0:
            break
    return gain


@njit(cache=True)
def _move_opt_near(sets, vert, n, data):
    """:func:`_move_opt` over the places next to each set's ``data.near`` neighbours and
    its own place (symmetric legs, read along rows); returns the gain."""
    legs = data.legs
    off = data.offsets
    near = data.near
    pos = np.empty(n, dtype=np.int64)
    for k in range(n):
        pos[sets[k]] = k
    gain = 0.0
    for _ in range(50):
        swept = 0.0
        for v in range(n):
            p = pos[v]
            a = vert[(p - 1) % n]
            r = vert[p]
            b = vert[(p + 1) % n]
            saved = legs[a, r] + legs[b, r] - legs[a, b]
            eps = 1e-9 * max(1.0, saved)
            best = saved - eps
            best_x = -1
            best_r = -1
            for t in range(-1, near.shape[1]):
                for side in range(2):
                    if t < 0:
                        if side == 1:
                            break
                        x = (p - 1) % n
                        y = (p + 1) % n
                    else:
                        q = pos[near[v, t]]
                        if q == p:
                            continue
                        x = q if side == 0 else (q - 1) % n
                        y = (q + 1) % n if side == 0 else q
                        if x == p:
                            x = (p - 1) % n
                        if y == p:
                            y = (p + 1) % n
                        if x == (p - 1) % n and y == (p + 1) % n:
                            continue  # v's own place, tried at t = -1
                    vx = vert[x]
                    vy = vert[y]
                    xy = legs[vx, vy]
                    for rr in range(off[v], off[v + 1]):
                        d = legs[rr, vx] + legs[rr, vy] - xy
                        if d < best:
                            best = d
                            best_x = x
                            best_r = rr
            if best_x < 0:
                continue
            swept += saved - best
            if best_x == (p - 1) % n and vert[(best_x + 1) % n] == r:  # same place
                vert[p] = best_r
                continue
            # move v from index p to just after index best_x
            if best_x > p:
                for q in range(p, best_x):
                    sets[q] = sets[q + 1]
                    vert[q] = vert[q + 1]
                    pos[sets[q]] = q
                sets[best_x] = v
                vert[best_x] = best_r
                pos[v] = best_x
            else:
                for q in range(p, best_x + 1, -1):
                    sets[q] = sets[q - 1]
                    vert[q] = vert[q - 1]
                    pos[sets[q]] = q
                sets[best_x + 1] = v
                vert[best_x + 1] = best_r
                pos[v] = best_x + 1
        gain += swept
        if swept <= 0.0:
            break
    return gain


@njit(cache=True)
def _two_opt(sets, vert, n, legs):
    """First-improvement 2-opt on the fixed vertices (symmetric legs); returns the gain."""
    gain = 0.0
    improved = True
    while improved:
        improved = False
        for i in range(n - 1):
            a = vert[i]
            b = vert[i + 1]
            ab = legs[a, b]
            for j in range(i + 2, n if i > 0 else n - 1):
                c = vert[j]
                d = vert[(j + 1) % n]
                delta = legs[a, c] + legs[b, d] - ab - legs[c, d]
                if delta < -1e-9 * max(1.0, ab):
                    lo = i + 1
                    hi = j
                    while lo < hi:
                        sets[lo], sets[hi] = sets[hi], sets[lo]
                        vert[lo], vert[hi] = vert[hi], vert[lo]
                        lo += 1
                        hi -= 1
                    gain -= delta
                    improved = True
                    b = vert[i + 1]
                    ab = legs[a, b]
    return gain


@njit(cache=True)
def _polish(sets, vert, n, data, work, symmetric, aux, strong):
    """Vertices re-chosen, single sets moved (and 2-opt with symmetric legs) until nothing
    improves; returns the cost. ``strong`` with symmetric legs: the clustered chromosome's
    own search (:func:`local_search`: neighbour-list 2-opt and Or-opt on the decoded
    vertices, vertex-choosing relocations) first."""
    if strong and symmetric:
        local_search(sets, n, data, aux)
    cost = _sp_tour(sets, n, data, vert, work)
    for _ in range(20):
        if symmetric:
            _move_opt_near(sets, vert, n, data)
            _two_opt(sets, vert, n, data.legs)
        else:
            _move_opt(sets, vert, n, data)
        new = _sp_tour(sets, n, data, vert, work)
        if new >= cost - 1e-9 * max(1.0, cost):
            cost = min(cost, new)
            break
        cost = new
    return _cycle_cost(vert, n, data.legs)


@njit(cache=True)
def _remove_sets(sets, vert, n, k, data, rng, removed):
    """Take ``k`` sets out of the tour by one of four rules (random, a segment, the most
    expensive, a set and its nearest); ``removed`` receives them; returns the tour's
    new length."""
    legs = data.legs
    rule = rng.integers(0, 4)
    take = np.zeros(data.dist.shape[0], dtype=np.bool_)
    if rule == 0:  # random sets
        for i in range(k):
            removed[i] = sets[i]
        for i in range(k, n):
            j = rng.integers(0, i + 1)
            if j < k:
                removed[j] = sets[i]
        for i in range(k):
            take[removed[i]] = True
    elif rule == 1:  # a segment
        p = rng.integers(0, n)
        for i in range(k):
            take[sets[(p + i) % n]] = True
    elif rule == 2:  # the most expensive sets to visit (randomised)
        score = np.empty(n)
        for p in range(n):
            a = vert[(p - 1) % n]
            r = vert[p]
            b = vert[(p + 1) % n]
            score[p] = -(legs[a, r] + legs[r, b] - legs[a, b]) * (rng.random() ** 2)
        idx = np.argsort(score)
        for i in range(k):
            take[sets[idx[i]]] = True
    else:  # a random set and its nearest
        c = sets[rng.integers(0, n)]
        d = np.empty(n)
        for p in range(n):
            d[p] = data.dist[c, sets[p]] + data.dist[sets[p], c]
        idx = np.argsort(d)
        for i in range(k):
            take[sets[idx[i]]] = True
    m = 0
    r = 0
    for p in range(n):
        if take[sets[p]]:
            removed[r] = sets[p]
            r += 1
        else:
            sets[m] = sets[p]
            vert[m] = vert[p]
            m += 1
    return m


@njit(cache=True)
def large_neighbourhood_search(genes, n, data, aux, rng, steps, temperature0=LNS_TEMPERATURE,
                               slack=LNS_POLISH_SLACK, share=LNS_REMOVE_SHARE, strong=True):
    """``steps`` annealed remove-and-insert steps from the order ``genes[:n]``, each
    polished (:func:`_polish`); ``genes`` receives the best order found. Returns its cost."""
    legs = data.legs
    symmetric = data.near.shape[0] > 0
    sets = np.empty(n, dtype=np.int64)
    vert = np.empty(n, dtype=np.int64)
    work = np.empty(n, dtype=np.int64)
    removed = np.empty(n, dtype=np.int64)
    for k in range(n):
        sets[k] = genes[k]
    cost = _polish(sets, vert, n, data, work, symmetric, aux, strong)
    best_sets = sets.copy()
    best_vert = vert.copy()
    best = cost
    cur_sets = sets.copy()
    cur_vert = vert.copy()
    t0 = temperature0 * cost
    most = max(1, min(n - 2, int(share * n)))
    for step in range(steps):
        temperature = t0 * 0.01 ** (step / max(1, steps - 1))
        for k in range(n):
            sets[k] = cur_sets[k]
            vert[k] = cur_vert[k]
        k_out = 1 + rng.integers(0, most)
        m = _remove_sets(sets, vert, n, k_out, data, rng, removed)
        m = _insert_all(sets, vert, m, removed, n - m, data, rng,
                        0.0 if rng.random() < 0.5 else 0.1)
        new = _cycle_cost(vert, n, legs)
        if new < cost * (1.0 + slack):  # hopeless changes skip the polish
            new = _polish(sets, vert, n, data, work, symmetric, aux, strong)
        if new < cost - 1e-9 * max(1.0, cost) or rng.random() < np.exp(
                -(new - cost) / max(temperature, 1e-300)):
            cost = new
            for k in range(n):
                cur_sets[k] = sets[k]
                cur_vert[k] = vert[k]
            if new < best - 1e-9 * max(1.0, best):
                best = new
                for k in range(n):
                    best_sets[k] = sets[k]
                    best_vert[k] = vert[k]
    for k in range(n):
        genes[k] = best_sets[k]
    return best

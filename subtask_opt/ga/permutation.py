"""Permutation chromosomes for the travelling-salesman problem of sequencing.

``data`` is the N x N travel-time matrix; a chromosome is a closed tour, a
permutation of 0..N-1. ``aux`` holds the operator parameters (see
:func:`make_aux`):

* ``aux[AUX_FALLBACK]`` - greedy-crossover fallback when both parents' next
  cities are used: 0 picks an unvisited city at random (the paper), 1 the
  nearest one;
* ``aux[AUX_GRASP]`` - share of restart individuals built by randomised
  nearest neighbour rather than by a double-bridge kick of the best tour;
* ``aux[AUX_MAX_SEGMENT]`` - longest run Or-opt moves;
* ``aux[AUX_NEIGHBOURS]`` = K, followed by the N x K table of each city's K
  nearest cities (row-major), used by the fast local search;
* ``aux[AUX_SEARCH]`` - how the operators search (a preset is a flag, not a
  chromosome type): :data:`SEARCH_PAPER` (the paper's micro-GA: random
  restarts, no local search), :data:`SEARCH_FAST` (kicked or GRASP restarts and
  children polished by neighbour-list 2-opt/Or-opt around what changed; for
  symmetric costs) or :data:`SEARCH_EXACT` (kicked restarts, full-sweep exact
  2-opt/Or-opt; any costs).

:func:`randomize`, :func:`crossover` and :func:`improve` are the operators the
GA dispatch registers; they branch on ``aux[AUX_SEARCH]``.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.np.random.random_methods import random_interval

FALLBACK_RANDOM = 0.0
FALLBACK_NEAREST = 1.0
SEARCH_PAPER = 0.0
SEARCH_FAST = 1.0
SEARCH_EXACT = 2.0
AUX_FALLBACK, AUX_GRASP, AUX_MAX_SEGMENT, AUX_NEIGHBOURS, AUX_SEARCH = range(5)
_AUX_TABLE = 5


def neighbour_table(matrix: np.ndarray, k: int | None = None) -> np.ndarray:
    """Each city's ``k`` nearest other cities (default: all), nearest first, by the cheaper
    of the two directions; ties go to the lower index (as a stable sort would).

    Only the ``k`` nearest are sorted (``argpartition``), so building the table costs
    O(N^2) plus O(N k log k) rather than a full O(N^2 log N) sort.
    """
    closeness = np.minimum(matrix, matrix.T).astype(float)
    np.fill_diagonal(closeness, np.inf)
    n = closeness.shape[0]
    k = n - 1 if k is None else max(1, min(int(k), n - 1))
    if k >= n - 1:
        return np.argsort(closeness, axis=1, kind="stable")[:, :-1]
    part = np.argpartition(closeness, k - 1, axis=1)[:, :k]
    values = np.take_along_axis(closeness, part, axis=1)
    order = np.lexsort((part, values), axis=1)  # by value, then index
    table = np.take_along_axis(part, order, axis=1)
    # a tie at the k-th value may have left out a lower index: redo those rows exactly
    kth = values.max(axis=1)
    ties = np.flatnonzero((closeness <= kth[:, None]).sum(axis=1) > k)
    for i in ties:
        table[i] = np.argsort(closeness[i], kind="stable")[:k]
    return table


def make_aux(table: np.ndarray, *, nearest_fallback: bool, grasp_share: float = 0.25,
             max_segment: int = 3, neighbours: int = 8,
             search: float = SEARCH_PAPER) -> np.ndarray:
    """Pack the operator parameters and the first ``neighbours`` columns of
    ``table`` (:func:`neighbour_table` of the matrix) into ``aux``."""
    k = max(1, min(neighbours, table.shape[1]))
    head = [FALLBACK_NEAREST if nearest_fallback else FALLBACK_RANDOM, grasp_share,
            float(max_segment), float(k), float(search)]
    return np.concatenate([np.array(head), table[:, :k].astype(float).ravel()])


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
    # rng.permutation(n), written out: the same Fisher-Yates draws as NumPy's
    # shuffle, without compiling numba's general n-d shuffle (seconds of JIT)
    for i in range(n):
        genes[i] = i
    for i in range(n - 1, 0, -1):
        j = np.int64(random_interval(rng.bit_generator, i))
        genes[i], genes[j] = genes[j], genes[i]
    return n


@njit(cache=True)
def nearest_neighbour_tour(genes, data, rng):
    """Randomised nearest-neighbour tour: random first city, then one of the
    two nearest unvisited cities at each step (a GRASP construction)."""
    n = data.shape[0]
    used = np.zeros(n, dtype=np.bool_)
    current = rng.integers(0, n)
    genes[0] = current
    used[current] = True
    for k in range(1, n):
        first = -1
        second = -1
        d1 = np.inf
        d2 = np.inf
        for c in range(n):
            if used[c]:
                continue
            d = data[current, c]
            if d < d1:
                second, d2 = first, d1
                first, d1 = c, d
            elif d < d2:
                second, d2 = c, d
        nxt = second if second >= 0 and rng.random() < 0.3 else first
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
    if best_len == 0 or rng.random() < aux[AUX_GRASP]:
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
    nearest = aux[AUX_FALLBACK] > 0.5
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
def _or_opt_pass(tour, n, data, fwd, bwd, scratch, max_seg):
    """One sweep of first-improvement segment insertion (Or-opt generalised).

    Moves a run of 1..max_seg consecutive cities between two other neighbours,
    either way round: two of the four pure 3-opt reconnections. Costs may be
    asymmetric. After a move the sweep goes on. True if anything moved.
    """
    eps = 1e-12
    moved = False
    for seg in range(1, max_seg + 1):
        for i in range(n):
            closing_f = data[tour[n - 1], tour[0]]
            closing_b = data[tour[0], tour[n - 1]]
            # the run is tour[i .. i+seg-1] (indices mod n); p before it, q after it
            end = i + seg - 1
            p = tour[(i - 1) % n]
            s0 = tour[i]
            s1 = tour[end % n]
            q = tour[(end + 1) % n]
            if end < n:
                inner_f = fwd[end] - fwd[i]
                inner_b = bwd[end] - bwd[i]
            else:  # the run wraps round the end of the array
                inner_f = fwd[n - 1] - fwd[i] + closing_f + fwd[end - n]
                inner_b = bwd[n - 1] - bwd[i] + closing_b + bwd[end - n]
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
                    _prefix_costs(tour, n, data, fwd, bwd)
                    moved = True
                    break  # the run at position i changed: go on with the next i
    return moved


@njit(cache=True)
def exact_local_search(genes, length, data, aux):
    """2-opt and Or-opt to a local optimum, full sweeps; costs may be asymmetric."""
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
        if _or_opt_pass(genes, n, data, fwd, bwd, scratch, min(int(aux[AUX_MAX_SEGMENT]), n - 3)):
            continue
        return n


# ---------------------------------------------------------------------------
# Fast local search for symmetric costs: neighbour lists + a queue of active
# cities (don't-look bits). Only moves that add an edge to one of a city's K
# nearest cities, shorter than the edge it removes, are tried.


@njit(cache=True)
def _reverse(tour, pos, n, i, j):
    """Reverse the cyclic run tour[i..j] (or its complement, same cycle)."""
    length = (j - i) % n + 1
    if 2 * length > n:  # reversing the complement gives the same cycle, cheaper
        i, j = (j + 1) % n, (i - 1) % n
        length = n - length
    for _ in range(length // 2):
        a, b = tour[i], tour[j]
        tour[i], tour[j] = b, a
        pos[b], pos[a] = i, j
        i = (i + 1) % n
        j = (j - 1) % n


@njit(cache=True)
def _move_run(tour, pos, n, i, seg, x_pos, reverse, scratch):
    """Move the run tour[i..i+seg-1] to just after position x_pos."""
    m = 0
    k = (i + seg) % n
    while True:
        scratch[m] = tour[k]
        m += 1
        if k == x_pos:
            break
        k = (k + 1) % n
    for t in range(seg):
        scratch[m] = tour[(i + (seg - 1 - t if reverse else t)) % n]
        m += 1
    k = (x_pos + 1) % n
    while m < n:
        scratch[m] = tour[k]
        m += 1
        k = (k + 1) % n
    for t in range(n):
        tour[t] = scratch[t]
        pos[scratch[t]] = t


@njit(cache=True)
def _push(queue, queued, tail, n, city):
    if not queued[city]:
        queued[city] = True
        queue[tail % n] = city
        tail += 1
    return tail


@njit(cache=True)
def local_search(genes, length, data, aux):
    """2-opt and Or-opt to a local optimum for symmetric costs (fast), all cities active."""
    return local_search_around(genes, length, data, aux, genes[:length].copy(), length)


@njit(cache=True)
def _two_opt_move(a, genes, pos, n, data, aux, k_nb, touched):
    """Apply the first improving 2-opt move that links ``a`` to one of its nearest
    cities; write the four cities it touched into ``touched`` and return 4 (0: none)."""
    eps = 1e-12
    for side in range(2):
        ia = pos[a]
        b = genes[(ia + 1) % n] if side == 0 else genes[(ia - 1) % n]
        d_ab = data[a, b]
        for t in range(k_nb):
            c = int(aux[_AUX_TABLE + a * k_nb + t])
            d_ac = data[a, c]
            if d_ac >= d_ab - eps:  # neighbours are sorted: no shorter new edge follows
                break
            ic = pos[c]
            d = genes[(ic + 1) % n] if side == 0 else genes[(ic - 1) % n]
            if c == b or d == a:
                continue
            if d_ac + data[b, d] - d_ab - data[c, d] < -eps:
                if side == 0:  # a b ... c d  ->  a c ... b d
                    _reverse(genes, pos, n, (ia + 1) % n, ic)
                else:  # d c ... b a  ->  d b ... c a
                    _reverse(genes, pos, n, ic, (ia - 1) % n)
                touched[0], touched[1], touched[2], touched[3] = a, b, c, d
                return 4
    return 0


@njit(cache=True)
def _or_opt_move(a, genes, pos, n, data, aux, k_nb, max_seg, scratch, touched):
    """Apply the first improving move of a run of 1..max_seg cities starting or
    ending at ``a`` next to one of the nearest cities of its end points (either
    way round); write the six cities it touched into ``touched`` and return 6 (0: none)."""
    eps = 1e-12
    for seg in range(1, max_seg + 1):
        for end in range(2):
            i = pos[a] if end == 0 else (pos[a] - seg + 1) % n
            s0 = genes[i]
            s1 = genes[(i + seg - 1) % n]
            p = genes[(i - 1) % n]
            q = genes[(i + seg) % n]
            removed = data[p, s0] + data[s1, q] - data[p, q]
            if removed <= eps:
                continue
            for which in range(2):
                s = s0 if which == 0 else s1
                for t in range(k_nb):
                    c = int(aux[_AUX_TABLE + s * k_nb + t])
                    if data[s, c] >= removed - eps:
                        break
                    ic = pos[c]
                    if (ic - i) % n < seg:  # c is inside the run
                        continue
                    for after in range(2):  # the edge after c, then the edge before it
                        x_pos = ic if after == 1 else (ic - 1) % n
                        if (x_pos - i) % n < seg or ((x_pos + 1) - i) % n < seg:
                            continue
                        x = genes[x_pos]
                        y = genes[(x_pos + 1) % n]
                        fwd = data[x, s0] + data[s1, y]
                        rev = data[x, s1] + data[s0, y]
                        if removed + data[x, y] - min(fwd, rev) > eps:
                            _move_run(genes, pos, n, i, seg, x_pos, rev < fwd, scratch)
                            touched[0], touched[1], touched[2] = p, q, s0
                            touched[3], touched[4], touched[5] = s1, x, y
                            return 6
    return 0


@njit(cache=True)
def local_search_around(genes, length, data, aux, active, n_active):
    """2-opt and Or-opt for symmetric costs, starting from the cities ``active[:n_active]``.

    A city whose moves all fail goes idle until a move changes one of its tour
    neighbours, so polishing a tour that changed in a few places costs little.
    """
    n = length
    if n < 5:
        return exact_local_search(genes, length, data, aux)
    k_nb = int(aux[AUX_NEIGHBOURS])
    max_seg = min(int(aux[AUX_MAX_SEGMENT]), n - 3)
    pos = np.empty(n, dtype=np.int64)
    for i in range(n):
        pos[genes[i]] = i
    queue = np.empty(n, dtype=np.int64)
    queued = np.zeros(n, dtype=np.bool_)
    scratch = np.empty(n, dtype=genes.dtype)
    touched = np.empty(6, dtype=np.int64)
    head = 0
    tail = 0
    for i in range(n_active):
        tail = _push(queue, queued, tail, n, active[i])
    # Every move lowers the cost when costs are symmetric; the budget only
    # guarantees termination if a caller breaks that contract.
    budget = 50 * n * n
    while head < tail and budget > 0:
        budget -= 1
        a = queue[head % n]
        head += 1
        queued[a] = False
        moved = _two_opt_move(a, genes, pos, n, data, aux, k_nb, touched)
        if moved == 0:
            moved = _or_opt_move(a, genes, pos, n, data, aux, k_nb, max_seg, scratch, touched)
        if moved > 0:
            for k in range(moved):
                tail = _push(queue, queued, tail, n, touched[k])
            tail = _push(queue, queued, tail, n, a)
    return n


@njit(cache=True)
def kicked_best_polished(genes, data, aux, rng, best, best_len):
    """:func:`kicked_best`, then local search around what changed.

    A nearest-neighbour tour is polished everywhere; a double-bridge kick only
    around the eight cities at its three junctions and the wrap-around.
    """
    n = kicked_best(genes, data, aux, rng, best, best_len)
    if best_len == 0 or n < 8 or not _differs(genes, best, n):
        return local_search(genes, n, data, aux)
    pos = np.empty(n, dtype=np.int64)
    for i in range(n):
        pos[best[i]] = i
    active = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):  # cities whose successor changed, and those successors
        a = genes[i]
        b = genes[(i + 1) % n]
        if best[(pos[a] + 1) % n] != b and best[(pos[b] + 1) % n] != a:
            active[m] = a
            active[m + 1] = b
            m += 2
            if m + 2 > n:
                break
    return local_search_around(genes, n, data, aux, active, m)


@njit(cache=True)
def _differs(a, b, n):
    for i in range(n):
        if a[i] != b[i]:
            return True
    return False


@njit(cache=True)
def greedy_crossover_polished(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """:func:`greedy_crossover`, then local search around the edges neither parent has."""
    n = greedy_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child)
    succ_a = np.empty(n, dtype=np.int64)
    succ_b = np.empty(n, dtype=np.int64)
    for i in range(n):
        succ_a[genes_a[i]] = genes_a[(i + 1) % n]
        succ_b[genes_b[i]] = genes_b[(i + 1) % n]
    active = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        u = child[i]
        v = child[(i + 1) % n]
        parental = (succ_a[u] == v or succ_a[v] == u or succ_b[u] == v or succ_b[v] == u)
        if not parental and m + 2 <= n:
            active[m] = u
            active[m + 1] = v
            m += 2
    if m == 0:
        return n
    return local_search_around(child, n, data, aux, active, m)


@njit(cache=True, inline="always")
def randomize(genes, data, aux, rng, best, best_len):
    """A new tour for the initial population or a restart, as ``aux[AUX_SEARCH]`` says."""
    search = aux[AUX_SEARCH]
    if search == SEARCH_FAST:
        return kicked_best_polished(genes, data, aux, rng, best, best_len)
    if search == SEARCH_EXACT:
        return kicked_best(genes, data, aux, rng, best, best_len)
    return random_tour(genes, data, aux, rng, best, best_len)


@njit(cache=True, inline="always")
def crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """Greedy crossover; polished around the new edges when searching fast."""
    if aux[AUX_SEARCH] == SEARCH_FAST:
        return greedy_crossover_polished(genes_a, len_a, genes_b, len_b, data, aux, rng, child)
    return greedy_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child)


@njit(cache=True, inline="always")
def improve(genes, length, data, aux):
    """The exact full-sweep local search when searching exactly; else nothing
    (the fast search polishes inside crossover and randomize)."""
    if aux[AUX_SEARCH] == SEARCH_EXACT:
        return exact_local_search(genes, length, data, aux)
    return length

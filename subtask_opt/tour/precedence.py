"""Pinned permutations: closed tours with a fixed first node, an optional fixed
last node and precedence pairs ``a`` before ``b`` (a GA chromosome kind).

Every operator keeps a chromosome feasible, so the GA never sees an
infeasible tour (:func:`tour_cost` still returns ``inf`` for one, as a guard):

* construction and crossover build the tour front to back from the nodes
  whose predecessors are all placed (Kahn's order): the crossover takes the
  cheaper of the two parents' successors of the current node when it is
  available, else the nearest available node (greedy crossover under
  precedence); the random construction picks at random or near-greedily;
* a restart perturbs the best tour (double bridge) and *repairs* it: Kahn's
  order taking, among the available nodes, the one earliest in the perturbed
  tour, which keeps the relative order wherever the constraints allow;
* the local search moves only where the constraints allow: Or-opt (a run of
  1 to :data:`MAX_SEGMENT` nodes moved forward no further than its first successor, backward no
  further than its last predecessor) and 2-opt (a reversed run may hold no
  constrained pair) and exchanges of two nodes, with exact asymmetric costs (reversals priced with
  prefix sums of both directions).

``data`` is the (N, N) cost matrix (asymmetric allowed; the return leg to the
first node is an ordinary leg, so open paths are zero-cost returns, see
:mod:`subtask_opt.tour.constraints`). ``aux`` is a :class:`PinnedAux` built by
:func:`make_pinned_aux`: the pins and the predecessor and successor lists in CSR form.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.ga.dispatch import OperatorSet

MAX_SEGMENT = 8
"""The longest run of nodes Or-opt moves (segment moves of this length cover the
orientation-keeping 3-opt moves that matter on asymmetric costs)."""


class PinnedAux(NamedTuple):
    """The constraints as the kernels read them."""

    first: int
    last: int
    pred_ptr: np.ndarray
    pred_idx: np.ndarray
    succ_ptr: np.ndarray
    succ_idx: np.ndarray


def make_pinned_aux(n: int, first: int, last: int, pairs: np.ndarray) -> PinnedAux:
    """The ``aux`` of this kind: the pins and the (P, 2) pairs ``a`` before ``b`` as CSR lists."""
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    pred_ptr, pred_idx = _csr(n, p[:, 1], p[:, 0])
    succ_ptr, succ_idx = _csr(n, p[:, 0], p[:, 1])
    return PinnedAux(int(first), int(last), pred_ptr, pred_idx, succ_ptr, succ_idx)


def _csr(n: int, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(rows, kind="stable")
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.add.at(ptr, rows + 1, 1)
    return np.cumsum(ptr), cols[order]


@njit(cache=True)
def feasible(genes, a):
    """Whether ``genes`` starts at the first pin, ends at the last and keeps every pair."""
    n = genes.shape[0]
    if genes[0] != a.first or (a.last >= 0 and genes[n - 1] != a.last):
        return False
    pos = np.empty(n, dtype=np.int64)
    for k in range(n):
        pos[genes[k]] = k
    for v in range(n):
        for q in range(a.succ_ptr[v], a.succ_ptr[v + 1]):
            if pos[v] > pos[a.succ_idx[q]]:
                return False
    return True


@njit(cache=True)
def tour_cost(genes, length, data, aux):
    """Closed-tour cost of ``genes``; ``inf`` if it breaks a pin or a pair."""
    a = aux
    if not feasible(genes[:length], a):
        return np.inf
    total = 0.0
    for k in range(length):
        total += data[genes[k], genes[(k + 1) % length]]
    return total


# --- construction -----------------------------------------------------------------

_RANDOM, _GREEDY, _CROSS, _REPAIR = 0, 1, 2, 3


@njit(cache=True)
def _build(out, data, a, rng, mode, pa, pb, priority):
    """Write a feasible tour into ``out``, front to back over the available nodes.

    ``mode``: random pick, near-greedy pick, greedy crossover of ``pa``/``pb``,
    or repair (the available node of least ``priority``).
    """
    n = out.shape[0]
    remaining = np.empty(n, dtype=np.int64)
    for v in range(n):
        remaining[v] = a.pred_ptr[v + 1] - a.pred_ptr[v]
    avail = np.empty(n, dtype=np.int64)
    where = np.full(n, -1, dtype=np.int64)
    count = 0
    for v in range(n):
        if remaining[v] == 0 and v != a.first and v != a.last:
            avail[count] = v
            where[v] = count
            count += 1
    pos_a = np.empty(n, dtype=np.int64)
    pos_b = np.empty(n, dtype=np.int64)
    if mode == _CROSS:
        for k in range(n):
            pos_a[pa[k]] = k
            pos_b[pb[k]] = k
    cur = a.first
    for step in range(n):
        if step == 0:
            nxt = a.first
        elif step == n - 1 and a.last >= 0:
            nxt = a.last
        else:
            nxt = -1
            if mode == _CROSS:
                ca = pa[(pos_a[cur] + 1) % n]
                cb = pb[(pos_b[cur] + 1) % n]
                ok_a = where[ca] >= 0
                ok_b = where[cb] >= 0
                if ok_a and ok_b:
                    nxt = ca if data[cur, ca] <= data[cur, cb] else cb
                elif ok_a:
                    nxt = ca
                elif ok_b:
                    nxt = cb
            if nxt < 0:
                if mode == _RANDOM:
                    nxt = avail[rng.integers(0, count)]
                elif mode == _REPAIR:
                    best = 0
                    for q in range(1, count):
                        if priority[avail[q]] < priority[avail[best]]:
                            best = q
                    nxt = avail[best]
                else:  # nearest (greedy and crossover fallback), near-greedy when _GREEDY
                    b1 = -1
                    b2 = -1
                    for q in range(count):
                        v = avail[q]
                        if b1 < 0 or data[cur, v] < data[cur, b1]:
                            b2 = b1
                            b1 = v
                        elif b2 < 0 or data[cur, v] < data[cur, b2]:
                            b2 = v
                    nxt = b1
                    if mode == _GREEDY and b2 >= 0 and rng.random() < 0.25:
                        nxt = b2
        out[step] = nxt
        if where[nxt] >= 0:  # take it out of the available list
            q = where[nxt]
            count -= 1
            avail[q] = avail[count]
            where[avail[q]] = q
            where[nxt] = -1
        for q in range(a.succ_ptr[nxt], a.succ_ptr[nxt + 1]):
            w = a.succ_idx[q]
            remaining[w] -= 1
            if remaining[w] == 0 and w != a.last and w != a.first:
                avail[count] = w
                where[w] = count
                count += 1
        cur = nxt


@njit(cache=True)
def repair(genes, aux):
    """In place: the feasible tour closest to ``genes`` in relative order (see module doc)."""
    a = aux
    n = genes.shape[0]
    priority = np.empty(n, dtype=np.int64)
    for k in range(n):
        priority[genes[k]] = k
    dummy = np.empty((1, 1))
    _build(genes, dummy, a, np.random.default_rng(0), _REPAIR, genes, genes, priority)


@njit(cache=True)
def randomize(genes, data, aux, rng, best, best_len):
    """A new feasible tour: random or near-greedy, or (restart) a repaired kick of ``best``."""
    a = aux
    n = data.shape[0]
    out = genes[:n]
    empty = np.empty(0, dtype=np.int64)
    if best_len > 0 and rng.random() < 0.34:
        out[:] = best[:n]
        hi = n - 1 if a.last < 0 else n - 2  # last movable position
        movable = hi  # positions 1..hi
        if movable >= 4:  # double bridge on the movable run: A B C D -> A C B D
            seg = out[1:hi + 1].copy()
            cuts = np.empty(3, dtype=np.int64)
            c = 0
            while c < 3:
                x = rng.integers(1, movable)
                fresh = True
                for q in range(c):
                    fresh = fresh and cuts[q] != x
                if fresh:
                    cuts[c] = x
                    c += 1
            cuts.sort()
            i, j, k = cuts[0], cuts[1], cuts[2]
            out[1:hi + 1] = np.concatenate((seg[:i], seg[j:k], seg[i:j], seg[k:]))
        elif movable >= 2:
            rng.shuffle(out[1:hi + 1])
        priority = np.empty(n, dtype=np.int64)
        for q in range(n):
            priority[out[q]] = q
        _build(out, data, a, rng, _REPAIR, empty, empty, priority)
        return n
    mode = _GREEDY if rng.random() < 0.34 else _RANDOM
    _build(out, data, a, rng, mode, empty, empty, empty)
    return n


@njit(cache=True)
def crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    """Greedy crossover under precedence (see the module doc); always feasible."""
    a = aux
    n = len_a
    _build(child[:n], data, a, rng, _CROSS, genes_a[:n], genes_b[:n], np.empty(0, np.int64))
    return n


@njit(cache=True)
def no_mutation(genes, length, data, aux, rng, strength):
    """The micro-GA has no mutation."""
    return length


# --- local search -----------------------------------------------------------------

@njit(cache=True)
def _prefix(t, data, fw, bw):
    n = t.shape[0]
    fw[0] = 0.0
    bw[0] = 0.0
    for k in range(n - 1):
        fw[k + 1] = fw[k] + data[t[k], t[k + 1]]
        bw[k + 1] = bw[k] + data[t[k + 1], t[k]]


@njit(cache=True)
def _better(new, old):
    return new < old - 1e-12 * (abs(old) + 1.0)


@njit(cache=True)
def _has_predecessor_from(a, pos, v, i):
    """True if a required predecessor of ``v`` sits at tour position ``i`` or later."""
    for q in range(a.pred_ptr[v], a.pred_ptr[v + 1]):
        if pos[a.pred_idx[q]] >= i:
            return True
    return False


@njit(cache=True)
def _two_opt(t, data, a, pos, fw, bw):
    """One pass of feasible reversals; True if any was applied."""
    n = t.shape[0]
    hi = n - 1 if a.last < 0 else n - 2
    changed = False
    for i in range(1, hi):
        j = i + 1
        while j <= hi:
            v = t[j]
            if _has_predecessor_from(a, pos, v, i):
                break  # a longer reversal holds the same pair
            prev = t[i - 1]
            nxt = t[(j + 1) % n]
            old = data[prev, t[i]] + (fw[j] - fw[i]) + data[t[j], nxt]
            new = data[prev, t[j]] + (bw[j] - bw[i]) + data[t[i], nxt]
            if _better(new, old):
                lo, up = i, j
                while lo < up:
                    t[lo], t[up] = t[up], t[lo]
                    lo += 1
                    up -= 1
                for k in range(i, j + 1):
                    pos[t[k]] = k
                _prefix(t, data, fw, bw)
                changed = True
            j += 1
    return changed


@njit(cache=True)
def _or_opt(t, data, a, pos, tmp):
    """One pass of feasible segment moves (kept in order); True if any was applied."""
    n = t.shape[0]
    hi = n - 1 if a.last < 0 else n - 2
    changed = False
    for length in range(1, min(MAX_SEGMENT, hi) + 1):
        i = 1
        while i + length - 1 <= hi:
            e = i + length - 1
            s0 = t[i]
            s1 = t[e]
            prev = t[i - 1]
            nxt = t[(e + 1) % n]
            gain = data[prev, s0] + data[s1, nxt] - data[prev, nxt]
            jmax = hi
            jmin = 0
            for k in range(i, e + 1):
                v = t[k]
                for q in range(a.succ_ptr[v], a.succ_ptr[v + 1]):
                    p = pos[a.succ_idx[q]]
                    if p > e and p - 1 < jmax:
                        jmax = p - 1
                for q in range(a.pred_ptr[v], a.pred_ptr[v + 1]):
                    p = pos[a.pred_idx[q]]
                    if p < i and p > jmin:
                        jmin = p
            best_j = -1
            best_delta = 0.0
            for j in range(jmin, i - 1):  # insert between t[j] and t[j + 1], before the run
                u = t[j]
                w = t[j + 1]
                delta = data[u, s0] + data[s1, w] - data[u, w] - gain
                if delta < best_delta:
                    best_delta = delta
                    best_j = j
            for j in range(e + 1, jmax + 1):  # after the run
                u = t[j]
                w = t[(j + 1) % n]
                delta = data[u, s0] + data[s1, w] - data[u, w] - gain
                if delta < best_delta:
                    best_delta = delta
                    best_j = j
            if best_j >= 0 and _better(gain + best_delta, gain):
                # the move rotates t[lo:hi_] so that t[mid:hi_] comes first
                if best_j < i:
                    lo, mid, hi_ = best_j + 1, i, e + 1
                else:
                    lo, mid, hi_ = i, e + 1, best_j + 1
                m = hi_ - lo
                tmp[:hi_ - mid] = t[mid:hi_]
                tmp[hi_ - mid:m] = t[lo:mid]
                for k in range(m):
                    t[lo + k] = tmp[k]
                    pos[tmp[k]] = lo + k
                changed = True
            i += 1
    return changed


@njit(cache=True)
def _swap(t, data, a, pos):
    """One pass of feasible exchanges of two nodes; True if any was applied."""
    n = t.shape[0]
    hi = n - 1 if a.last < 0 else n - 2
    changed = False
    for i in range(1, hi):
        x = t[i]
        jmax = hi  # x may not pass its first successor
        for q in range(a.succ_ptr[x], a.succ_ptr[x + 1]):
            p = pos[a.succ_idx[q]]
            if p > i and p < jmax + 1:
                jmax = p - 1
        for j in range(i + 1, jmax + 1):
            y = t[j]
            if _has_predecessor_from(a, pos, y, i):
                continue
            p = t[i - 1]
            nq = t[(j + 1) % n]
            if j == i + 1:
                old = data[p, x] + data[x, y] + data[y, nq]
                new = data[p, y] + data[y, x] + data[x, nq]
            else:
                u = t[i + 1]
                b = t[j - 1]
                old = data[p, x] + data[x, u] + data[b, y] + data[y, nq]
                new = data[p, y] + data[y, u] + data[b, x] + data[x, nq]
            if _better(new, old):
                t[i] = y
                t[j] = x
                pos[y] = i
                pos[x] = j
                changed = True
                break
    return changed


@njit(cache=True)
def local_search(genes, length, data, aux):
    """2-opt, Or-opt and node exchanges under the pins and the pairs until none improves."""
    a = aux
    t = genes[:length]
    n = length
    pos = np.empty(n, dtype=np.int64)
    for k in range(n):
        pos[t[k]] = k
    fw = np.empty(n)
    bw = np.empty(n)
    tmp = np.empty(n, dtype=np.int64)
    for _ in range(10 * n + 100):
        _prefix(t, data, fw, bw)
        moved = _two_opt(t, data, a, pos, fw, bw)
        moved = _or_opt(t, data, a, pos, tmp) or moved
        moved = _swap(t, data, a, pos) or moved
        if not moved:
            break
    return length


@njit(cache=True)
def improve(genes, length, data, aux):
    """The local search (the GA's improve operator)."""
    return local_search(genes, length, data, aux)


OPERATORS = OperatorSet(randomize, tour_cost, crossover, no_mutation, improve)
"""The pinned permutation kind's operators (registered by :mod:`subtask_opt.chromosomes`)."""

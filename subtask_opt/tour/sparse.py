"""Generalised TSP on candidate legs: order and configuration together, no M x M matrix.

The clustered search of :mod:`subtask_opt.tour.clustered` reads an (M, M) matrix of
leg times between every two configurations; at thousands of targets with dozens of
configurations each that matrix does not fit (2,000 x 64 configurations: 130 GB).
Here each target keeps only its *candidate* neighbour targets, and the leg times of
each candidate pair are one (K_a, K_b) block; memory is linear in targets x
configurations x candidates.

:class:`SparseLegs` (robot-free): target ``a`` owns configurations
``offsets[a] .. offsets[a + 1] - 1``; ``nbr[a, s]`` is its s-th candidate target (-1:
a free slot), whose block of leg times starts at ``legs[start[a, s]]`` (row-major,
a's configurations the rows); ``home`` (M,) the leg between the home and each
configuration (legs are symmetric: the same either way). A leg between two targets
that are not candidates of each other costs ``penalty`` (more than any tour of
stored legs) plus the targets' distance (``coords``): the search needs as few as it
can and keeps those it needs short, and when its answer holds one the caller
adds the pair's block (``LazyLegsProblem.extend``, "the legs the search asks
for") and searches again.

:func:`search` is an iterated local search, seeded: nearest-neighbour construction
over the candidates, then rounds of (1) the exact configurations of the order (the
layered shortest path of :func:`decode`), (2) 2-opt moves between candidate
neighbours with the configurations fixed, until neither improves; then local
double-bridge kicks, each polished the same way and kept when the tour gets shorter.
No Or-opt pass: relocations that choose the moved target's configuration cost about
15 times the CPU at 2,000 holes for 0.1-0.3% shorter tours.

:func:`one_tree_bound` is a Held-Karp (1-tree, subgradient) lower bound on a complete
graph of which only some edges are known exactly: every other pair (a, b) must cost
at least ``(rho[a] + rho[b]) / 2``. It is valid for the complete graph (a 1-tree on
the candidate edges alone is not): see its docstring.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError


class SparseLegs(NamedTuple):
    """Candidate leg blocks of a clustered tour with a home (module doc).

    Attributes:
        offsets: (N + 1,) int64, configurations of target a: offsets[a]..offsets[a+1]-1.
        nbr: (N, S) int64 candidate targets of each target, -1 for a free slot.
        start: (N, S) int64 start of each candidate's (K_a, K_b) block in ``legs``.
        legs: (L,) float64 leg times of every block.
        home: (M,) float64 time between the home and each configuration.
        coords: (N, d) float64 target coordinates (the construction's fallback when
            every candidate of a target is visited: the nearest unvisited by these; the
            length of a jump between targets that are not candidates).
        penalty: the time of a leg not stored, plus its jump's length (more than any
            tour of stored legs).
    """

    offsets: np.ndarray
    nbr: np.ndarray
    start: np.ndarray
    legs: np.ndarray
    home: np.ndarray
    coords: np.ndarray
    penalty: float

    @property
    def size(self) -> int:
        return int(self.offsets.shape[0] - 1)

    def nbytes(self) -> int:
        """Bytes held by the arrays."""
        return int(sum(a.nbytes for a in (self.offsets, self.nbr, self.start, self.legs,
                                          self.home, self.coords)))


# ---------------------------------------------------------------- leg look-up


@njit(cache=True)
def _slot(data, a, b):
    """Index of b among a's candidates, -1 when it is not one."""
    out = -1
    row = data.nbr[a]
    for s in range(row.shape[0]):
        if row[s] == b:
            out = s
            break
    return out


@njit(cache=True)
def _missing(data, a, b):
    """Time the search gives a leg between targets a and b that is not stored: the penalty
    plus their distance (``coords``), so that of tours with as many such legs the search
    keeps the one whose jumps are shortest: their true legs, added afterwards, are then
    short too (with the penalty alone it keeps any, and a jump across a 2,000-hole panel
    stays in the tour)."""
    d = 0.0
    for j in range(data.coords.shape[1]):
        x = data.coords[a, j] - data.coords[b, j]
        d += x * x
    return data.penalty + math.sqrt(d)


@njit(cache=True)
def leg(data, a, ca, b, cb):
    """Time from configuration ca (index within target a) to cb of target b; a or b equal
    to N is the home (its configuration index ignored)."""
    n = data.offsets.shape[0] - 1
    off = data.offsets
    out = 0.0  # the home to itself
    if a == n and b < n:
        out = data.home[off[b] + cb]
    elif b == n and a < n:
        out = data.home[off[a] + ca]
    elif a < n:
        s = _slot(data, a, b)
        if s >= 0:
            kb = off[b + 1] - off[b]
            out = data.legs[data.start[a, s] + ca * kb + cb]
        else:
            out = _missing(data, a, b)
    return out


@njit(cache=True)
def decode(tour, data, choice):
    """Exact configurations of ``tour`` (home, targets..., home; home = N): the layered
    shortest path, O(N K^2). Writes the choice (index within each target) and returns
    the tour time."""
    n = data.offsets.shape[0] - 1
    off = data.offsets
    kmax = 1
    for i in range(n):
        kmax = max(kmax, off[i + 1] - off[i])
    length = tour.shape[0] - 2
    pred = np.zeros((length, kmax), dtype=np.int64)
    cost = np.empty(kmax)
    new = np.empty(kmax)
    first = tour[1]
    for c in range(off[first + 1] - off[first]):
        cost[c] = data.home[off[first] + c]
    for k in range(1, length):
        a = tour[k]
        b = tour[k + 1]
        ka = off[a + 1] - off[a]
        kb = off[b + 1] - off[b]
        s = _slot(data, a, b)
        jump = _missing(data, a, b) if s < 0 else 0.0
        for cb in range(kb):
            best = np.inf
            arg = 0
            for ca in range(ka):
                if s >= 0:
                    v = cost[ca] + data.legs[data.start[a, s] + ca * kb + cb]
                else:
                    v = cost[ca] + jump
                if v < best:
                    best = v
                    arg = ca
            new[cb] = best
            pred[k, cb] = arg
        for cb in range(kb):
            cost[cb] = new[cb]
    last = tour[length]
    total = np.inf
    c_last = 0
    for c in range(off[last + 1] - off[last]):
        v = cost[c] + data.home[off[last] + c]
        if v < total:
            total = v
            c_last = c
    c = c_last
    for k in range(length, 1, -1):
        choice[tour[k]] = c
        c = pred[k - 1, c]
    choice[tour[1]] = c
    return total


@njit(cache=True)
def tour_time(tour, data, choice):
    """Time of ``tour`` with the configurations ``choice`` fixed."""
    total = 0.0
    for k in range(tour.shape[0] - 1):
        a = tour[k]
        b = tour[k + 1]
        total += leg(data, a, choice[a] if a < choice.shape[0] else 0, b,
                     choice[b] if b < choice.shape[0] else 0)
    return total


# ---------------------------------------------------------------- construction


@njit(cache=True)
def _nearest_neighbour(data, first):
    """Home, then from each target its cheapest unvisited candidate (block minimum), or
    the nearest unvisited target by coordinates when every candidate is visited."""
    n = data.offsets.shape[0] - 1
    off = data.offsets
    tour = np.empty(n + 2, dtype=np.int64)
    seen = np.zeros(n, dtype=np.bool_)
    tour[0] = n
    tour[n + 1] = n
    cur = first
    for k in range(1, n + 1):
        tour[k] = cur
        seen[cur] = True
        if k == n:
            break
        best = np.inf
        nxt = -1
        row = data.nbr[cur]
        for s in range(row.shape[0]):
            b = row[s]
            if b < 0 or seen[b]:
                continue
            size = (off[cur + 1] - off[cur]) * (off[b + 1] - off[b])
            m = np.inf
            for t in range(data.start[cur, s], data.start[cur, s] + size):
                if data.legs[t] < m:
                    m = data.legs[t]
            if m < best:
                best = m
                nxt = b
        if nxt < 0:
            bd = np.inf
            for b in range(n):
                if not seen[b]:
                    d = 0.0
                    for j in range(data.coords.shape[1]):
                        x = data.coords[b, j] - data.coords[cur, j]
                        d += x * x
                    if d < bd:
                        bd = d
                        nxt = b
        cur = nxt
    return tour


# ---------------------------------------------------------------- local search


@njit(cache=True)
def _c(data, choice, u, v):
    n = choice.shape[0]
    return leg(data, u, choice[u] if u < n else 0, v, choice[v] if v < n else 0)


@njit(cache=True, inline="always")
def _reverse(tour, pos, i, j):
    """Reverse tour[i..j] (inclusive), keeping ``pos`` (position of each node) in step."""
    while i < j:
        a = tour[i]
        b = tour[j]
        tour[i] = b
        tour[j] = a
        pos[b] = i
        pos[a] = j
        i += 1
        j -= 1


@njit(cache=True)
def _two_opt(tour, pos, data, choice, active):
    """First-improvement 2-opt over candidate neighbours (symmetric legs), the
    configurations fixed; ``active`` marks the targets to look from. Returns the gain."""
    n = data.offsets.shape[0] - 1
    gain = 0.0
    improved = True
    while improved:
        improved = False
        for t1 in range(n):
            if not active[t1]:
                continue
            found = False
            for direction in range(2):
                i = pos[t1]
                t2 = tour[i + 1] if direction == 0 else tour[i - 1]
                d12 = _c(data, choice, t1, t2)
                row = data.nbr[t1]
                for s in range(row.shape[0]):
                    t3 = row[s]
                    if t3 < 0 or t3 == t2:
                        continue
                    d13 = _c(data, choice, t1, t3)
                    if d13 >= d12:
                        continue
                    j = pos[t3]
                    t4 = tour[j + 1] if direction == 0 else tour[j - 1]
                    if t4 == t1:
                        continue
                    d34 = _c(data, choice, t3, t4)
                    delta = d13 + _c(data, choice, t2, t4) - d12 - d34
                    # a relative tolerance: with penalty legs (~1e5 s) a rounding error
                    # would otherwise pass for a gain and the moves could cycle
                    if delta < -1e-9 * (1.0 + d12 + d34):
                        if direction == 0:  # t1 t2 ... t3 t4 -> t1 t3 ... t2 t4
                            if i < j:
                                _reverse(tour, pos, i + 1, j)
                            else:
                                _reverse(tour, pos, j + 1, i)
                        else:  # t2 t1 ... t4 t3 -> t3 t1 ... (reversed)
                            if i < j:
                                _reverse(tour, pos, i, j - 1)
                            else:
                                _reverse(tour, pos, j, i - 1)
                        gain -= delta
                        improved = True
                        found = True
                        for x in (t2, t3, t4):
                            if x < n:
                                active[x] = True
                        break
                if found:
                    break
            if not found:
                active[t1] = False
    return gain


def _polish(tour: np.ndarray, pos: np.ndarray, data: SparseLegs, choice: np.ndarray,
            active: np.ndarray) -> float:
    """Decode and 2-opt until neither improves; returns the tour time. (Driven from
    Python: a kernel that calls the move kernels links and re-optimises all of them,
    which took numba many minutes to compile; the calls cost microseconds.)"""
    cost = float(decode(tour, data, choice))
    while True:
        _two_opt(tour, pos, data, choice, active)
        new = float(decode(tour, data, choice))
        if new >= cost - 1e-12:
            cost = min(cost, new)
            break
        cost = new
        active[:] = True
    return cost


@njit(cache=True)
def _kick_at(tour, pos, rng, lo, w, active):
    """A random change of tour positions lo .. lo+w-1 (the home ends kept): at three
    distinct cut points a < b < c in lo .. lo+w, a double bridge (A B C D -> A C B D)
    or, half the time, B C reversed; the moved targets become active."""
    if w >= 2:
        cuts = np.zeros(3, dtype=np.int64)
        got = 0
        while got < 3:
            x = rng.integers(0, w + 1)
            fresh = True
            for t in range(got):
                if cuts[t] == x:
                    fresh = False
            if fresh:
                cuts[got] = x
                got += 1
        cuts = np.sort(cuts)
        a = lo + cuts[0]
        b = lo + cuts[1]
        c = lo + cuts[2]
        seg = tour[a:c].copy()
        if rng.random() < 0.5:
            for t in range(c - a):
                tour[a + t] = seg[c - a - 1 - t]
        else:
            k = a
            for t in range(b - a, c - a):
                tour[k] = seg[t]
                k += 1
            for t in range(0, b - a):
                tour[k] = seg[t]
                k += 1
        for t in range(a, c):
            pos[tour[t]] = t
            active[tour[t]] = True


@njit(cache=True)
def _decode_window(tour, data, choice, i, j):
    """Best configurations of tour positions i+1 .. j-1, those at i and j kept (the home
    at 0 and n + 1): the layered shortest path of that stretch. Applied when shorter;
    returns the time saved (0 or more)."""
    off = data.offsets
    n = off.shape[0] - 1
    i = max(i, 0)
    j = min(j, n + 1)
    if j - i < 2:
        return 0.0
    old = 0.0
    for k in range(i, j):
        old += _c(data, choice, tour[k], tour[k + 1])
    kmax = 1
    for k in range(i + 1, j):
        t = tour[k]
        kmax = max(kmax, off[t + 1] - off[t])
    span = j - i - 1
    pred = np.zeros((span, kmax), dtype=np.int64)
    cost = np.empty(kmax)
    new = np.empty(kmax)
    a = tour[i]
    first = tour[i + 1]
    for c in range(off[first + 1] - off[first]):
        cost[c] = leg(data, a, choice[a] if a < n else 0, first, c)
    for k in range(1, span):
        u = tour[i + k]
        v = tour[i + k + 1]
        ku = off[u + 1] - off[u]
        kv = off[v + 1] - off[v]
        s = _slot(data, u, v)
        jump = _missing(data, u, v) if s < 0 else 0.0
        for cv in range(kv):
            best = np.inf
            arg = 0
            for cu in range(ku):
                if s >= 0:
                    x = cost[cu] + data.legs[data.start[u, s] + cu * kv + cv]
                else:
                    x = cost[cu] + jump
                if x < best:
                    best = x
                    arg = cu
            new[cv] = best
            pred[k, cv] = arg
        for cv in range(kv):
            cost[cv] = new[cv]
    last = tour[j - 1]
    b = tour[j]
    total = np.inf
    c_last = 0
    for c in range(off[last + 1] - off[last]):
        x = cost[c] + leg(data, last, c, b, choice[b] if b < n else 0)
        if x < total:
            total = x
            c_last = c
    saved = 0.0
    if total < old - 1e-9 * (1.0 + old):  # relative: penalty legs are ~1e5 s
        saved = old - total
        c = c_last
        for k in range(span - 1, 0, -1):
            choice[tour[i + 1 + k]] = c
            c = pred[k, c]
        choice[tour[i + 1]] = c
    return saved


@njit(cache=True)
def _stretch(tour, data, choice, i, j):
    """Time of tour positions i .. j (legs i -> i+1, ..., j-1 -> j)."""
    out = 0.0
    for k in range(i, j):
        out += _c(data, choice, tour[k], tour[k + 1])
    return out


DECODE_MARGIN = 8
"""Positions either side of a kick's window that its local decode re-chooses."""
WALK_SLACK = 0.002
"""Up to :data:`SLACK_TARGETS` targets, a kicked tour replaces the walk's current one when
shorter or when at most a random share in [0, WALK_SLACK) longer than the best (the walk
leaves a local optimum); above, only when shorter. Without it a cluttered 8-hole cell
(``tests/cell/test_cells.py``, three quarters of its legs in collision) ended at a tour
without its detours, 4% longer. On long tours a kick changes a few legs, so a share of the
whole tour's time lets the walk drift far from its best: 0.002 at every size left the
2,000-hole panel (20 kicks per target, three seeds) 0.6-0.7% longer than none, the
5,000-hole one 1.0%; a share shrinking as 50 / N was 0.5% shorter at 2,000 holes but 0.7%
longer at 5,000 and 0.6-4% longer on RoboTSP's subsets (one seed each)."""
SLACK_TARGETS = 16
"""Most targets for which the walk takes :data:`WALK_SLACK`."""


def _walk(tour: np.ndarray, data: SparseLegs, choice: np.ndarray,
          rng: np.random.Generator, kicks: int, window: int, cost: float | None = None,
          ) -> tuple[float, int]:
    """Polish ``tour`` (in place, with ``choice``), then ``kicks`` kicked restarts, the
    best kept; returns (time, kicks that improved). A kick's trial is evaluated locally
    (O(window) per kick, not O(N)): the kick's own change, the configurations around it
    re-chosen (:func:`_decode_window`), then the exact gains of the 2-opt moves
    (configurations fixed) and of re-choosing the configurations again, until none
    improves; the whole tour is decoded again at the end. The walk moves to a trial that
    is shorter than its current tour or within a random share of the best
    (:data:`WALK_SLACK`, :data:`SLACK_TARGETS`)."""
    n = data.size
    pos = np.empty(n + 1, dtype=np.int64)
    pos[tour[1:n + 1]] = np.arange(1, n + 1)
    pos[n] = 0
    active = np.ones(n, dtype=np.bool_)
    # a full polish is O(N): only when the tour's time is not known (the first call)
    best = _polish(tour, pos, data, choice, active) if cost is None else cost
    wins = 0
    cur, cpos, cchoice = tour.copy(), pos.copy(), choice.copy()
    current = best
    trial, tpos, tchoice = tour.copy(), pos.copy(), choice.copy()
    active[:] = False
    w = min(window, n)
    slack = WALK_SLACK if n <= SLACK_TARGETS else 0.0
    for _ in range(kicks):
        trial[:] = cur
        tpos[:] = cpos
        tchoice[:] = cchoice
        lo = 1 + int(rng.integers(0, n - w + 1))
        before = _stretch(trial, data, tchoice, lo - 1, lo + w)
        _kick_at(trial, tpos, rng, lo, w, active)
        value = current - before + _stretch(trial, data, tchoice, lo - 1, lo + w)
        # configurations first, so the fixed-configuration moves do not just undo the kick
        value -= _decode_window(trial, data, tchoice, lo - 1 - DECODE_MARGIN,
                                lo + w + DECODE_MARGIN)
        while True:
            g = _two_opt(trial, tpos, data, tchoice, active)
            g += _decode_window(trial, data, tchoice, lo - 1 - DECODE_MARGIN,
                                lo + w + DECODE_MARGIN)
            value -= g
            if g <= 1e-9 * (1.0 + value):
                break
        active[:] = False
        if value < current - 1e-9 or value < best * (1.0 + slack * rng.random()):
            current = value
            cur[:] = trial
            cpos[:] = tpos
            cchoice[:] = tchoice
            if value < best - 1e-9:
                best = value
                tour[:] = trial
                pos[:] = tpos
                choice[:] = tchoice
                wins += 1
    return best, wins


# ---------------------------------------------------------------- Python side


class SearchOutcome(NamedTuple):
    """What :func:`search` found: ``tour`` home (N), targets..., home; ``choice`` the
    configuration index within each target; ``cost`` its time; ``kicks`` made."""

    tour: np.ndarray
    choice: np.ndarray
    cost: float
    kicks: int
    improved: int


KICK_WINDOW = 30
"""Positions a kick's double bridge spans (local kicks keep the candidate legs)."""


def search(data: SparseLegs, *, seed: int, kicks: int, tour: np.ndarray | None = None,
           choice: np.ndarray | None = None, chunk: int = 200,
           should_stop: Any = None, on_chunk: Any = None) -> SearchOutcome:
    """Iterated local search on :class:`SparseLegs` (module doc), seeded.

    Args:
        seed: seed of ``np.random.default_rng`` (the kicks); same seed, same answer.
        kicks: most kicked restarts after the first polish.
        tour, choice: a start (default: nearest neighbour from the target whose cheapest
            home leg is smallest).
        chunk: kicks between checks (at least N / 4): ``should_stop()`` (True ends the
            search) and ``on_chunk(kicks done, best time)`` are called.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
            0 <= seed < 2**63):
        raise ParameterError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    if isinstance(kicks, bool) or not isinstance(kicks, (int, np.integer)) or kicks < 0:
        raise ParameterError(f"kicks must be an integer >= 0, got {kicks!r}")
    n = data.size
    rng = np.random.default_rng(seed)
    if tour is None:
        first = int(np.argmin(np.minimum.reduceat(data.home, data.offsets[:-1])))
        tour = _nearest_neighbour(data, first)
    tour = np.ascontiguousarray(tour, dtype=np.int64).copy()
    if tour.shape != (n + 2,) or tour[0] != n or tour[-1] != n or not np.array_equal(
            np.sort(tour[1:-1]), np.arange(n)):
        raise ParameterError("tour must be home (N), a permutation of the targets, home")
    choice = (np.zeros(n, dtype=np.int64) if choice is None
              else np.ascontiguousarray(choice, dtype=np.int64).copy())
    done = improved = 0
    cost, wins = _walk(tour, data, choice, rng, 0, KICK_WINDOW)
    chunk = max(chunk, n // 4)  # a chunk's own cost is O(N): keep their number O(kicks / N)
    while done < kicks:
        if should_stop is not None and should_stop():
            break
        step = min(chunk, kicks - done)
        cost, wins = _walk(tour, data, choice, rng, step, KICK_WINDOW, cost)
        done += step
        improved += wins
        if on_chunk is not None:
            on_chunk(done, float(cost))
    if done:  # a last full polish (the kicks were judged locally)
        pos = np.empty(n + 1, dtype=np.int64)
        pos[tour[1:n + 1]] = np.arange(1, n + 1)
        pos[n] = 0
        cost = _polish(tour, pos, data, choice, np.ones(n, dtype=np.bool_))
    return SearchOutcome(tour, choice, float(cost), done, improved)


# ---------------------------------------------------------------- lower bound


@njit(cache=True)
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True)
def _one_tree(n, ea, eb, w, rho, home_w, pi, degree):
    """Value of the 1-tree of the node weights ``pi`` (module doc, :func:`one_tree_bound`);
    the degrees of its nodes into ``degree`` (node n the home)."""
    best_s = 0
    best = np.inf
    for a in range(n):
        v = 0.5 * rho[a] + pi[a]
        if v < best:
            best = v
            best_s = a
    m = ea.shape[0]
    cand_w = np.empty(m + n)
    cand_a = np.empty(m + n, dtype=np.int64)
    cand_b = np.empty(m + n, dtype=np.int64)
    for e in range(m):
        a = ea[e]
        b = eb[e]
        cand_w[e] = w[e] + pi[a] + pi[b]
        cand_a[e] = a
        cand_b[e] = b
    k = m
    for a in range(n):
        if a != best_s:
            cand_w[k] = 0.5 * (rho[a] + rho[best_s]) + pi[a] + pi[best_s]
            cand_a[k] = a
            cand_b[k] = best_s
            k += 1
    order = np.argsort(cand_w[:k])
    parent = np.arange(n)
    degree[:] = 0
    total = 0.0
    used = 0
    for t in range(k):
        e = order[t]
        ra = _find(parent, cand_a[e])
        rb = _find(parent, cand_b[e])
        if ra != rb:
            parent[ra] = rb
            total += cand_w[e]
            degree[cand_a[e]] += 1
            degree[cand_b[e]] += 1
            used += 1
            if used == n - 1:
                break
    # the home's two cheapest edges
    m1 = np.inf
    m2 = np.inf
    i1 = -1
    i2 = -1
    for a in range(n):
        v = home_w[a] + pi[a]
        if v < m1:
            m2 = m1
            i2 = i1
            m1 = v
            i1 = a
        elif v < m2:
            m2 = v
            i2 = a
    total += m1 + m2
    degree[i1] += 1
    degree[i2] += 1
    degree[n] = 2
    s = 0.0
    for a in range(n):
        s += pi[a]
    return total - 2.0 * s


@njit(cache=True)
def _ascent(n, ea, eb, w, rho, home_w, upper, iterations, patience, momentum, lam, pi):
    """Held-Karp subgradient ascent from the node weights ``pi`` (changed in place): a
    Polyak step ``lam (upper - value) / |d|^2`` along the subgradient with momentum,
    ``lam`` halved after ``patience`` steps without a better value. Returns the best
    value and the weights that gave it."""
    direction = np.zeros(n)
    degree = np.zeros(n + 1, dtype=np.int64)
    best = -np.inf
    best_pi = pi.copy()
    stall = 0
    for _ in range(iterations):
        value = _one_tree(n, ea, eb, w, rho, home_w, pi, degree)
        if value > best + 1e-12 * abs(value):
            best = value
            best_pi[:] = pi
            stall = 0
        else:
            stall += 1
            if stall >= patience:
                lam *= 0.5
                stall = 0
                if lam < 1e-6:
                    break
        norm = 0.0
        for a in range(n):
            direction[a] = (degree[a] - 2) + momentum * direction[a]
            norm += direction[a] * direction[a]
        if norm == 0:
            break
        step = lam * (upper - value) / norm
        for a in range(n):
            pi[a] += step * direction[a]
    return best, best_pi


def _cheapest_edges(n: int, edges: np.ndarray, weights: np.ndarray, k: int) -> np.ndarray:
    """Mask of the edges among the ``k`` cheapest of either of their nodes."""
    m = edges.shape[0]
    node = np.concatenate([edges[:, 0], edges[:, 1]])
    edge = np.concatenate([np.arange(m), np.arange(m)])
    by = np.lexsort((np.concatenate([weights, weights]), node))  # by node, then weight
    sorted_node = node[by]
    rank = np.arange(2 * m) - np.searchsorted(sorted_node, sorted_node)
    keep = np.zeros(m, dtype=bool)
    keep[edge[by[rank < k]]] = True
    return keep


BOUND_ITERATIONS = 3000
"""Subgradient steps of :func:`one_tree_bound` on the cheap edges (its first phase)."""
BOUND_POLISH = 100
"""Subgradient steps on every edge after them (the second phase)."""
ASCENT_EDGES = 8
"""Each node's cheapest edges the first phase of :func:`one_tree_bound` steers by."""
ASCENT_STEP = 0.1
"""First Polyak step factor of the ascent (short: the tour's time it aims at is several
percent above the bound's limit), with momentum :data:`ASCENT_MOMENTUM`, halved after
:data:`ASCENT_PATIENCE` steps without a better value; the second phase starts at a tenth
of it and a third of the patience."""
ASCENT_MOMENTUM = 0.5
ASCENT_PATIENCE = 60


def one_tree_bound(n: int, edges: np.ndarray, weights: np.ndarray, rho: np.ndarray,
                   home: np.ndarray, *, upper: float,
                   iterations: int = BOUND_ITERATIONS) -> float:
    """A lower bound on every closed tour home -> all n targets -> home.

    Inputs: ``edges`` (E, 2) target pairs whose cost is at most their cheapest leg
    (``weights`` (E,)); ``rho`` (n,) with every other pair (a, b) costing at least
    ``(rho[a] + rho[b]) / 2``; ``home`` (n,) at most the cheapest leg between the home
    and each target. ``upper``: a tour's time (the subgradient's step size).

    Why it is valid: for given node weights ``pi`` let ``s`` be the target of least
    ``sigma = rho / 2 + pi``, and give every pair of targets the weight w(a, b) =
    ``weights`` when it is an edge, (rho[a] + rho[b]) / 2 otherwise, except that a pair
    with s takes the smaller of the two; each home leg ``home``. No weight exceeds the
    pair's cheapest leg, so every tour costs at least its weight, which is at least the
    Held-Karp 1-tree value ``L(pi) = min 1-tree(w + pi_a + pi_b) - 2 sum pi`` (every
    tour is a 1-tree with degree 2 everywhere). The minimum spanning tree of that
    complete graph is found without its n^2 edges: a non-edge (a, b) away from s weighs
    ``sigma_a + sigma_b``, at least ``sigma_a + sigma_s`` and ``sigma_s + sigma_b``,
    which bound the weights of (a, s) and (s, b); it is the heaviest edge of the cycle
    a-s-b-a, so by the cycle property a minimum spanning tree lies within the edges and
    the star around s (Kruskal on both). ``rho`` may be +inf where a target has no
    other pair.

    The ascent has two phases: ``iterations`` steps over each target's
    :data:`ASCENT_EDGES` cheapest edges only (an order of magnitude fewer: the good
    weights ``pi`` of a 1-tree are found among short edges), then :data:`BOUND_POLISH`
    steps over every edge from the best ``pi``. Only values of the second phase, whose
    1-trees see every edge, are returned: the first phase only steers ``pi``.
    """
    e = np.ascontiguousarray(edges, dtype=np.int64).reshape(-1, 2)
    w = np.ascontiguousarray(weights, dtype=np.float64)
    r = np.ascontiguousarray(rho, dtype=np.float64)
    h = np.ascontiguousarray(home, dtype=np.float64)
    if w.shape != (e.shape[0],) or r.shape != (n,) or h.shape != (n,):
        raise ParameterError(f"one_tree_bound: {e.shape[0]} edges need as many weights and "
                             f"{n} rho and home values, got {w.shape}, {r.shape}, {h.shape}")
    if n < 2:
        return float(2 * h.min()) if n == 1 else 0.0
    if not (math.isfinite(upper) and upper > 0):
        raise ParameterError(f"one_tree_bound: upper must be a finite time > 0, got {upper!r}")
    pi = np.zeros(n)
    steps, lam, patience = int(iterations), ASCENT_STEP, ASCENT_PATIENCE
    if e.shape[0] > ASCENT_EDGES * n:
        few = _cheapest_edges(n, e, w, ASCENT_EDGES)
        _, pi = _ascent(n, e[few, 0].copy(), e[few, 1].copy(), w[few].copy(), r, h,
                        float(upper), steps, patience, ASCENT_MOMENTUM, lam, pi)
        steps, lam, patience = BOUND_POLISH, lam / 10, patience // 3
    # else few edges already: every step over all of them
    best, _ = _ascent(n, e[:, 0].copy(), e[:, 1].copy(), w, r, h, float(upper), steps,
                      patience, ASCENT_MOMENTUM, lam, pi)
    return float(best)


__all__ = ["ASCENT_EDGES", "ASCENT_MOMENTUM", "ASCENT_PATIENCE", "ASCENT_STEP",
           "BOUND_ITERATIONS", "BOUND_POLISH", "DECODE_MARGIN", "KICK_WINDOW", "SearchOutcome",
           "SLACK_TARGETS", "SparseLegs", "WALK_SLACK", "decode", "one_tree_bound", "search",
           "tour_time"]

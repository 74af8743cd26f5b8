"""Exact travelling-salesman solvers: oracles that certify the GA's answers.

* :func:`held_karp` - dynamic programming, O(2^N N^2), for N <= 16; pure
  numpy/Python, no extra dependency.
* :func:`milp_optimum` - integer program over the edges of a symmetric matrix
  with degree constraints and subtour-elimination cuts added until the
  solution is one tour (Dantzig-Fulkerson-Johnson), solved by HiGHS
  (``highspy``, in the ``dev`` and ``bench`` extras). Certifies 20- and
  30-subtask instances in well under a second.
* :func:`optimal_tours` - every optimal tour, by the same MILP with a no-good
  cut after each one found.
* :func:`held_karp_pinned` and :func:`milp_pinned` - the same two methods for
  tours with a pinned start, an optional pinned end and precedence pairs
  (asymmetric costs welcome); :func:`exact_constrained` applies them to a matrix
  problem with :class:`~subtask_opt.tour.constraints.TourConstraints`.
* :func:`gtsp_optimum` - the generalised TSP (one node of each cluster: an
  arm's subtasks, each reachable in several elbow configurations) by branch and
  cut with HiGHS; certifies the joint time model's 30- to 60-subtask optima.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError, SubtaskOptError, require_int
from subtask_opt.base.files import quiet_stdout

if TYPE_CHECKING:
    from subtask_opt.tour.constraints import TourConstraints


def _square_matrix(matrix: np.ndarray) -> np.ndarray:
    try:
        m = np.asarray(matrix, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"need a square matrix of numbers, got "
                             f"{type(matrix).__name__}") from None
    if m.ndim != 2 or m.shape[0] != m.shape[1] or m.shape[0] < 3:
        raise ParameterError(f"need a square matrix of at least 3 x 3, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ParameterError("matrix entries must be finite")
    return m


def tour_length(matrix: np.ndarray, order: np.ndarray) -> float:
    """Cost of the closed tour ``order`` over ``matrix``."""
    order = np.asarray(order, dtype=int)
    return float(np.sum(np.asarray(matrix)[order, np.roll(order, -1)]))


def held_karp(matrix: np.ndarray) -> tuple[float, np.ndarray]:
    """Exact minimum closed tour by dynamic programming (N <= 16), starting at 0.

    Returns ``(cost, order)``. Works for asymmetric matrices.
    """
    m = _square_matrix(matrix)
    n = m.shape[0]
    if n > 16:
        raise ParameterError(f"held_karp is for at most 16 subtasks, got {n}")
    size = 1 << (n - 1)
    cost = np.full((size, n - 1), math.inf)
    parent = np.full((size, n - 1), -1, dtype=np.int64)
    for j in range(n - 1):
        cost[1 << j, j] = m[0, j + 1]
    for subset in range(1, size):
        members = [j for j in range(n - 1) if (subset >> j) & 1]
        for j in members:
            c = cost[subset, j]
            if c == math.inf:
                continue
            for k in range(n - 1):
                if (subset >> k) & 1:
                    continue
                nxt = subset | (1 << k)
                value = c + m[j + 1, k + 1]
                if value < cost[nxt, k]:
                    cost[nxt, k] = value
                    parent[nxt, k] = j
    full = size - 1
    closing = cost[full] + m[1:, 0]
    last = int(np.argmin(closing))
    best = float(closing[last])
    order = [last + 1]
    subset = full
    while parent[subset, last] >= 0:
        prev = int(parent[subset, last])
        subset ^= 1 << last
        last = prev
        order.append(last + 1)
    return best, np.array([0] + order[::-1], dtype=np.int64)


def milp_optimum(matrix: np.ndarray, *, max_rounds: int = 200,
                 time_limit: float | None = None) -> tuple[float, np.ndarray]:
    """Certified minimum closed tour of a symmetric matrix by MILP with subtour cuts.

    Returns ``(cost, order)`` with ``order`` starting at 0. Raises
    :class:`SubtaskOptError` if HiGHS does not prove optimality (within
    ``time_limit`` seconds in all, when given). Nothing is printed.
    """
    deadline = None if time_limit is None else time.perf_counter() + float(time_limit)
    model = _TspModel(_square_matrix(matrix))
    order = model.solve(max_rounds, deadline, time_limit)
    return tour_length(model.m, order), order


@dataclass(frozen=True)
class OptimalTours:
    """Every optimal closed tour of a symmetric matrix (:func:`optimal_tours`).

    Attributes:
        cost: the optimal cost.
        tours: the optimal tours, each starting at 0 and listed once (a tour and
            its reverse are the same tour); in the order the MILP found them.
        next_cost: the cost of the best tour that is not in ``tours`` (``inf``
            when there is none): strictly above ``cost``, the proof that the
            list is complete.
    """

    cost: float
    tours: tuple[np.ndarray, ...]
    next_cost: float


def optimal_tours(matrix: np.ndarray, *, rtol: float = 1e-9, max_tours: int = 1000,
                  max_rounds: int = 200, exclude: Sequence[np.ndarray] = ()) -> OptimalTours:
    """All optimal closed tours of a symmetric matrix, by repeated MILP with no-good cuts.

    After each optimal tour T is found, the cut "at most N - 1 of T's N edges"
    excludes T (both directions: the edges are undirected) and nothing else, and
    the MILP is solved again; the enumeration ends at the first tour costlier than
    the optimum by more than ``rtol`` (relative). Raises :class:`SubtaskOptError`
    when more than ``max_tours`` optima exist. The tours in ``exclude`` are cut
    off from the start (the optima of the other tours are returned).
    """
    require_int("optimal_tours", "max_tours", max_tours, 1)
    if not (isinstance(rtol, (int, float)) and 0.0 <= rtol < 1.0):
        raise ParameterError(f"optimal_tours.rtol must be in [0, 1), got {rtol!r}")
    model = _TspModel(_square_matrix(matrix))
    model.h.setOptionValue("mip_abs_gap", 0.0)  # each re-solve must be exactly the best left
    n = model.m.shape[0]
    for tour in exclude:
        t = np.asarray(tour, dtype=np.int64)
        if sorted(t.tolist()) != list(range(n)):
            raise ParameterError(f"optimal_tours.exclude: {tour!r} is not a tour of 0..{n - 1}")
        model.exclude(t, n)
    tours: list[np.ndarray] = []
    best = math.inf
    while True:
        try:
            order = model.solve(max_rounds, None, None)
        except _Infeasible:  # every tour is excluded (tiny instances)
            return OptimalTours(best, tuple(tours), math.inf)
        cost = tour_length(model.m, order)
        if not tours:
            best = cost
        elif cost > best + rtol * abs(best):
            return OptimalTours(best, tuple(tours), cost)
        if len(tours) == max_tours:
            raise SubtaskOptError(f"optimal_tours: more than max_tours={max_tours} optima")
        tours.append(order)
        model.exclude(order, n)


class _Infeasible(SubtaskOptError):
    """The model has no tour left."""


class _TspModel:
    """The edge MILP of a symmetric TSP in HiGHS: degree rows; cuts added as needed."""

    def __init__(self, m: np.ndarray) -> None:
        if not np.allclose(m, m.T, rtol=1e-9, atol=1e-12):
            raise ParameterError("milp_optimum needs a symmetric matrix")
        try:
            import highspy
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise SubtaskOptError(
                "milp_optimum needs highspy: pip install 'subtask_opt[bench]'") from exc
        self.highspy = highspy
        self.m = m
        n = m.shape[0]
        self.iu, self.ju = np.triu_indices(n, 1)
        n_edges = len(self.iu)
        with quiet_stdout():  # HiGHS prints its banner on construction
            h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        h.setOptionValue("mip_rel_gap", 0.0)
        h.addCols(n_edges, m[self.iu, self.ju], np.zeros(n_edges), np.ones(n_edges), 0,
                  np.array([], dtype=np.int32), np.array([], dtype=np.int32), np.array([]))
        h.changeColsIntegrality(n_edges, np.arange(n_edges, dtype=np.int32),
                                np.full(n_edges, highspy.HighsVarType.kInteger))
        self.edge_index: dict[tuple[int, int], int] = {}
        for e, (i, j) in enumerate(zip(self.iu.tolist(), self.ju.tolist(), strict=True)):
            self.edge_index[(i, j)] = e
        for v in range(n):  # every city has degree 2
            idx = np.array([self.edge_index[(min(v, u), max(v, u))] for u in range(n) if u != v],
                           dtype=np.int32)
            h.addRow(2.0, 2.0, len(idx), idx, np.ones(len(idx)))
        self.h = h

    def solve(self, max_rounds: int, deadline: float | None,
              time_limit: float | None) -> np.ndarray:
        """The optimal tour of the model (subtour cuts added until it is one tour)."""
        highspy, h, iu, ju = self.highspy, self.h, self.iu, self.ju
        n = self.m.shape[0]
        for _ in range(max_rounds):
            status = _run_highs(h, deadline, f"milp_optimum: not proven within {time_limit} s")
            if status == highspy.HighsModelStatus.kInfeasible:
                raise _Infeasible("no tour satisfies the cuts")
            if status != highspy.HighsModelStatus.kOptimal:
                raise SubtaskOptError(
                    f"HiGHS did not solve the TSP: {h.modelStatusToString(status)}")
            x = np.asarray(h.getSolution().col_value) > 0.5
            components = _components(n, iu[x], ju[x])
            if len(components) == 1:
                return _walk(n, iu[x], ju[x])
            for comp in components:  # at most |S| - 1 edges inside any proper subset S
                inside = set(comp)
                idx = np.array([e for e, (i, j) in enumerate(zip(iu, ju, strict=True))
                                if i in inside and j in inside], dtype=np.int32)
                h.addRow(-highspy.kHighsInf, len(comp) - 1.0, len(idx), idx, np.ones(len(idx)))
        raise SubtaskOptError(f"milp_optimum: no single tour after {max_rounds} rounds of cuts")

    def exclude(self, order: np.ndarray, n: int) -> None:
        """The no-good cut: at most n - 1 of the tour's n (undirected) edges."""
        idx = np.array([self.edge_index[(min(a, b), max(a, b))]
                        for a, b in zip(order.tolist(), np.roll(order, -1).tolist(),
                                        strict=True)], dtype=np.int32)
        self.h.addRow(-self.highspy.kHighsInf, n - 1.0, n, idx, np.ones(n))


def _run_highs(h: Any, deadline: float | None, late: str) -> Any:
    """Run the HiGHS model ``h`` in the time left before ``deadline`` (perf_counter
    seconds; None: no limit) and return its model status; raise ``late`` (a
    :class:`SubtaskOptError` message) when no time is left."""
    if deadline is not None:
        left = deadline - time.perf_counter()
        if left <= 0:
            raise SubtaskOptError(late)
        h.setOptionValue("time_limit", left)
    h.run()
    return h.getModelStatus()


def _components(n: int, a: np.ndarray, b: np.ndarray) -> list[list[int]]:
    parent = list(range(n))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for i, j in zip(a, b, strict=True):
        parent[find(int(i))] = find(int(j))
    groups: dict[int, list[int]] = {}
    for v in range(n):
        groups.setdefault(find(v), []).append(v)
    return list(groups.values())


def _walk(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    neighbours: list[list[int]] = [[] for _ in range(n)]
    for i, j in zip(a, b, strict=True):
        neighbours[int(i)].append(int(j))
        neighbours[int(j)].append(int(i))
    order = [0]
    prev, cur = -1, 0
    for _ in range(n - 1):
        nxt = neighbours[cur][0] if neighbours[cur][0] != prev else neighbours[cur][1]
        order.append(nxt)
        prev, cur = cur, nxt
    return np.array(order, dtype=np.int64)


# --- tours with a pinned start, an optional pinned end and precedence pairs ---------------
#
# These work on the canonical form of :mod:`subtask_opt.tour.constraints`: a closed tour
# over a (possibly asymmetric) matrix starting at ``first``, ending at ``last`` (-1: any
# node) and placing ``a`` before ``b`` for every pair. An open path is a closed tour whose
# return leg costs nothing; :func:`exact_constrained` does that transform for you.

HELD_KARP_PINNED_MAX = 13
"""The most nodes :func:`held_karp_pinned` accepts (2^12 subsets x 12 x 12 steps)."""


def _pinned_inputs(matrix: np.ndarray, first: int, last: int,
                   pairs: np.ndarray | Sequence[tuple[int, int]]) -> tuple[np.ndarray, np.ndarray]:
    m = _square_matrix(matrix)
    n = m.shape[0]
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not 0 <= first < n or not -1 <= last < n or last == first:
        raise ParameterError(f"first={first} and last={last} must be distinct nodes in "
                             f"0..{n - 1} (last -1: free)")
    if p.size and (p.min() < 0 or p.max() >= n):
        raise ParameterError(f"precedence pairs must name nodes in 0..{n - 1}")
    return m, p


def held_karp_pinned(matrix: np.ndarray, first: int = 0, last: int = -1,
                     pairs: np.ndarray | Sequence[tuple[int, int]] = (),
                     ) -> tuple[float, np.ndarray]:
    """Exact minimum closed tour from ``first`` (ending at ``last`` if >= 0) keeping the pairs.

    Dynamic programming over (set of visited nodes, last node): a node may join
    a set only when all its predecessors are in it, and ``last`` only as the
    final node. O(2^N N^2) time; N <= :data:`HELD_KARP_PINNED_MAX`. Returns
    ``(cost, tour)`` with ``tour[0] == first``; ``(inf, empty)`` if no tour
    keeps every pair (a cycle).
    """
    m, p = _pinned_inputs(matrix, first, last, pairs)
    n = m.shape[0]
    if n > HELD_KARP_PINNED_MAX:
        raise ParameterError(f"held_karp_pinned is for at most {HELD_KARP_PINNED_MAX} nodes, "
                             f"got {n}")
    others = [v for v in range(n) if v != first]
    bit = {v: i for i, v in enumerate(others)}
    r = n - 1
    need = [0] * r  # bit mask of the predecessors of others[i] (first is always placed)
    for a, b in p.tolist():
        if b == first:
            return math.inf, np.empty(0, dtype=np.int64)
        if a != first:
            need[bit[b]] |= 1 << bit[a]
    full = (1 << r) - 1
    lastbit = -1 if last < 0 else bit[last]
    cost = np.full((1 << r, r), math.inf)
    parent = np.full((1 << r, r), -1, dtype=np.int64)
    for k in range(r):
        if need[k] == 0 and (k != lastbit or r == 1):
            cost[1 << k, k] = m[first, others[k]]
    for subset in range(1, full + 1):
        row = cost[subset]
        for j in range(r):
            c = row[j]
            if c == math.inf:
                continue
            src = others[j]
            for k in range(r):
                if (subset >> k) & 1 or need[k] & ~subset:
                    continue
                nxt = subset | (1 << k)
                if k == lastbit and nxt != full:
                    continue
                value = c + m[src, others[k]]
                if value < cost[nxt, k]:
                    cost[nxt, k] = value
                    parent[nxt, k] = j
    closing = cost[full] + m[others, first]
    end = int(np.argmin(closing))
    best = float(closing[end])
    if best == math.inf:
        return math.inf, np.empty(0, dtype=np.int64)
    order = [others[end]]
    subset = full
    j = end
    while parent[subset, j] >= 0:
        prev = int(parent[subset, j])
        subset ^= 1 << j
        j = prev
        order.append(others[j])
    return best, np.array([first] + order[::-1], dtype=np.int64)


def milp_pinned(matrix: np.ndarray, first: int = 0, last: int = -1,
                pairs: np.ndarray | Sequence[tuple[int, int]] = (), *,
                time_limit: float | None = None) -> tuple[float, np.ndarray]:
    """Certified minimum closed tour from ``first`` (to ``last``) keeping the pairs, by MILP.

    Asymmetric formulation: binary arcs ``x_ij`` with in- and out-degree one,
    and Miller-Tucker-Zemlin positions ``u_i`` in [1, N-1] for the nodes other
    than ``first`` (``u_j >= u_i + 1`` on a used arc, which forbids subtours;
    lifted as Desrochers and Laporte do); a pair ``(a, b)`` is ``u_a + 1 <= u_b``,
    a pinned end fixes the arc ``last -> first``. The transitive closure of the
    pairs tightens it: a node's position lies between its number of ancestors
    and N - 1 minus its number of descendants, and arcs against the closure (or
    skipping a node that must lie between) are fixed to zero. Solved by HiGHS
    with a zero gap; nothing is printed.
    Raises :class:`SubtaskOptError` if optimality is not proven (within
    ``time_limit`` seconds) or no tour keeps the pairs.
    """
    m, p = _pinned_inputs(matrix, first, last, pairs)
    try:
        import highspy
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SubtaskOptError("milp_pinned needs highspy") from exc
    n = m.shape[0]
    for a, b in p.tolist():
        if b == first:
            raise SubtaskOptError(f"no tour keeps the pair ({a}, {b}): {b} is the start")
    before = _precedence_closure(n, first, last, p)
    if np.any(np.diag(before)):
        raise SubtaskOptError("no tour keeps the pairs: they form a cycle")
    ancestors = before.sum(axis=0)  # first counts: it precedes everyone
    descendants = before.sum(axis=1)
    between = (before.astype(np.int64) @ before.astype(np.int64)) > 0  # a < c < b for some c
    arcs = [(i, j) for i in range(n) for j in range(n) if i != j]
    arc = {a: k for k, a in enumerate(arcs)}
    n_arcs = len(arcs)
    others = [v for v in range(n) if v != first]
    u = {v: n_arcs + k for k, v in enumerate(others)}
    with quiet_stdout():
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("mip_rel_gap", 0.0)
    if time_limit is not None:
        h.setOptionValue("time_limit", float(time_limit))
    inf = highspy.kHighsInf
    lower = np.zeros(n_arcs)
    upper = np.ones(n_arcs)
    for k, (i, j) in enumerate(arcs):
        if (j != first and before[j, i]) or between[i, j] or (
                j == first and descendants[i] > 0) or (
                i == first and ancestors[j] > 1):
            upper[k] = 0.0  # against the order, or skipping a node that lies between
    if last >= 0:
        lower[arc[(last, first)]] = 1.0
    empty_i = np.array([], dtype=np.int32)
    h.addCols(n_arcs, np.array([m[i, j] for i, j in arcs]), lower, upper, 0, empty_i, empty_i,
              np.array([]))
    h.changeColsIntegrality(n_arcs, np.arange(n_arcs, dtype=np.int32),
                            np.full(n_arcs, highspy.HighsVarType.kInteger))
    u_low = np.array([float(ancestors[v]) for v in others])  # first is one ancestor
    u_high = np.array([n - 1.0 - descendants[v] for v in others])
    h.addCols(n - 1, np.zeros(n - 1), u_low, u_high, 0, empty_i, empty_i, np.array([]))
    for v in range(n):
        out = np.array([arc[(v, w)] for w in range(n) if w != v], dtype=np.int32)
        into = np.array([arc[(w, v)] for w in range(n) if w != v], dtype=np.int32)
        h.addRow(1.0, 1.0, n - 1, out, np.ones(n - 1))
        h.addRow(1.0, 1.0, n - 1, into, np.ones(n - 1))
    for i in others:
        for j in others:
            if i != j:  # u_i - u_j + (n - 1) x_ij + (n - 3) x_ji <= n - 2
                h.addRow(-inf, n - 2.0, 4,
                         np.array([u[i], u[j], arc[(i, j)], arc[(j, i)]], dtype=np.int32),
                         np.array([1.0, -1.0, n - 1.0, n - 3.0]))
    for a, b in p.tolist():
        if a != first:
            h.addRow(-inf, -1.0, 2, np.array([u[a], u[b]], dtype=np.int32),
                     np.array([1.0, -1.0]))
    h.run()
    status = h.getModelStatus()
    if status != highspy.HighsModelStatus.kOptimal:
        raise SubtaskOptError(f"HiGHS did not prove an optimal tour: "
                              f"{h.modelStatusToString(status)}")
    x = np.asarray(h.getSolution().col_value)[:n_arcs] > 0.5
    succ = {arcs[k][0]: arcs[k][1] for k in np.flatnonzero(x)}
    order = [first]
    while len(order) < n:
        order.append(succ[order[-1]])
    tour = np.array(order, dtype=np.int64)
    return tour_length(m, tour), tour


def _precedence_closure(n: int, first: int, last: int, pairs: np.ndarray) -> np.ndarray:
    """``before[a, b]``: a must come before b (the pairs, the pins, transitively)."""
    before = np.zeros((n, n), dtype=bool)
    before[first, :] = True
    before[first, first] = False
    if last >= 0:
        before[:, last] = True
        before[last, last] = False
    for a, b in pairs.tolist():
        before[a, b] = True
    for k in range(n):  # Warshall
        before |= before[:, k:k + 1] & before[k:k + 1, :]
    return before


def exact_constrained(matrix: np.ndarray, constraints: TourConstraints, *,
                      method: str = "held_karp", default_start: int = 0,
                      time_limit: float | None = None) -> tuple[float, np.ndarray]:
    """The optimum of a matrix problem under ``constraints``, in the user's terms.

    Returns ``(total, order)``: ``order`` without the home, ``total`` without the
    free return leg of an open path. ``method``: ``"held_karp"`` (N <= 13) or
    ``"milp"``.
    """
    from subtask_opt.tour.constraints import canonical

    if method not in ("held_karp", "milp"):
        raise ParameterError(f"method must be 'held_karp' or 'milp', got {method!r}")
    m = _square_matrix(matrix)
    constraints.check_size(m.shape[0], matrix_home=True)
    canon = canonical(m, constraints, default_start=default_start)
    if method == "held_karp":
        cost, tour = held_karp_pinned(canon.matrix, canon.first, canon.last, canon.pairs)
    else:
        cost, tour = milp_pinned(canon.matrix, canon.first, canon.last, canon.pairs,
                                 time_limit=time_limit)
    if tour.size == 0:
        raise SubtaskOptError("no tour keeps every constraint")
    return float(np.sum(canon.user_legs(m, tour))), canon.user_order(tour)


# --- the generalised TSP: one configuration per subtask ------------------------------------


@njit(cache=True)
def _pair_cuts(w: np.ndarray, y: np.ndarray, start: np.ndarray, tol: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The violated generalised cut constraints of the LP point ``(w, y)``.

    Nodes are grouped by cluster: cluster k is nodes ``start[k]:start[k + 1]``.
    For each pair of clusters i < j, the least of x(delta(S)) + 2 y(C_i - S)
    + 2 y(C_j & S) over node sets S is a minimum s-t cut (s joined to C_i by arcs
    2 y, C_j joined to t), found by augmenting paths over the support of ``w``,
    stopped once the flow reaches 2. Returns the pairs (i, j) whose minimum is
    below 2 - ``tol``, the minimum, and the source side S of each.
    """
    m = w.shape[0]
    n = start.shape[0] - 1
    s, t = m, m + 1
    degree = np.zeros(m, dtype=np.int64)
    for u in range(m):
        for v in range(m):
            if w[u, v] > 1e-12:
                degree[u] += 1
    first = np.zeros(m + 1, dtype=np.int64)
    first[1:] = np.cumsum(degree)
    adj = np.empty(first[m], dtype=np.int64)
    for u in range(m):
        k = first[u]
        for v in range(m):
            if w[u, v] > 1e-12:
                adj[k] = v
                k += 1
    r = np.zeros((m + 2, m + 2))  # residual capacities
    r[:m, :m] = w
    pred = np.empty(m + 2, dtype=np.int64)
    queue = np.empty(m + 2, dtype=np.int64)
    path = np.empty(m + 2, dtype=np.int64)
    size = n * (n - 1) // 2
    pairs = np.empty((size, 2), dtype=np.int64)
    values = np.empty(size)
    sides = np.zeros((size, m), dtype=np.bool_)
    found = 0
    for i in range(n):
        for j in range(i + 1, n):
            for u in range(start[i], start[i + 1]):
                r[s, u] = 2.0 * y[u]
                r[u, s] = 0.0
            for u in range(start[j], start[j + 1]):
                r[u, t] = 2.0 * y[u]
                r[t, u] = 0.0
            flow = 0.0
            while flow < 2.0 - tol:
                pred[:] = -1
                pred[s] = s
                head, tail = 0, 0
                for u in range(start[i], start[i + 1]):
                    if r[s, u] > 1e-12:
                        pred[u] = s
                        queue[tail] = u
                        tail += 1
                while head < tail and pred[t] < 0:
                    u = queue[head]
                    head += 1
                    if r[u, t] > 1e-12:
                        pred[t] = u
                        break
                    for k in range(first[u], first[u + 1]):
                        v = adj[k]
                        if pred[v] < 0 and r[u, v] > 1e-12:
                            pred[v] = u
                            queue[tail] = v
                            tail += 1
                if pred[t] < 0:
                    break
                push = np.inf
                length = 0
                v = t
                while v != s:
                    push = min(push, r[pred[v], v])
                    path[length] = v
                    length += 1
                    v = pred[v]
                for k in range(length):
                    v = path[k]
                    r[pred[v], v] -= push
                    r[v, pred[v]] += push
                flow += push
            if flow < 2.0 - tol:  # the last search found no path: its reach is S
                pairs[found, 0] = i
                pairs[found, 1] = j
                values[found] = flow
                for u in range(m):
                    sides[found, u] = pred[u] >= 0
                found += 1
            for u in range(m):  # restore the residual capacities of the support
                for k in range(first[u], first[u + 1]):
                    r[u, adj[k]] = w[u, adj[k]]
            for u in range(start[i], start[i + 1]):
                r[s, u] = 0.0
                r[u, s] = 0.0
            for u in range(start[j], start[j + 1]):
                r[u, t] = 0.0
                r[t, u] = 0.0
    return pairs[:found], values[:found], sides[:found]


CLUSTERED_HELD_KARP_MAX = 12
"""Most clusters :func:`clustered_held_karp` takes (its table has 2**N x M entries)."""


def clustered_held_karp(legs: np.ndarray, offsets: np.ndarray, start: np.ndarray,
                        back: np.ndarray | None, *, pairs: np.ndarray | None = None,
                        last: int = -1) -> float:
    """Exact minimum of a tour from a start node through one node of every cluster.

    Held and Karp's dynamic programme over (clusters visited, node last visited): the
    path starts at a start node outside the clusters (a robot's home), visits one node of
    each of the N clusters (``offsets``: cluster i owns nodes offsets[i]..offsets[i+1]-1
    of ``legs``), and returns to the start (``back``, the (M,) costs node -> start) or,
    ``back=None``, ends at its last node (an open path; ``last`` >= 0 fixes its cluster).
    ``pairs`` (P, 2): cluster a before cluster b.

    Args:
        legs: (M, M) costs between nodes.
        start: (M,) costs start -> node.

    Raises:
        ParameterError: more than :data:`CLUSTERED_HELD_KARP_MAX` clusters, or shapes
            that do not fit.
    """
    off = np.asarray(offsets, dtype=np.int64)
    n = off.size - 1
    m = int(off[-1])
    c = np.asarray(legs, dtype=float)
    if not 1 <= n <= CLUSTERED_HELD_KARP_MAX:
        raise ParameterError(f"clustered_held_karp takes 1..{CLUSTERED_HELD_KARP_MAX} "
                             f"clusters, got {n}")
    if c.shape != (m, m) or np.shape(start) != (m,) or (back is not None
                                                        and np.shape(back) != (m,)):
        raise ParameterError(f"clustered_held_karp: legs must be ({m}, {m}) and start/back "
                             f"({m},)")
    need = np.zeros(n, dtype=np.int64)  # bit mask of the clusters each cluster waits for
    for a, b in np.asarray(pairs if pairs is not None else [], dtype=np.int64).reshape(-1, 2):
        need[b] |= 1 << int(a)
    owner = np.repeat(np.arange(n), np.diff(off))
    best = np.full((1 << n, m), np.inf)
    for t in range(n):
        if need[t] == 0:
            best[1 << t, off[t]:off[t + 1]] = np.asarray(start, dtype=float)[off[t]:off[t + 1]]
    for subset in range(1, 1 << n):
        row = best[subset]
        if not np.isfinite(row).any():
            continue
        inside = ((subset >> owner) & 1).astype(bool)
        here = np.where(inside, row, np.inf)
        for t in range(n):
            if subset >> t & 1 or need[t] & ~subset:
                continue
            block = slice(off[t], off[t + 1])
            reach = np.min(here[:, None] + c[:, block], axis=0)
            target = best[subset | 1 << t, block]
            np.minimum(target, reach, out=target)
    full = best[(1 << n) - 1]
    if back is not None:
        return float(np.min(full + np.asarray(back, dtype=float)))
    if last >= 0:
        return float(np.min(full[off[last]:off[last + 1]]))
    return float(np.min(full))


def gtsp_optimum(cost: np.ndarray, clusters: np.ndarray | Sequence[int], *,
                 incumbent: np.ndarray | Sequence[int] | None = None,
                 time_limit: float | None = None,
                 max_rounds: int = 500) -> tuple[float, np.ndarray, np.ndarray]:
    """Certified minimum closed tour visiting one node of every cluster, by branch and cut.

    ``cost`` is a symmetric M x M matrix over nodes (an arm's subtask
    configurations), ``clusters[v]`` the cluster of node v (0..n-1, each used,
    n >= 3). Binary ``x_e`` per edge between nodes of different clusters and
    ``y_v`` per node: one node per cluster, degree 2 y_v at each. On the LP
    relaxation, rounds of generalised cut constraints (after Fischetti, Salazar
    and Toth): for any node set S and clusters i != j,
    x(delta(S)) >= 2 (y(S & C_i) + y(C_j - S) - 1), all violated ones found
    exactly by a minimum cut per pair of clusters. They close most of the gap of
    the LP with cluster subtour cuts only (which can split every cluster in halves
    and walk all M nodes at x = 1/2). Then HiGHS branches; an ``incumbent`` (a
    tour as node indices, one per cluster, e.g. the GA's answer) lets it prune
    from the start and fixes to 0 every column whose reduced cost exceeds the gap.
    Cluster subtours of an integer answer are cut off and it is solved again.

    Returns ``(cost, order, nodes)``: ``order`` the clusters from cluster 0,
    ``nodes[k]`` the node visited at ``order[k]``. Raises
    :class:`SubtaskOptError` if optimality is not proven within ``time_limit``
    seconds (or ``max_rounds`` rounds of cuts). Nothing is printed.
    """
    c = _square_matrix(cost)
    if not np.allclose(c, c.T, rtol=1e-9, atol=1e-12):
        raise ParameterError("gtsp_optimum needs a symmetric cost matrix")
    cl, n = _cluster_labels(clusters, c.shape[0])
    require_int("gtsp_optimum", "max_rounds", max_rounds, 1)
    if time_limit is not None and not (isinstance(time_limit, (int, float))
                                       and time_limit > 0):
        raise ParameterError(f"gtsp_optimum.time_limit must be > 0 s, got {time_limit!r}")
    model = _GtspModel(c, cl.astype(np.int64))
    if incumbent is not None:
        model.set_incumbent(np.asarray(incumbent, dtype=np.int64))
    deadline = None if time_limit is None else time.perf_counter() + float(time_limit)
    model.root_cuts(max_rounds, deadline)
    tour = model.branch(max_rounds, deadline)
    return float(c[tour, np.roll(tour, -1)].sum()), cl[tour], tour


def gtsp_lp_bound(cost: np.ndarray, clusters: np.ndarray | Sequence[int], *,
                  time_limit: float | None = None, max_rounds: int = 500) -> float:
    """A lower bound of the symmetric generalised TSP: the LP relaxation of
    :func:`gtsp_optimum`'s model (one node per cluster, degree 2 y_v) after as many rounds
    of cluster subtour cuts and generalised cut constraints as ``time_limit`` seconds
    allow. Every round's LP optimum is a valid bound (the cuts hold for every tour), and
    the rounds only raise it; the last one solved is returned. Much tighter than the
    bound of the cheapest arcs between clusters when clusters overlap (GTSPLIB's 11eil51:
    174, the optimum, where Held-Karp on those arcs gives 98).

    Raises:
        SubtaskOptError: not even the first LP was solved within ``time_limit``.
    """
    c = _square_matrix(cost)
    if not np.allclose(c, c.T, rtol=1e-9, atol=1e-12):
        raise ParameterError("gtsp_lp_bound needs a symmetric cost matrix")
    cl, n = _cluster_labels(clusters, c.shape[0])
    deadline = None if time_limit is None else time.perf_counter() + float(time_limit)
    model = _GtspModel(c, cl.astype(np.int64))
    try:
        model.root_cuts(max_rounds, deadline, bound_only=True)
    except SubtaskOptError:
        pass  # out of time or rounds: the last LP solved still bounds every tour
    bound = model.best_lp_bound
    if not math.isfinite(bound):
        raise SubtaskOptError("gtsp_lp_bound: no LP solved within the time limit")
    return float(bound)


class _GtspModel:
    """The GTSP edge MILP of :func:`gtsp_optimum` in HiGHS; cuts added as needed."""

    def __init__(self, c: np.ndarray, clusters: np.ndarray) -> None:
        try:
            import highspy
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise SubtaskOptError("gtsp_optimum needs highspy") from exc
        self.highspy = highspy
        self.c, self.clusters = c, clusters
        self.perm = np.argsort(clusters, kind="stable")  # internal node u is perm[u]
        self.sub = clusters[self.perm]
        m, n = len(self.sub), int(self.sub[-1]) + 1
        self.m, self.n = m, n
        self.start = np.searchsorted(self.sub, np.arange(n + 1)).astype(np.int64)
        iu, ju = np.triu_indices(m, 1)
        keep = self.sub[iu] != self.sub[ju]
        self.iu, self.ju = iu[keep], ju[keep]
        self.n_edges = len(self.iu)
        self.incumbent: np.ndarray | None = None
        self.incumbent_cost = math.inf
        self.incumbent_tour = np.empty(0, dtype=np.int64)
        with quiet_stdout():  # HiGHS prints its banner on construction
            h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        h.setOptionValue("mip_rel_gap", 0.0)
        n_cols = self.n_edges + m
        weights = c[self.perm[self.iu], self.perm[self.ju]]
        h.addCols(n_cols, np.concatenate([weights, np.zeros(m)]), np.zeros(n_cols),
                  np.ones(n_cols), 0, np.array([], dtype=np.int32),
                  np.array([], dtype=np.int32), np.array([]))
        for k in range(n):  # one node per cluster
            idx = np.arange(self.n_edges + self.start[k], self.n_edges + self.start[k + 1],
                            dtype=np.int32)
            h.addRow(1.0, 1.0, len(idx), idx, np.ones(len(idx)))
        for v in range(m):  # degree 2 at a chosen node, 0 elsewhere
            idx = np.concatenate([np.flatnonzero((self.iu == v) | (self.ju == v)),
                                  [self.n_edges + v]]).astype(np.int32)
            h.addRow(0.0, 0.0, len(idx), idx, np.concatenate([np.ones(len(idx) - 1), [-2.0]]))
        self.h = h

    def set_incumbent(self, tour: np.ndarray) -> None:
        """Keep ``tour`` (original node indices) as a starting solution for branching."""
        if (tour.ndim != 1 or np.any((tour < 0) | (tour >= self.m))
                or sorted(self.clusters[tour].tolist()) != list(range(self.n))):
            raise ParameterError("gtsp_optimum.incumbent must visit one node of every cluster")
        inner = np.argsort(self.perm)[tour]
        a, b = np.minimum(inner, np.roll(inner, -1)), np.maximum(inner, np.roll(inner, -1))
        edge = {(int(i), int(j)): e for e, (i, j) in
                enumerate(zip(self.iu.tolist(), self.ju.tolist(), strict=True))}
        sol = np.zeros(self.n_edges + self.m)
        sol[[edge[(int(i), int(j))] for i, j in zip(a, b, strict=True)]] = 1.0
        sol[self.n_edges + inner] = 1.0
        self.incumbent = sol
        self.incumbent_cost = float(self.c[tour, np.roll(tour, -1)].sum())
        self.incumbent_tour = tour

    def _run(self, deadline: float | None) -> np.ndarray:
        highspy, h = self.highspy, self.h
        status = _run_highs(h, deadline, "gtsp_optimum: not proven within the time limit")
        if status == highspy.HighsModelStatus.kTimeLimit:
            raise SubtaskOptError("gtsp_optimum: not proven within the time limit")
        if status != highspy.HighsModelStatus.kOptimal:
            raise SubtaskOptError(f"HiGHS did not solve the GTSP: "
                                  f"{h.modelStatusToString(status)}")
        return np.asarray(h.getSolution().col_value)

    def _cluster_components(self, x: np.ndarray) -> list[list[int]]:
        used = x > 1e-9
        return _components(self.n, self.sub[self.iu[used]], self.sub[self.ju[used]])

    def _add_cuts(self, sides: list[np.ndarray], pairs: list[tuple[int, int]] | None) -> None:
        """x(delta(S)) >= 2 for each S in ``sides`` (whole clusters), or with ``pairs``
        the generalised x(delta(S)) - 2 y(S & C_i) - 2 y(C_j - S) >= -2 (one addRows)."""
        starts: list[int] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        nnz = 0
        for k, side in enumerate(sides):
            idx = np.flatnonzero(side[self.iu] != side[self.ju])
            starts.append(nnz)
            if pairs is None:
                cols.append(idx)
                vals.append(np.ones(len(idx)))
            else:
                i, j = pairs[k]
                ys = np.flatnonzero(((self.sub == i) & side) | ((self.sub == j) & ~side))
                cols.append(np.concatenate([idx, self.n_edges + ys]))
                vals.append(np.concatenate([np.ones(len(idx)), np.full(len(ys), -2.0)]))
            nnz += len(cols[-1])
        low = np.full(len(sides), 2.0 if pairs is None else -2.0)
        self.h.addRows(len(sides), low, np.full(len(sides), self.highspy.kHighsInf),
                       nnz, np.array(starts, dtype=np.int32),
                       np.concatenate(cols).astype(np.int32), np.concatenate(vals))

    def _cut_subtours(self, comps: list[list[int]]) -> None:
        self._add_cuts([np.isin(self.sub, comp) for comp in comps], None)

    best_lp_bound = -math.inf
    """The largest LP optimum of :meth:`root_cuts` so far (a lower bound of every tour)."""

    def root_cuts(self, max_rounds: int, deadline: float | None,
                  bound_only: bool = False) -> None:
        """Rounds of cuts on the LP relaxation until none is violated; then the cuts
        that are slack at the final LP point are dropped (a lighter LP to branch on).
        Each LP's optimum is recorded in :attr:`best_lp_bound`; ``bound_only``: stop
        after the cuts, no clean-up."""
        n_rows = self.n + self.m
        for _ in range(max_rounds):
            sol = self._run(deadline)
            self.best_lp_bound = max(self.best_lp_bound,
                                     float(self.h.getInfo().objective_function_value))
            x, y = sol[:self.n_edges], sol[self.n_edges:]
            comps = self._cluster_components(x)
            if len(comps) > 1:
                self._cut_subtours(comps)
                continue
            w = np.zeros((self.m, self.m))
            w[self.iu, self.ju] = np.maximum(x, 0.0)
            pairs, _, sides = _pair_cuts(w + w.T, np.maximum(y, 0.0), self.start, 1e-6)
            if len(pairs) == 0:
                break
            seen: set[bytes] = set()
            keep = []
            for k, side in enumerate(sides):
                key = side.tobytes()
                if key not in seen:
                    seen.add(key)
                    keep.append(k)
            self._add_cuts([sides[k] for k in keep], [tuple(pairs[k]) for k in keep])
        else:
            raise SubtaskOptError(f"gtsp_optimum: cuts still violated after {max_rounds} "
                                  f"rounds")
        if bound_only:
            return
        final = self.h.getSolution()
        if self.incumbent is not None:  # reduced-cost fixing against the incumbent
            bound = self.h.getInfo().objective_function_value
            gap = self.incumbent_cost - bound + 1e-9 * abs(self.incumbent_cost)
            value = np.asarray(final.col_value)
            # a tour using a column at 0 in the LP costs at least bound + its reduced cost
            fixed = np.flatnonzero((np.asarray(final.col_dual) > gap) & (value < 1e-9)
                                   & (self.incumbent < 0.5)).astype(np.int32)
            if len(fixed):
                self.h.changeColsBounds(len(fixed), fixed, np.zeros(len(fixed)),
                                        np.zeros(len(fixed)))
        activity = np.asarray(final.row_value)[n_rows:]
        low = np.asarray(self.h.getLp().row_lower_)[n_rows:]
        slack = np.flatnonzero(activity > low + 1e-6) + n_rows
        if len(slack):
            self.h.deleteRows(len(slack), slack.astype(np.int32))

    def branch(self, max_rounds: int, deadline: float | None) -> np.ndarray:
        """Branch and bound, cutting the cluster subtours of each integer answer."""
        highspy, h = self.highspy, self.h
        n_cols = self.n_edges + self.m
        h.changeColsIntegrality(n_cols, np.arange(n_cols, dtype=np.int32),
                                np.full(n_cols, highspy.HighsVarType.kInteger))
        for _ in range(max_rounds):
            if self.incumbent is not None:  # a true tour: it keeps every cut
                sol = highspy.HighsSolution()
                sol.col_value = self.incumbent.tolist()
                sol.value_valid = True
                h.setSolution(sol)
            x = self._run(deadline)[:self.n_edges] > 0.5
            comps = self._cluster_components(x.astype(float))
            if len(comps) == 1:
                return self.perm[self._tour(self.iu[x], self.ju[x])]
            if self.incumbent is not None and (
                    h.getInfo().objective_function_value
                    >= self.incumbent_cost - 1e-12 * abs(self.incumbent_cost)):
                break  # nothing, subtours allowed, is cheaper: the incumbent is optimal
            self._cut_subtours(comps)
        else:
            raise SubtaskOptError(f"gtsp_optimum: no single tour after {max_rounds} rounds "
                                  f"of cuts")
        tour = self.incumbent_tour
        return np.roll(tour, -int(np.flatnonzero(self.clusters[tour] == 0)[0]))

    def _tour(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The chosen nodes in tour order, from the node of cluster 0."""
        chosen = np.unique(np.concatenate([a, b]))  # sorted by cluster: chosen[k] in C_k
        rank = np.searchsorted(chosen, np.arange(self.m))
        order = _walk(self.n, rank[a], rank[b])
        return chosen[order]


def _node_clusters(name: str, cost: Any, clusters: Any) -> tuple[np.ndarray, np.ndarray, int]:
    """(cost matrix, cluster of every node, number of clusters) checked for ``name``: a
    square matrix of at least 3 x 3 (inf: forbidden), clusters numbered 0..n-1, n >= 3."""
    c = np.asarray(cost, dtype=float)
    if c.ndim != 2 or c.shape[0] != c.shape[1] or c.shape[0] < 3 or np.isnan(c).any():
        raise ParameterError(f"{name} needs a square cost matrix of at least 3 x 3 "
                             f"(inf: forbidden), got shape {c.shape}")
    cl, n = _cluster_labels(clusters, c.shape[0])
    return c, cl, n


def _cluster_labels(clusters: Any, m: int) -> tuple[np.ndarray, int]:
    """(the cluster of each of the ``m`` nodes, the number of clusters): integers
    numbering every cluster 0..n-1, n >= 3."""
    cl = np.asarray(clusters)
    if cl.shape != (m,) or not np.issubdtype(cl.dtype, np.integer):
        raise ParameterError(f"clusters must be {m} integers (one per node), "
                             f"got shape {cl.shape} of {cl.dtype}")
    n = int(cl.max()) + 1
    if cl.min() < 0 or len(np.unique(cl)) != n or n < 3:
        raise ParameterError(f"clusters must number every cluster 0..n-1 (n >= 3), "
                             f"got {sorted(set(cl.tolist()))}")
    return cl, n


def agtsp_optimum(cost: np.ndarray, clusters: np.ndarray | Sequence[int], *,
                  incumbent: np.ndarray | Sequence[int] | None = None,
                  time_limit: float | None = None,
                  max_rounds: int = 500) -> tuple[float, np.ndarray, np.ndarray]:
    """Certified minimum closed tour through one node of every cluster, any costs.

    The asymmetric generalised TSP (GTSPLIB's AGTSP, forbidden arcs as inf) as an arc
    MILP in HiGHS: binary ``x_uv`` per finite arc between nodes of different clusters and
    ``y_v`` per node; one node per cluster; one arc in and one out of a chosen node, none
    at the others; cluster subtours of each integer answer cut off (at least one arc
    leaves every proper union of clusters the answer closes a cycle on) until it is one
    tour. ``incumbent`` (nodes, one per cluster, in tour order) starts the search.

    Returns ``(cost, order, nodes)`` as :func:`gtsp_optimum`. Raises
    :class:`SubtaskOptError` if no tour exists or none is proven within ``time_limit``.
    """
    c, cl, n = _node_clusters("agtsp_optimum", cost, clusters)
    require_int("agtsp_optimum", "max_rounds", max_rounds, 1)
    if time_limit is not None and not (isinstance(time_limit, (int, float))
                                       and time_limit > 0):
        raise ParameterError(f"agtsp_optimum.time_limit must be > 0 s, got {time_limit!r}")
    try:
        import highspy
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SubtaskOptError("agtsp_optimum needs highspy") from exc
    deadline = None if time_limit is None else time.perf_counter() + float(time_limit)
    m = c.shape[0]
    tail, head = np.nonzero((cl[:, None] != cl[None, :]) & np.isfinite(c))
    n_arcs = len(tail)
    with quiet_stdout():
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("mip_rel_gap", 0.0)
    n_cols = n_arcs + m
    h.addCols(n_cols, np.concatenate([c[tail, head], np.zeros(m)]), np.zeros(n_cols),
              np.ones(n_cols), 0, np.array([], dtype=np.int32), np.array([], dtype=np.int32),
              np.array([]))
    for k in range(n):  # one node per cluster
        idx = (n_arcs + np.flatnonzero(cl == k)).astype(np.int32)
        h.addRow(1.0, 1.0, len(idx), idx, np.ones(len(idx)))
    for ends in (tail, head):  # one arc out of (into) a chosen node, none elsewhere
        order = np.argsort(ends, kind="stable")
        bounds = np.searchsorted(ends[order], np.arange(m + 1))
        for v in range(m):
            idx = np.concatenate([order[bounds[v]:bounds[v + 1]], [n_arcs + v]]).astype(np.int32)
            h.addRow(0.0, 0.0, len(idx), idx,
                     np.concatenate([np.ones(len(idx) - 1), [-1.0]]))
    # the LP relaxation first, with every violated cluster cut found by a maximum flow from
    # cluster 0 to each other cluster over the summed arc values
    for _ in range(max_rounds):
        status = _run_highs(h, deadline, "agtsp_optimum: not proven within the time limit")
        if status != highspy.HighsModelStatus.kOptimal:
            break  # infeasible or stuck: the integer loop below says why
        x = np.asarray(h.getSolution().col_value)[:n_arcs]
        cuts = _cluster_cuts(n, cl[tail], cl[head], x)
        if not cuts:
            break
        for inside_clusters in cuts:
            inside = np.isin(cl, inside_clusters)
            idx = np.flatnonzero(inside[tail] & ~inside[head]).astype(np.int32)
            h.addRow(1.0, highspy.kHighsInf, len(idx), idx, np.ones(len(idx)))
    h.changeColsIntegrality(n_cols, np.arange(n_cols, dtype=np.int32),
                            np.full(n_cols, highspy.HighsVarType.kInteger))
    start_solution = None
    if incumbent is not None:
        tour = np.asarray(incumbent, dtype=np.int64)
        if (tour.ndim != 1 or np.any((tour < 0) | (tour >= m))
                or sorted(cl[tour].tolist()) != list(range(n))):
            raise ParameterError("agtsp_optimum.incumbent must visit one node of every cluster")
        arc = {(int(u), int(v)): a for a, (u, v) in
               enumerate(zip(tail.tolist(), head.tolist(), strict=True))}
        legs = list(zip(tour.tolist(), np.roll(tour, -1).tolist(), strict=True))
        if all(leg in arc for leg in legs):
            start_solution = np.zeros(n_cols)
            start_solution[[arc[leg] for leg in legs]] = 1.0
            start_solution[n_arcs + tour] = 1.0
    for _ in range(max_rounds):
        if start_solution is not None:
            sol = highspy.HighsSolution()
            sol.col_value = start_solution.tolist()
            sol.value_valid = True
            h.setSolution(sol)
        status = _run_highs(h, deadline, "agtsp_optimum: not proven within the time limit")
        if status == highspy.HighsModelStatus.kInfeasible:
            raise SubtaskOptError("agtsp_optimum: no tour avoids the forbidden arcs")
        if status != highspy.HighsModelStatus.kOptimal:
            raise SubtaskOptError(f"HiGHS did not solve the GTSP: "
                                  f"{h.modelStatusToString(status)}")
        x = np.asarray(h.getSolution().col_value)[:n_arcs] > 0.5
        comps = _components(n, cl[tail[x]], cl[head[x]])
        if len(comps) == 1:
            nxt = dict(zip(tail[x].tolist(), head[x].tolist(), strict=True))
            first = next(v for v in nxt if cl[v] == 0)
            nodes = [first]
            while len(nodes) < n:
                nodes.append(nxt[nodes[-1]])
            out = np.array(nodes, dtype=np.int64)
            return float(c[out, np.roll(out, -1)].sum()), cl[out], out
        for comp in comps:  # an arc must leave every cycle's union of clusters
            inside = np.isin(cl, comp)
            idx = np.flatnonzero(inside[tail] & ~inside[head]).astype(np.int32)
            h.addRow(1.0, highspy.kHighsInf, len(idx), idx, np.ones(len(idx)))
    raise SubtaskOptError(f"agtsp_optimum: no single tour after {max_rounds} rounds of cuts")


def _cluster_cuts(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray,
                  tol: float = 1e-6) -> list[np.ndarray]:
    """Unions S of clusters that the arc values ``x`` (arcs from cluster a to b) leave by
    less than 1: for each cluster k, a minimum cut between cluster 0 and k, both ways."""
    cap = np.zeros((n, n))
    np.add.at(cap, (a, b), np.maximum(x, 0.0))
    np.fill_diagonal(cap, 0.0)
    cuts: list[np.ndarray] = []
    seen: set[bytes] = set()
    for k in range(1, n):
        for source, sink in ((0, k), (k, 0)):
            value, side = _min_cut(cap, source, sink, 1.0 - tol)
            if value >= 1.0 - tol:
                continue
            key = side.tobytes()
            if key not in seen:
                seen.add(key)
                cuts.append(np.flatnonzero(side))
    return cuts


def _min_cut(cap: np.ndarray, source: int, sink: int, enough: float
             ) -> tuple[float, np.ndarray]:
    """Maximum flow by shortest augmenting paths (Edmonds-Karp) on the dense capacities,
    stopped once it reaches ``enough``; returns the flow and the source side of a minimum
    cut (the nodes the residual graph reaches)."""
    residual = cap.copy()
    n = cap.shape[0]
    flow = 0.0
    while True:
        parent = np.full(n, -1)
        parent[source] = source
        queue = [source]
        while queue and parent[sink] < 0:
            nxt = []
            for u in queue:
                for v in np.flatnonzero((residual[u] > 1e-12) & (parent < 0)).tolist():
                    parent[v] = u
                    nxt.append(v)
            queue = nxt
        if parent[sink] < 0:
            return flow, parent >= 0
        path = []
        v = sink
        while v != source:
            path.append((int(parent[v]), v))
            v = int(parent[v])
        push = min(residual[u, w] for u, w in path)
        for u, w in path:
            residual[u, w] -= push
            residual[w, u] += push
        flow += push
        if flow >= enough:
            return flow, parent >= 0


def gtsp_set_optimum(problem: Any, *, incumbent: np.ndarray | Sequence[int] | None = None,
                     time_limit: float | None = None) -> tuple[float, np.ndarray]:
    """Certified optimum of a :class:`~subtask_opt.tour.problem.GtspProblem` (closed tour):
    :func:`gtsp_optimum` for finite symmetric weights, :func:`agtsp_optimum` otherwise.
    ``incumbent``: vertices in tour order, one per set. Returns ``(cost, vertices)``, the
    vertices in tour order from set 0."""
    w = np.array(problem.weights, dtype=float)
    sets = np.asarray(problem.sets, dtype=np.int64)
    if np.all(np.isfinite(w)) and np.array_equal(w, w.T):
        cost, _, nodes = gtsp_optimum(w, sets, incumbent=incumbent, time_limit=time_limit)
    else:
        cost, _, nodes = agtsp_optimum(w, sets, incumbent=incumbent, time_limit=time_limit)
    return cost, nodes


def milp_pinned_clustered(cost: np.ndarray, clusters: np.ndarray | Sequence[int],
                          first: int = 0, last: int = -1,
                          pairs: np.ndarray | Sequence[tuple[int, int]] = (), *,
                          time_limit: float | None = None
                          ) -> tuple[float, np.ndarray, np.ndarray]:
    """Certified minimum closed tour through one node of every cluster that starts in
    cluster ``first``, ends in ``last`` (if >= 0) and keeps the cluster pairs ``(a, b)``
    (a before b): the precedence-constrained generalised TSP, any costs (inf: forbidden).

    Arc MILP in HiGHS: binary ``x_uv`` per finite arc between nodes of different clusters
    and ``y_v`` per node, one node per cluster, one arc in and out of a chosen node and
    none at the others; Miller-Tucker-Zemlin positions of the clusters other than
    ``first`` over the summed arcs between two clusters (lifted as Desrochers and Laporte
    do), bounded by the transitive closure of the pairs; ``(a, b)`` is ``u_a + 1 <= u_b``;
    a pinned end takes an arc from ``last`` into ``first``. Zero gap, nothing printed.

    Returns ``(cost, order, nodes)``: the clusters in tour order from ``first`` and the
    node visited in each. Raises :class:`SubtaskOptError` if no tour keeps the rules or
    none is proven optimal within ``time_limit`` seconds.
    """
    c, cl, n = _node_clusters("milp_pinned_clustered", cost, clusters)
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not 0 <= first < n or not -1 <= last < n or last == first:
        raise ParameterError(f"first={first} and last={last} must be distinct clusters in "
                             f"0..{n - 1} (last -1: free)")
    if p.size and (p.min() < 0 or p.max() >= n):
        raise ParameterError(f"precedence pairs must name clusters in 0..{n - 1}")
    if any(b == first for _, b in p.tolist()):
        raise SubtaskOptError(f"no tour keeps the pairs: one ends in the start {first}")
    try:
        import highspy
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SubtaskOptError("milp_pinned_clustered needs highspy") from exc
    before = _precedence_closure(n, first, last, p)
    if np.any(np.diag(before)):
        raise SubtaskOptError("no tour keeps the pairs: they form a cycle")
    ancestors = before.sum(axis=0)
    descendants = before.sum(axis=1)
    m = c.shape[0]
    tail, head = np.nonzero((cl[:, None] != cl[None, :]) & np.isfinite(c))
    ct, ch = cl[tail], cl[head]
    n_arcs = len(tail)
    deadline = None if time_limit is None else time.perf_counter() + float(time_limit)
    with quiet_stdout():
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("mip_rel_gap", 0.0)
    inf = highspy.kHighsInf
    empty_i = np.array([], dtype=np.int32)
    upper = np.ones(n_arcs + m)
    # an arc against the closure of the pairs is never used
    upper[:n_arcs][(ch != first) & before[ch, ct]] = 0.0
    h.addCols(n_arcs + m, np.concatenate([c[tail, head], np.zeros(m)]), np.zeros(n_arcs + m),
              upper, 0, empty_i, empty_i, np.array([]))
    others = [k for k in range(n) if k != first]
    u = {k: n_arcs + m + i for i, k in enumerate(others)}
    h.addCols(n - 1, np.zeros(n - 1), np.array([float(max(1, ancestors[k])) for k in others]),
              np.array([n - 1.0 - descendants[k] for k in others]), 0, empty_i, empty_i,
              np.array([]))
    for k in range(n):  # one node per cluster
        idx = (n_arcs + np.flatnonzero(cl == k)).astype(np.int32)
        h.addRow(1.0, 1.0, len(idx), idx, np.ones(len(idx)))
    for ends in (tail, head):  # one arc out of (into) a chosen node, none elsewhere
        order = np.argsort(ends, kind="stable")
        bounds = np.searchsorted(ends[order], np.arange(m + 1))
        for v in range(m):
            idx = np.concatenate([order[bounds[v]:bounds[v + 1]], [n_arcs + v]]).astype(np.int32)
            h.addRow(0.0, 0.0, len(idx), idx, np.concatenate([np.ones(len(idx) - 1), [-1.0]]))
    between: dict[tuple[int, int], list[int]] = {}
    for a in range(n_arcs):
        between.setdefault((int(ct[a]), int(ch[a])), []).append(a)
    for i in others:
        for j in others:
            if i >= j:
                continue
            ij = between.get((i, j), [])
            ji = between.get((j, i), [])
            for x, y, fw, bw in ((i, j, ij, ji), (j, i, ji, ij)):
                # u_x - u_y + (n - 1) z_xy + (n - 3) z_yx <= n - 2
                idx = np.array([u[x], u[y], *fw, *bw], dtype=np.int32)
                val = np.array([1.0, -1.0] + [n - 1.0] * len(fw) + [n - 3.0] * len(bw))
                h.addRow(-inf, n - 2.0, len(idx), idx, val)
    for a, b in p.tolist():
        if a != first:
            h.addRow(-inf, -1.0, 2, np.array([u[a], u[b]], dtype=np.int32),
                     np.array([1.0, -1.0]))
    if last >= 0:
        idx = np.array(between.get((last, first), []), dtype=np.int32)
        h.addRow(1.0, 1.0, len(idx), idx, np.ones(len(idx)))
    late = "milp_pinned_clustered: not proven within the time limit"
    h.changeColsIntegrality(n_arcs + m, np.arange(n_arcs + m, dtype=np.int32),
                            np.full(n_arcs + m, highspy.HighsVarType.kInteger))
    status = _run_highs(h, deadline, late)
    if status == highspy.HighsModelStatus.kInfeasible:
        raise SubtaskOptError("milp_pinned_clustered: no tour keeps the rules")
    if status != highspy.HighsModelStatus.kOptimal:
        raise SubtaskOptError(f"HiGHS did not solve the precedence-constrained GTSP: "
                              f"{h.modelStatusToString(status)}")
    used = np.asarray(h.getSolution().col_value)[:n_arcs] > 0.5
    nxt = dict(zip(tail[used].tolist(), head[used].tolist(), strict=True))
    start = next(v for v in nxt if cl[v] == first)
    nodes = [start]
    while len(nodes) < n:
        nodes.append(nxt[nodes[-1]])
    out = np.array(nodes, dtype=np.int64)
    return float(c[out, np.roll(out, -1)].sum()), cl[out].astype(np.int64), out

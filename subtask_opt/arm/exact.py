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
  problem with :class:`~subtask_opt.arm.constraints.TourConstraints`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from subtask_opt.base.errors import ParameterError, SubtaskOptError, require_int
from subtask_opt.base.files import quiet_stdout

if TYPE_CHECKING:
    from subtask_opt.arm.constraints import TourConstraints


def _square_matrix(matrix: np.ndarray) -> np.ndarray:
    m = np.asarray(matrix, dtype=float)
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
            if deadline is not None:
                left = deadline - time.perf_counter()
                if left <= 0:
                    raise SubtaskOptError(f"milp_optimum: not proven within {time_limit} s")
                h.setOptionValue("time_limit", left)
            h.run()
            status = h.getModelStatus()
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
# These work on the canonical form of :mod:`subtask_opt.arm.constraints`: a closed tour
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
    from subtask_opt.arm.constraints import canonical

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

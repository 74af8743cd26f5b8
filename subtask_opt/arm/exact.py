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
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from subtask_opt.base.errors import ParameterError, SubtaskOptError, require_int
from subtask_opt.base.files import quiet_stdout


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

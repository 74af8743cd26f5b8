"""Exact travelling-salesman solvers: oracles that certify the GA's answers.

* :func:`held_karp` - dynamic programming, O(2^N N^2), for N <= 16; pure
  numpy/Python, no extra dependency.
* :func:`milp_optimum` - integer program over the edges of a symmetric matrix
  with degree constraints and subtour-elimination cuts added until the
  solution is one tour (Dantzig-Fulkerson-Johnson), solved by HiGHS
  (``highspy``, in the ``dev`` and ``bench`` extras). Certifies 20- and
  30-subtask instances in well under a second.
"""

from __future__ import annotations

import math
import time

import numpy as np

from subtask_opt.base.errors import ParameterError, SubtaskOptError
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
    m = _square_matrix(matrix)
    if not np.allclose(m, m.T, rtol=1e-9, atol=1e-12):
        raise ParameterError("milp_optimum needs a symmetric matrix")
    try:
        import highspy
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SubtaskOptError("milp_optimum needs highspy: pip install 'subtask_opt[bench]'") \
            from exc
    n = m.shape[0]
    iu, ju = np.triu_indices(n, 1)
    n_edges = len(iu)
    with quiet_stdout():  # HiGHS prints its banner on construction
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("mip_rel_gap", 0.0)
    inf = highspy.kHighsInf
    h.addCols(n_edges, m[iu, ju], np.zeros(n_edges), np.ones(n_edges), 0,
              np.array([], dtype=np.int32), np.array([], dtype=np.int32), np.array([]))
    h.changeColsIntegrality(n_edges, np.arange(n_edges, dtype=np.int32),
                            np.full(n_edges, highspy.HighsVarType.kInteger))
    edge_index: dict[tuple[int, int], int] = {}
    for e, (i, j) in enumerate(zip(iu.tolist(), ju.tolist(), strict=True)):
        edge_index[(i, j)] = e
    for v in range(n):  # every city has degree 2
        idx = np.array([edge_index[(min(v, u), max(v, u))] for u in range(n) if u != v],
                       dtype=np.int32)
        h.addRow(2.0, 2.0, len(idx), idx, np.ones(len(idx)))
    for _ in range(max_rounds):
        if deadline is not None:
            left = deadline - time.perf_counter()
            if left <= 0:
                raise SubtaskOptError(f"milp_optimum: not proven within {time_limit} s")
            h.setOptionValue("time_limit", left)
        h.run()
        status = h.getModelStatus()
        if status != highspy.HighsModelStatus.kOptimal:
            raise SubtaskOptError(f"HiGHS did not solve the TSP: {h.modelStatusToString(status)}")
        x = np.asarray(h.getSolution().col_value) > 0.5
        components = _components(n, iu[x], ju[x])
        if len(components) == 1:
            order = _walk(n, iu[x], ju[x])
            return tour_length(m, order), order
        for comp in components:  # at most |S| - 1 edges inside any proper subset S
            inside = set(comp)
            idx = np.array([e for e, (i, j) in enumerate(zip(iu, ju, strict=True))
                            if i in inside and j in inside], dtype=np.int32)
            h.addRow(-inf, len(comp) - 1.0, len(idx), idx, np.ones(len(idx)))
    raise SubtaskOptError(f"milp_optimum: no single tour after {max_rounds} rounds of cuts")


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

"""Lower bounds on the length of a closed tour: how far can an answer be from the best?

:func:`lower_bound` returns a number no tour of the matrix can beat, so for a
tour of length ``L`` and a bound ``B`` the tour is at most ``(L - B) / B``
above the optimum.

Symmetric matrices: the Held-Karp 1-tree bound. A 1-tree is a minimum
spanning tree over the cities ``1..N-1`` plus the two cheapest edges at city
0; every tour is a 1-tree, so the cheapest 1-tree is a lower bound. With node
penalties ``pi`` the edge costs become ``c_ij + pi_i + pi_j``; every tour's
length grows by exactly ``2 * sum(pi)``, so ``w(pi) = 1tree(pi) - 2 sum(pi)`` is
a bound for any ``pi``. Subgradient ascent on ``pi`` (the subgradient is
``degree - 2``) raises it, with Polyak's step ``t = lam (U - w) / |g|^2``
(Held, Wolfe and Crowder 1974), ``U`` a known tour length: the ``upper`` you
pass, otherwise a nearest-neighbour tour. ``lam`` starts at
:attr:`BoundParams.initial_step` and halves after
:attr:`BoundParams.patience` iterations without a better bound. When a
1-tree is a tour it is an optimal one, and the bound is exact.

Asymmetric matrices: the larger of two valid bounds, (a) the 1-tree bound of
the symmetrised matrix ``min(c_ij, c_ji)`` (every directed tour costs at least
its undirected cycle under the cheaper direction) and (b) the assignment bound
(every tour is an assignment without self-loops; solved exactly by the
Hungarian method, in numba).

If every entry is a whole number, every tour length is one too and the bound
is rounded up to the next whole number.

Cost: one O(N^2) minimum spanning tree per iteration; the default 1000
iterations take milliseconds at N=30, a fraction of a second at N=300 and
seconds at N=1000 (``benchmarks/tsplib.py`` prints the times; pass
``time_limit`` to cap it).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    require_in_range,
    require_int,
    require_positive,
)

DEFAULT_ITERATIONS = 1000


@dataclass(frozen=True)
class BoundParams:
    """Tuning of the subgradient ascent of :func:`lower_bound`.

    Attributes:
        initial_step: Polyak step factor ``lam`` at the start (in (0, 2]).
        patience: iterations without a better bound before ``lam`` halves.
        min_step: the ascent stops once ``lam`` falls below this.
        momentum: weight of the previous subgradient in the direction
            (0 = plain subgradient).
    """

    initial_step: float = 2.0
    patience: int = 20
    min_step: float = 1e-5
    momentum: float = 0.3

    def __post_init__(self) -> None:
        require_in_range("BoundParams", "initial_step", self.initial_step, 1e-12, 2.0)
        require_int("BoundParams", "patience", self.patience, 1)
        require_positive("BoundParams", "min_step", self.min_step)
        require_in_range("BoundParams", "momentum", self.momentum, 0.0, 0.99)


class _AscentParams(NamedTuple):
    """What the kernel needs (numba caches NamedTuples)."""

    iterations: int
    initial_step: float
    patience: int
    min_step: float
    momentum: float
    upper: float
    tolerance: float


@njit(cache=True)
def _one_tree(matrix, pi, degree):
    """Cost of the minimum 1-tree under ``c_ij + pi_i + pi_j`` (special city 0).

    Fills ``degree`` with each city's degree in that 1-tree and returns the
    cost (penalties included).
    """
    n = matrix.shape[0]
    for i in range(n):
        degree[i] = 0
    # Prim over cities 1..n-1; the key update and the search for the next
    # city share one pass over the row
    in_tree = np.zeros(n, dtype=np.bool_)
    key = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    total = 0.0
    u = 1
    for _ in range(n - 2):
        in_tree[u] = True
        pu = pi[u]
        nxt = -1
        best = np.inf
        for v in range(1, n):
            if not in_tree[v]:
                c = matrix[u, v] + pu + pi[v]
                if c < key[v]:
                    key[v] = c
                    parent[v] = u
                if key[v] < best or nxt < 0:
                    best = key[v]
                    nxt = v
        total += key[nxt]
        degree[nxt] += 1
        degree[parent[nxt]] += 1
        u = nxt
    # the two cheapest edges at city 0
    first = -1
    second = -1
    c1 = np.inf
    c2 = np.inf
    p0 = pi[0]
    for v in range(1, n):
        c = matrix[0, v] + p0 + pi[v]
        if c < c1:
            c2 = c1
            second = first
            c1 = c
            first = v
        elif c < c2:
            c2 = c
            second = v
    total += c1 + c2
    degree[0] = 2
    degree[first] += 1
    degree[second] += 1
    return total


@njit(cache=True)
def _nearest_neighbour_length(matrix, start):
    """Length of the nearest-neighbour tour from ``start`` (an upper bound)."""
    n = matrix.shape[0]
    visited = np.zeros(n, dtype=np.bool_)
    visited[start] = True
    current = start
    total = 0.0
    for _ in range(n - 1):
        nxt = -1
        best = np.inf
        for v in range(n):
            if not visited[v] and matrix[current, v] < best:
                best = matrix[current, v]
                nxt = v
        visited[nxt] = True
        total += best
        current = nxt
    return total + matrix[current, start]


# slots of the ascent's state vector (it survives between chunks of iterations)
_BEST, _STEP, _SINCE_BETTER, _DONE, _FINISHED = range(5)


@njit(cache=True)
def _held_karp_ascent(matrix, params, pi, direction, state, chunk):
    """Run up to ``chunk`` more iterations of the subgradient ascent.

    ``pi`` (penalties), ``direction`` (last step direction) and ``state``
    (best bound, step factor ``lam``, iterations since the best improved,
    iterations done, finished flag) carry the ascent from one call to the
    next, so a caller can stop between chunks (a deadline) and the result does
    not depend on the chunk size. ``state[_FINISHED]`` becomes 1 when the
    ascent is over: a 1-tree was a tour (then the bound is the optimum), the
    bound met ``params.upper``, ``lam`` fell below ``min_step``, or
    ``params.iterations`` ran.
    """
    n = matrix.shape[0]
    degree = np.zeros(n, dtype=np.int64)
    for _ in range(chunk):
        if state[_FINISHED] != 0.0 or state[_DONE] >= params.iterations:
            state[_FINISHED] = 1.0
            break
        state[_DONE] += 1.0
        w = _one_tree(matrix, pi, degree)
        for i in range(n):
            w -= 2.0 * pi[i]
        if w > state[_BEST] + params.tolerance:
            state[_BEST] = w
            state[_SINCE_BETTER] = 0.0
        else:
            if w > state[_BEST]:
                state[_BEST] = w
            state[_SINCE_BETTER] += 1.0
            if state[_SINCE_BETTER] >= params.patience:
                state[_STEP] *= 0.5
                state[_SINCE_BETTER] = 0.0
                if state[_STEP] < params.min_step:
                    state[_FINISHED] = 1.0
                    break
        norm = 0.0
        off = 0
        for i in range(n):
            g = degree[i] - 2.0
            direction[i] = g + params.momentum * direction[i]
            norm += direction[i] * direction[i]
            off += abs(degree[i] - 2)
        if off == 0 or params.upper - state[_BEST] <= params.tolerance or norm == 0.0:
            state[_FINISHED] = 1.0  # a tour (optimal), or nothing left to prove
            break
        step = state[_STEP] * (params.upper - w) / norm
        if step <= 0.0:
            step = state[_STEP] * params.tolerance / norm
        for i in range(n):
            pi[i] += step * direction[i]


def _checked_matrix(matrix: np.ndarray) -> np.ndarray:
    try:
        m = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputDataError(f"lower_bound: matrix must be numeric ({exc})") from None
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputDataError(f"lower_bound: matrix must be square, got shape {m.shape}")
    if m.shape[0] < 3:
        raise InputDataError(f"lower_bound: need at least 3 cities, got {m.shape[0]}")
    off = ~np.eye(m.shape[0], dtype=bool)
    if not np.all(np.isfinite(m[off])):
        i, j = np.argwhere(~np.isfinite(m) & off)[0]
        raise InputDataError(
            f"lower_bound: matrix[{i}, {j}] is {m[i, j]} (entries must be finite)")
    np.fill_diagonal(m, 0.0)  # no tour uses the diagonal
    return m


def is_symmetric(matrix: np.ndarray) -> bool:
    """Whether ``matrix`` equals its transpose (to 1e-12 relative)."""
    m = np.asarray(matrix, dtype=float)
    return bool(np.allclose(m, m.T, rtol=1e-12, atol=0.0))


def one_tree_bound(matrix: np.ndarray, *, iterations: int = DEFAULT_ITERATIONS,
                   upper: float | None = None, seed: int | None = None,
                   params: BoundParams | None = None,
                   time_limit: float | None = None) -> float:
    """Held-Karp bound of the symmetric part ``min(c_ij, c_ji)`` of ``matrix``.

    A valid lower bound on every closed tour of ``matrix`` (symmetric or not);
    see :func:`lower_bound` for the arguments.
    """
    m = _checked_matrix(matrix)
    deadline = _deadline(time_limit)
    upper, params = _checked_options(m, iterations, upper, seed, params)
    return _integral(m, _one_tree_value(np.minimum(m, m.T), iterations, upper, params,
                                        deadline))


def assignment_bound(matrix: np.ndarray) -> float:
    """Cheapest assignment without self-loops: a lower bound on every closed tour.

    Solved exactly by the Hungarian method (shortest augmenting paths with
    potentials, O(N^3)) in numba.
    """
    m = _checked_matrix(matrix)
    forbidden = np.abs(m).sum() + 1.0  # dearer than any assignment that avoids the diagonal
    cost = m.copy()
    np.fill_diagonal(cost, forbidden)
    return _integral(m, float(_assignment_cost(cost)))


@njit(cache=True)
def _assignment_cost(cost):
    """Minimum total of ``cost[i, col[i]]`` over permutations ``col`` (Hungarian method).

    Rows are added one at a time; each addition finds a shortest augmenting
    path under the reduced costs ``cost[i, j] - u[i] - v[j]`` (Dijkstra-like,
    O(N^2)) and updates the potentials. Index 0 of the work arrays is a dummy
    column.
    """
    n = cost.shape[0]
    u = np.zeros(n + 1)
    v = np.zeros(n + 1)
    owner = np.zeros(n + 1, dtype=np.int64)  # owner[j]: the row assigned to column j (1-based)
    way = np.zeros(n + 1, dtype=np.int64)
    slack = np.empty(n + 1)
    used = np.empty(n + 1, dtype=np.bool_)
    for row in range(1, n + 1):
        owner[0] = row
        col = 0
        slack[:] = np.inf
        used[:] = False
        while True:
            used[col] = True
            i = owner[col]
            delta = np.inf
            nxt = 0
            for j in range(1, n + 1):
                if not used[j]:
                    reduced = cost[i - 1, j - 1] - u[i] - v[j]
                    if reduced < slack[j]:
                        slack[j] = reduced
                        way[j] = col
                    if slack[j] < delta:
                        delta = slack[j]
                        nxt = j
            for j in range(n + 1):
                if used[j]:
                    u[owner[j]] += delta
                    v[j] -= delta
                else:
                    slack[j] -= delta
            col = nxt
            if owner[col] == 0:
                break
        while col != 0:  # flip the augmenting path
            prev = way[col]
            owner[col] = owner[prev]
            col = prev
    total = 0.0
    for j in range(1, n + 1):
        total += cost[owner[j] - 1, j - 1]
    return total


def lower_bound(matrix: np.ndarray, *, iterations: int = DEFAULT_ITERATIONS,
                upper: float | None = None, seed: int | None = None,
                params: BoundParams | None = None, time_limit: float | None = None) -> float:
    """A number no closed tour through every city of ``matrix`` is shorter than.

    Args:
        matrix: N x N costs (N >= 3, finite off the diagonal; the diagonal is
            ignored). Symmetric: Held-Karp 1-tree bound. Asymmetric: the
            larger of the symmetrised 1-tree bound and the assignment bound.
        iterations: most subgradient steps (>= 1; each is one O(N^2) MST).
        upper: length of a known tour; it drives the step size. Without it a
            nearest-neighbour tour is used. A value below the bound raises
            :class:`ParameterError` (it cannot be a tour's length).
        seed: chooses the start city of that nearest-neighbour tour (None:
            city 0); the same seed gives the same bound.
        params: step-size schedule (default :class:`BoundParams`).
        time_limit: stop the ascent after about this many seconds (checked
            every ~20 ms of work; at least one chunk runs). The bound stays
            valid, only weaker; with a limit the result depends on the
            machine's speed, without one it is reproducible.

    Returns:
        The bound (a whole number when every entry of ``matrix`` is one).
    """
    m = _checked_matrix(matrix)
    deadline = _deadline(time_limit)
    upper_value, p = _checked_options(m, iterations, upper, seed, params)
    if is_symmetric(m):
        value = _one_tree_value(m, iterations, upper_value, p, deadline)
    else:
        value = max(_one_tree_value(np.minimum(m, m.T), iterations, upper_value, p, deadline),
                    assignment_bound(m))
    bound = _integral(m, value)
    if upper is not None and bound > upper * (1 + 1e-9) + 1e-9:
        raise ParameterError(
            f"lower_bound: upper={upper!r} is below the proven bound {bound}, "
            "so it is not the length of a tour of this matrix")
    return bound


def _deadline(time_limit: float | None) -> float | None:
    if time_limit is None:
        return None
    require_positive("lower_bound", "time_limit", time_limit)
    return time.perf_counter() + float(time_limit)


def _checked_options(m: np.ndarray, iterations: int, upper: float | None, seed: int | None,
                     params: BoundParams | None) -> tuple[float, BoundParams]:
    require_int("lower_bound", "iterations", iterations, 1)
    if seed is not None:
        require_int("lower_bound", "seed", seed, 0)
    if params is not None and not isinstance(params, BoundParams):
        raise ParameterError(f"lower_bound: params must be a BoundParams, got {params!r}")
    if upper is not None:
        if (isinstance(upper, bool) or not isinstance(upper, (int, float, np.integer,
                                                              np.floating))
                or not math.isfinite(upper)):
            raise ParameterError(f"lower_bound.upper must be a finite number, got {upper!r}")
        value = float(upper)
    else:
        start = 0 if seed is None else int(np.random.default_rng(seed).integers(m.shape[0]))
        value = float(_nearest_neighbour_length(m, start))
    return value, params or BoundParams()


def _one_tree_value(sym: np.ndarray, iterations: int, upper: float,
                    params: BoundParams, deadline: float | None) -> float:
    """The ascent on a symmetric matrix; ``upper`` may be any tour length (or more)."""
    scale = max(float(np.abs(sym).max()), 1.0) * sym.shape[0]
    kernel = _AscentParams(iterations=int(iterations), initial_step=float(params.initial_step),
                           patience=int(params.patience), min_step=float(params.min_step),
                           momentum=float(params.momentum), upper=float(upper),
                           tolerance=1e-12 * scale)
    n = sym.shape[0]
    pi = np.zeros(n)
    direction = np.zeros(n)
    state = np.zeros(5)
    state[_BEST] = -np.inf
    state[_STEP] = params.initial_step
    sym = np.ascontiguousarray(sym)
    if deadline is None:
        _held_karp_ascent(sym, kernel, pi, direction, state, int(iterations))
    else:  # chunks of about 20 ms of work, so the deadline is kept closely
        chunk = max(1, int(2e7 // (n * n)))
        while True:  # at least one chunk: the bound is always a real number
            _held_karp_ascent(sym, kernel, pi, direction, state, chunk)
            if state[_FINISHED] != 0.0 or time.perf_counter() >= deadline:
                break
    return float(state[_BEST])


def _integral(m: np.ndarray, value: float) -> float:
    """``value`` made safe against round-off: rounded up to a whole number when
    every tour length is one, else lowered by a bound on the float error of the
    tree sum (so a bound equal to the optimum never lands an ulp above it)."""
    n = m.shape[0]
    slack = 4.0 * n * np.finfo(float).eps * max(1.0, abs(value), float(np.abs(m).max()) * n)
    if np.all(m == np.round(m)):
        return float(math.ceil(value - max(slack, 1e-9 * max(1.0, abs(value)))))
    return float(value - slack)


# --------------------------------------------------------------------------- candidates

CANDIDATE_ITERATIONS = 50
"""Ascent steps behind :func:`alpha_neighbour_table`'s penalties (a fixed count, so
the table never depends on the machine's speed)."""

CANDIDATE_ASCENT = BoundParams(initial_step=1.0, patience=5)
"""A quicker ascent than the bound's: on pr1002 its 50 steps leave 2 edges of an optimal
tour out of the 8 alpha-nearest lists (the default schedule's: 3; the 8 nearest: 5)."""

ALPHA_FROM = 100
"""Fewest cities for which :func:`candidate_table` picks alpha-nearness."""
ALPHA_UNTIL = 2000
"""Cities from which :func:`candidate_table` takes the nearest again: its 50 ascent steps
cost O(N^2) each, 1.8-1.9 s of CPU at N = 3200 (0.37 s at 1600), where a search of 40
generations on the nearest lists ends 0.1-0.2% longer in 1.3 s less (uniform points,
benchmarks/regress.py's instances)."""


def candidate_table(matrix: np.ndarray, k: int) -> np.ndarray:
    """The local search's candidate lists: alpha-nearest (:func:`alpha_neighbour_table`)
    for a finite symmetric matrix of :data:`ALPHA_FROM` to :data:`ALPHA_UNTIL` cities,
    else the nearest (:func:`~subtask_opt.tour.permutation.neighbour_table`)."""
    from subtask_opt.tour.permutation import neighbour_table

    m = np.asarray(matrix, dtype=float)
    off = ~np.eye(m.shape[0], dtype=bool)
    if (not ALPHA_FROM <= m.shape[0] < ALPHA_UNTIL or not np.all(np.isfinite(m[off]))
            or not is_symmetric(m)):
        return neighbour_table(matrix, k)
    return alpha_neighbour_table(m, k)


def alpha_neighbour_table(matrix: np.ndarray, k: int, *,
                          iterations: int = CANDIDATE_ITERATIONS,
                          params: BoundParams = CANDIDATE_ASCENT) -> np.ndarray:
    """Each city's ``k`` alpha-nearest other cities (Helsgaun's LKH candidates).

    ``alpha(i, j)`` is how much the minimum 1-tree grows when edge ``(i, j)`` is
    forced into it, under the penalised costs ``c_ij + pi_i + pi_j`` of
    ``iterations`` steps of the Held-Karp ascent (:func:`lower_bound`). Optimal
    tours use edges of small alpha far more often than merely short edges, so
    these lists miss fewer optimal edges than the ``k`` nearest. Ties go to the
    cheaper edge, then the lower index. Cost: O(N^2) per ascent step and once
    for the alphas. Only the lists change: a search still prices moves on
    ``matrix``.
    """
    m = _checked_matrix(matrix)
    n = m.shape[0]
    require_int("alpha_neighbour_table", "k", k, 1)
    require_int("alpha_neighbour_table", "iterations", iterations, 0)
    sym = np.ascontiguousarray(np.minimum(m, m.T))
    pi = np.zeros(n)
    best_pi = pi.copy()
    if iterations > 0:
        # the ascent one step at a time, keeping the penalties of the best bound (the
        # last ones may have overshot)
        upper = float(_nearest_neighbour_length(sym, 0))
        kernel = _AscentParams(iterations=int(iterations), initial_step=params.initial_step,
                               patience=params.patience, min_step=params.min_step,
                               momentum=params.momentum, upper=upper,
                               tolerance=1e-12 * max(float(sym.max()), 1.0) * n)
        direction = np.zeros(n)
        state = np.zeros(5)
        state[_BEST] = -np.inf
        state[_STEP] = params.initial_step
        while state[_FINISHED] == 0.0:
            before = state[_BEST]
            previous = pi.copy()
            _held_karp_ascent(sym, kernel, pi, direction, state, 1)
            if state[_BEST] > before:
                best_pi = previous
    return _alpha_table(sym, best_pi, min(int(k), n - 1))


@njit(cache=True)
def _alpha_table(matrix, pi, k):
    """The ``k`` smallest alphas of each row, by (alpha, cost, index); see
    :func:`alpha_neighbour_table`. beta(i, j), the dearest edge on the tree path
    between i and j, fills in Prim's order from i (Helsgaun 2000, section 4.1):
    first up the path from i to the root, then every other city from its parent."""
    n = matrix.shape[0]
    # minimum spanning tree of cities 1..n-1 (Prim from city 1), its order and parents
    in_tree = np.zeros(n, dtype=np.bool_)
    key = np.full(n, np.inf)
    dad = np.full(n, -1, dtype=np.int64)
    order = np.empty(n - 1, dtype=np.int64)
    u = 1
    for t in range(n - 1):
        in_tree[u] = True
        order[t] = u
        nxt = -1
        best = np.inf
        for v in range(1, n):
            if not in_tree[v]:
                c = matrix[u, v] + (pi[u] + pi[v])
                if c < key[v]:
                    key[v] = c
                    dad[v] = u
                if key[v] < best or nxt < 0:
                    best = key[v]
                    nxt = v
        u = nxt
    # city 0 joins the 1-tree by its two cheapest edges
    c1 = np.inf
    c2 = np.inf
    for v in range(1, n):
        c = matrix[0, v] + (pi[0] + pi[v])
        if c < c1:
            c2 = c1
            c1 = c
        elif c < c2:
            c2 = c
    table = np.empty((n, k), dtype=np.int64)
    alpha = np.empty(n)
    beta = np.empty(n)
    mark = np.full(n, -1, dtype=np.int64)
    top_a = np.empty(k)
    top_c = np.empty(k)
    for i in range(n):
        if i == 0:
            for j in range(1, n):  # replacing the dearer of the two edges at 0
                alpha[j] = max(matrix[0, j] + (pi[0] + pi[j]) - c2, 0.0)
        else:
            mark[i] = i
            beta[i] = -np.inf
            u = i
            while dad[u] >= 0:
                v = dad[u]
                beta[v] = max(beta[u], matrix[u, v] + (pi[u] + pi[v]))
                mark[v] = i
                u = v
            for t in range(n - 1):
                j = order[t]
                if mark[j] != i:
                    p = dad[j]
                    beta[j] = max(beta[p], matrix[j, p] + (pi[j] + pi[p]))
            for j in range(1, n):
                alpha[j] = matrix[i, j] + (pi[i] + pi[j]) - beta[j]
            d0 = matrix[0, i] + (pi[0] + pi[i])
            alpha[0] = 0.0 if d0 <= c2 else d0 - c2
            alpha[i] = np.inf
        if i == 0:
            alpha[0] = np.inf
        # insertion into the k best of the row
        filled = 0
        for j in range(n):
            if j == i:
                continue
            a = alpha[j]
            c = matrix[i, j]
            if filled == k:
                la = top_a[k - 1]
                if a > la or (a == la and (c > top_c[k - 1]
                                           or (c == top_c[k - 1] and j > table[i, k - 1]))):
                    continue
                pos = k - 1
            else:
                pos = filled
                filled += 1
            while pos > 0:
                pa = top_a[pos - 1]
                pc = top_c[pos - 1]
                if pa < a or (pa == a and (pc < c or (pc == c and table[i, pos - 1] < j))):
                    break
                top_a[pos] = pa
                top_c[pos] = pc
                table[i, pos] = table[i, pos - 1]
                pos -= 1
            top_a[pos] = a
            top_c[pos] = c
            table[i, pos] = j
    return table

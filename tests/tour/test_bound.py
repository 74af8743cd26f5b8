"""The Held-Karp lower bound against exact optima (brute force, Held-Karp DP, MILP)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.bound import (
    ALPHA_FROM,
    BoundParams,
    _alpha_table,
    alpha_neighbour_table,
    assignment_bound,
    candidate_table,
    lower_bound,
    one_tree_bound,
)
from subtask_opt.tour.exact import held_karp, milp_optimum, tour_length
from subtask_opt.tour.permutation import neighbour_table
from tests.conftest import examples, size


def _brute_force(m: np.ndarray) -> float:
    n = m.shape[0]
    return min(tour_length(m, np.array((0,) + p)) for p in itertools.permutations(range(1, n)))


def _euclidean(points: np.ndarray) -> np.ndarray:
    return np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))


@st.composite
def _matrices(draw, symmetric: bool):
    n = draw(st.integers(3, 8))
    integral = draw(st.booleans())
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    m = rng.integers(0, 50, (n, n)).astype(float) if integral else rng.random((n, n)) * 10
    if symmetric:
        m = np.triu(m, 1) + np.triu(m, 1).T
    np.fill_diagonal(m, 0.0)
    return m


@settings(max_examples=examples(60), deadline=None)
@given(_matrices(symmetric=True))
def test_bound_below_brute_force_symmetric(m):
    assert lower_bound(m) <= _brute_force(m)


@settings(max_examples=examples(60), deadline=None)
@given(_matrices(symmetric=False))
def test_bound_below_brute_force_asymmetric(m):
    opt = _brute_force(m)
    assert lower_bound(m) <= opt
    assert one_tree_bound(m) <= opt
    assert assignment_bound(m) <= opt


@pytest.mark.parametrize("seed", range(4))
def test_bound_below_milp_optimum_12_to_15_nodes(seed):
    rng = np.random.default_rng(100 + seed)
    n = 12 + seed
    pts = rng.random((n, 2)) * 100
    m = _euclidean(pts)
    opt, _ = milp_optimum(m)
    bound = lower_bound(m)
    assert bound <= opt
    assert bound >= 0.9 * opt  # the ascent did work: a plain MST is far weaker
    rounded = np.floor(m + 0.5)  # TSPLIB-style integer distances
    opt_int, _ = milp_optimum(rounded)
    assert lower_bound(rounded) <= opt_int


@pytest.mark.parametrize("seed", range(3))
def test_asymmetric_bound_below_held_karp(seed):
    rng = np.random.default_rng(200 + seed)
    n = 12
    m = rng.integers(1, 100, (n, n)).astype(float)
    np.fill_diagonal(m, 0.0)
    opt, _ = held_karp(m)
    bound = lower_bound(m)
    assert bound <= opt
    assert bound == max(one_tree_bound(m), assignment_bound(m))


@pytest.mark.parametrize("seed", range(6))
def test_assignment_bound_matches_scipy(seed):
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 60))
    m = rng.random((n, n)) * 100 if seed % 2 else rng.integers(0, 20, (n, n)).astype(float)
    cost = m.copy()
    np.fill_diagonal(cost, 1e9)
    rows, cols = linear_sum_assignment(cost)
    expected = cost[rows, cols].sum()
    bound = assignment_bound(m)
    if seed % 2:  # lowered by the round-off allowance (4 N^2 eps max|c|), never raised
        assert expected - 1e-8 <= bound <= expected
    else:
        assert bound == expected  # whole numbers stay exact


@pytest.mark.parametrize("n", [3, 5, 8, 17, 40, 101])
def test_exact_on_a_regular_polygon(n):
    """Every city's two nearest are its neighbours on the circle: the 1-tree is the
    perimeter, which is the optimal tour (closed form 2 n R sin(pi / n))."""
    rng = np.random.default_rng(n)
    radius = rng.uniform(0.5, 50.0)
    angles = rng.uniform(0, 2 * math.pi) + 2 * math.pi * np.arange(n) / n
    pts = rng.uniform(-10, 10, 2) + radius * np.column_stack([np.cos(angles), np.sin(angles)])
    perimeter = 2 * n * radius * math.sin(math.pi / n)
    bound = lower_bound(_euclidean(pts))
    assert bound == pytest.approx(perimeter, rel=1e-10)
    assert bound <= perimeter * (1 + 1e-13)


@pytest.mark.parametrize("n", [3, 4, 9, 30, 64])
def test_exact_on_integer_cycle_metric(n):
    """Cities on a ring, distance = hops: the optimum is n and the 1-tree is the ring."""
    i = np.arange(n)
    hops = np.abs(i[:, None] - i[None])
    m = np.minimum(hops, n - hops)
    assert lower_bound(m) == n
    assert lower_bound(m, upper=n) == n


@pytest.mark.parametrize("seed", range(5))
def test_first_iteration_is_the_plain_one_tree(seed):
    """With one iteration the bound is the 1-tree without penalties: scipy's MST over
    cities 1..N-1 plus the two cheapest edges at city 0."""
    from scipy.sparse.csgraph import minimum_spanning_tree

    rng = np.random.default_rng(seed)
    m = _euclidean(rng.random((int(rng.integers(4, 40)), 2))) + 0.01  # no zero edges
    np.fill_diagonal(m, 0.0)
    mst = minimum_spanning_tree(m[1:, 1:]).sum()
    expected = mst + np.sort(m[0, 1:])[:2].sum()
    assert lower_bound(m, iterations=1) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_more_iterations_never_lower(seed):
    pts = np.random.default_rng(seed).random((40, 2))
    m = _euclidean(pts)
    values = [lower_bound(m, iterations=k) for k in (1, 10, 100, 1000)]
    assert values == sorted(values)
    assert values[-1] > values[0]


def test_same_seed_same_bound_and_upper_is_used():
    pts = np.random.default_rng(7).random((size(60, 20), 2))
    m = _euclidean(pts)
    assert lower_bound(m, seed=3) == lower_bound(m, seed=3)
    opt, _ = milp_optimum(m)
    with_upper = lower_bound(m, upper=opt)
    assert with_upper <= opt
    assert with_upper >= 0.98 * opt


def test_integer_matrix_gives_whole_number():
    pts = np.random.default_rng(1).integers(0, 1000, (25, 2)).astype(float)
    m = np.floor(_euclidean(pts) + 0.5)
    bound = lower_bound(m)
    assert bound == math.floor(bound)
    assert bound <= milp_optimum(m)[0]


def test_diagonal_is_ignored():
    pts = np.random.default_rng(2).random((10, 2))
    m = _euclidean(pts)
    noisy = m.copy()
    np.fill_diagonal(noisy, 1e6)
    assert lower_bound(noisy) == lower_bound(m)


def test_bad_inputs():
    good = _euclidean(np.random.default_rng(0).random((5, 2)))
    with pytest.raises(InputDataError, match="square"):
        lower_bound(np.zeros((3, 4)))
    with pytest.raises(InputDataError, match="at least 3"):
        lower_bound(np.zeros((2, 2)))
    bad = good.copy()
    bad[1, 2] = np.nan
    with pytest.raises(InputDataError, match=r"matrix\[1, 2\]"):
        lower_bound(bad)
    with pytest.raises(InputDataError, match="numeric"):
        lower_bound([["a", "b", "c"]] * 3)
    with pytest.raises(ParameterError, match="iterations"):
        lower_bound(good, iterations=0)
    with pytest.raises(ParameterError, match="iterations"):
        lower_bound(good, iterations=True)
    with pytest.raises(ParameterError, match="seed"):
        lower_bound(good, seed=-1)
    with pytest.raises(ParameterError, match="upper"):
        lower_bound(good, upper=math.inf)
    with pytest.raises(ParameterError, match="upper"):
        lower_bound(good, upper="10")
    with pytest.raises(ParameterError, match="not the length of a tour"):
        lower_bound(good, upper=0.5 * milp_optimum(good)[0])
    with pytest.raises(ParameterError, match="initial_step"):
        BoundParams(initial_step=3.0)
    with pytest.raises(ParameterError, match="patience"):
        BoundParams(patience=0)


def test_time_limit_keeps_a_valid_bound_and_chunks_change_nothing():
    pts = np.random.default_rng(11).random((size(80, 20), 2))
    m = _euclidean(pts)
    full = lower_bound(m)
    assert lower_bound(m, time_limit=1e6) == full  # chunked ascent, same path
    quick = lower_bound(m, time_limit=1e-9)  # one chunk only
    assert quick <= full
    assert math.isfinite(quick) and quick > 0
    with pytest.raises(ParameterError, match="time_limit"):
        lower_bound(m, time_limit=0)


def _min_one_tree(d: np.ndarray, forced: tuple[int, int] | None = None) -> float:
    """Brute-force oracle: the cheapest 1-tree (special city 0) of the costs ``d``,
    with the edge ``forced`` in it; Prim by plain loops over the edge list."""
    n = d.shape[0]
    big = float(np.abs(d).sum()) + 1.0
    w = d.copy()
    if forced is not None and 0 not in forced:
        w[forced] = w[forced[::-1]] = -big  # so cheap that every minimum tree takes it
    tree, total = {1}, 0.0
    while len(tree) < n - 1:
        c, v = min((w[u, v], v) for u in tree for v in range(1, n) if v not in tree)
        tree.add(v)
        total += c
    if forced is not None and 0 not in forced:
        total += big + d[forced]
    if forced is not None and 0 in forced:
        j = forced[0] + forced[1]
        return total + d[0, j] + min(d[0, v] for v in range(1, n) if v != j)
    return total + sum(sorted(d[0, 1:])[:2])


@pytest.mark.parametrize("seed", range(6))
def test_alpha_table_matches_forced_one_trees(seed):
    rng = np.random.default_rng(300 + seed)
    n = int(rng.integers(4, 11))
    c = rng.integers(0, 20, (n, n)).astype(float)  # small integers: many ties, exact sums
    c = np.triu(c, 1) + np.triu(c, 1).T
    pi = rng.integers(-5, 6, n).astype(float) if seed % 2 else np.zeros(n)
    d = c + pi[:, None] + pi[None, :]
    base = _min_one_tree(d)
    alpha = {(i, j): _min_one_tree(d, (i, j)) - base
             for i in range(n) for j in range(n) if i != j}
    k = int(rng.integers(1, n))
    table = alpha_neighbour_table(c, k, iterations=0) if seed % 2 == 0 else \
        _alpha_table(c, pi, k)
    for i in range(n):
        expected = sorted((j for j in range(n) if j != i),
                          key=lambda j: (alpha[i, j], c[i, j], j))[:k]
        assert table[i].tolist() == expected


def test_candidate_table_picks_alpha_only_for_finite_symmetric_and_large():
    rng = np.random.default_rng(7)
    pts = rng.random((ALPHA_FROM, 2)) * 100
    m = np.floor(_euclidean(pts) + 0.5)
    assert np.array_equal(candidate_table(m, 6), alpha_neighbour_table(m, 6))
    assert np.array_equal(candidate_table(m, 6), candidate_table(m.copy(), 6))  # deterministic
    small = m[:ALPHA_FROM - 1, :ALPHA_FROM - 1]
    assert np.array_equal(candidate_table(small, 6), neighbour_table(small, 6))
    skew = m.copy()
    skew[0, 1] += 1.0
    assert np.array_equal(candidate_table(skew, 6), neighbour_table(skew, 6))
    holed = m.copy()
    holed[2, 3] = holed[3, 2] = np.inf
    assert np.array_equal(candidate_table(holed, 6), neighbour_table(holed, 6))


def test_candidate_table_takes_the_nearest_again_from_alpha_until():
    from subtask_opt.tour.bound import ALPHA_UNTIL

    pts = np.random.default_rng(8).random((ALPHA_UNTIL, 2)) * 100
    m = _euclidean(pts)
    assert np.array_equal(candidate_table(m, 6), neighbour_table(m, 6))


def test_alpha_table_bad_inputs():
    m = np.ones((5, 5))
    with pytest.raises(ParameterError, match="k"):
        alpha_neighbour_table(m, 0)
    with pytest.raises(ParameterError, match="iterations"):
        alpha_neighbour_table(m, 2, iterations=-1)
    with pytest.raises(InputDataError):
        alpha_neighbour_table(np.ones((2, 2)), 1)

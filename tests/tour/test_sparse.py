"""The candidate-leg GTSP search and its bound against exact oracles (branch and cut)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from subtask_opt.base.errors import ParameterError
from subtask_opt.tour import sparse as ts
from subtask_opt.tour.exact import gtsp_optimum


def _instance(seed: int, n: int, k_conf: int, k_nbr: int):
    """Targets in the plane, each with k_conf configurations (points near it): legs are
    distances between configuration points; the home a point of its own."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(0, 1, (n, 2))
    pos = np.repeat(pts, k_conf, axis=0) + rng.uniform(-0.15, 0.15, (n * k_conf, 2))
    off = np.arange(0, n * k_conf + 1, k_conf, dtype=np.int64)
    full = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    home_point = np.array([0.5, -0.2])
    home = np.linalg.norm(pos - home_point, axis=1)
    _, idx = cKDTree(pts).query(pts, k=min(k_nbr, n - 1) + 1)
    pairs = {(a, int(b)) for a in range(n) for b in idx[a] if b != a}
    pairs |= {(b, a) for a, b in pairs}
    lists: list[list[int]] = [[] for _ in range(n)]
    for a, b in sorted(pairs):
        lists[a].append(b)
    width = max(len(x) for x in lists)
    nbr = np.full((n, width), -1, dtype=np.int64)
    start = np.full((n, width), -1, dtype=np.int64)
    legs: list[float] = []
    for a in range(n):
        for s, b in enumerate(lists[a]):
            nbr[a, s], start[a, s] = b, len(legs)
            legs.extend(full[off[a]:off[a + 1], off[b]:off[b + 1]].ravel())
    data = ts.SparseLegs(off, nbr, start, np.array(legs), home, pts, 1e3)
    return data, full, home, pos, pts, idx


def _exact(full, home, n, k_conf):
    m = full.shape[0]
    cost = np.zeros((m + 1, m + 1))
    cost[:m, :m] = full
    cost[m, :m] = cost[:m, m] = home
    clusters = np.append(np.repeat(np.arange(n), k_conf), n)
    return gtsp_optimum(cost, clusters, time_limit=60)[0]


@pytest.mark.parametrize("seed", range(4))
def test_search_finds_the_branch_and_cut_optimum_on_small_cases(seed):
    n, k = 8, 3
    data, full, home, *_ = _instance(seed, n, k, n - 1)  # every pair a candidate
    out = ts.search(data, seed=seed, kicks=300)
    assert out.cost == pytest.approx(_exact(full, home, n, k), rel=1e-9)
    # the reported time is the tour's, recomputed from the full matrix
    off = data.offsets
    nodes = [off[t] + out.choice[t] for t in out.tour[1:-1]]
    steps = zip(nodes[:-1], nodes[1:], strict=True)
    again = home[nodes[0]] + home[nodes[-1]] + sum(full[a, b] for a, b in steps)
    assert out.cost == pytest.approx(again, rel=1e-12)


def test_same_seed_same_answer():
    data, *_ = _instance(9, 30, 3, 6)
    a = ts.search(data, seed=5, kicks=200)
    b = ts.search(data, seed=5, kicks=200)
    assert np.array_equal(a.tour, b.tour) and np.array_equal(a.choice, b.choice)
    assert a.cost == b.cost


@pytest.mark.parametrize("seed", range(5))
def test_bound_on_candidate_edges_stays_below_the_optimum(seed):
    """Only the 2 nearest pairs are known exactly; every other pair costs at least the
    distance to the target's 2nd nearest minus twice the configurations' spread (0.15
    sqrt 2 each): the bound must stay below the branch-and-cut optimum."""
    n, k = 8, 3
    data, full, home, pos, pts, _ = _instance(seed, n, k, n - 1)
    dist, idx = cKDTree(pts).query(pts, k=3)
    edges = np.unique(np.sort(np.array([(a, int(b)) for a in range(n) for b in idx[a, 1:]]),
                                 axis=1), axis=0)
    weights = np.array([full[data.offsets[a]:data.offsets[a + 1],
                             data.offsets[b]:data.offsets[b + 1]].min() for a, b in edges])
    rho = np.maximum(dist[:, 2] - 2 * 0.15 * np.sqrt(2), 0.0)
    home_min = np.minimum.reduceat(home, data.offsets[:-1])
    optimum = _exact(full, home, n, k)
    # every non-edge really costs at least (rho_a + rho_b) / 2: the oracle of the premise
    known = {tuple(e) for e in edges.tolist()}
    for a in range(n):
        for b in range(a + 1, n):
            if (a, b) not in known:
                o = data.offsets
                block = full[o[a]:o[a + 1], o[b]:o[b + 1]]
                assert block.min() >= 0.5 * (rho[a] + rho[b]) - 1e-12
    bound = ts.one_tree_bound(n, edges, weights, rho, home_min, upper=optimum * 1.2)
    assert 0 < bound <= optimum * (1 + 1e-9)


def test_bound_with_every_edge_is_close_on_a_metric_instance():
    """With every pair exact, the 1-tree bound of a near-Euclidean instance is within a
    few percent of the optimum (and below it)."""
    n, k = 9, 1
    data, full, home, *_ = _instance(3, n, k, n - 1)
    edges = np.array([(a, b) for a in range(n) for b in range(a + 1, n)])
    weights = full[edges[:, 0], edges[:, 1]]
    optimum = _exact(full, home, n, k)
    bound = ts.one_tree_bound(n, edges, weights, np.full(n, np.inf), home, upper=optimum)
    assert 0.85 * optimum <= bound <= optimum * (1 + 1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_bound_with_every_edge_equals_the_dense_held_karp_bound(seed):
    """A second method: with every pair exact (60 targets, 1,770 edges, so the ascent
    steers over each target's cheap edges first), the bound equals the Held-Karp bound
    of the (N + 1) x (N + 1) matrix of target-level cheapest legs and the home
    (tour.bound.lower_bound) to 0.1%, and stays below a tour of that matrix."""
    from subtask_opt.tour.bound import lower_bound

    n, k = 60, 2
    data, full, home, *_ = _instance(seed, n, k, n - 1)
    off = data.offsets
    cheapest = np.array([[full[off[a]:off[a + 1], off[b]:off[b + 1]].min()
                          for b in range(n)] for a in range(n)])
    home_min = np.minimum.reduceat(home, off[:-1])
    matrix = np.zeros((n + 1, n + 1))
    matrix[:n, :n] = cheapest
    matrix[n, :n] = matrix[:n, n] = home_min
    edges = np.array([(a, b) for a in range(n) for b in range(a + 1, n)])
    assert edges.shape[0] > ts.ASCENT_EDGES * n  # the two-phase ascent runs
    tour = np.concatenate([[n], np.argsort(np.arctan2(*(data.coords - 0.5).T)), [n]])
    upper = float(matrix[tour[:-1], tour[1:]].sum())
    bound = ts.one_tree_bound(n, edges, cheapest[edges[:, 0], edges[:, 1]],
                              np.full(n, np.inf), home_min, upper=upper)
    held_karp = lower_bound(matrix, seed=0)
    assert bound <= upper * (1 + 1e-9)
    assert bound == pytest.approx(held_karp, rel=1e-3)


def test_cheapest_edges_are_each_nodes_k_cheapest():
    """Brute force: an edge is kept when it is among the k cheapest of either node."""
    rng = np.random.default_rng(5)
    n, k = 12, 3
    edges = np.array([(a, b) for a in range(n) for b in range(a + 1, n) if rng.random() < 0.6])
    weights = rng.permutation(edges.shape[0]).astype(float)  # distinct weights
    keep = ts._cheapest_edges(n, edges, weights, k)
    expected = np.zeros(edges.shape[0], dtype=bool)
    for node in range(n):
        mine = np.flatnonzero((edges == node).any(axis=1))
        expected[mine[np.argsort(weights[mine])[:k]]] = True
    np.testing.assert_array_equal(keep, expected)


def test_bad_inputs_are_refused():
    data, *_ = _instance(1, 6, 2, 3)
    with pytest.raises(ParameterError, match="seed"):
        ts.search(data, seed=-1, kicks=1)
    with pytest.raises(ParameterError, match="kicks"):
        ts.search(data, seed=0, kicks=-3)
    with pytest.raises(ParameterError, match="tour"):
        ts.search(data, seed=0, kicks=0, tour=np.arange(8))
    with pytest.raises(ParameterError, match="upper"):
        ts.one_tree_bound(6, np.zeros((0, 2)), np.zeros(0), np.zeros(6), np.ones(6),
                          upper=float("nan"))
    with pytest.raises(ParameterError, match="weights"):
        ts.one_tree_bound(6, np.zeros((2, 2)), np.zeros(1), np.zeros(6), np.ones(6), upper=1.0)


def test_jumps_between_targets_that_are_not_candidates_are_kept_short():
    """Two rows of targets, legs stored only within a row: a tour crosses between the
    rows once through the home and once by a leg that is not stored. That leg costs the
    penalty plus the targets' distance, so the search ends where the branch and cut on
    those times does (straight across), not with any crossing."""
    k_conf = 2
    pts = np.array([[x, y] for y in (0.0, 3.0) for x in np.linspace(0.0, 2.0, 5)])
    rng = np.random.default_rng(3)
    pos = np.repeat(pts, k_conf, axis=0) + rng.uniform(-0.1, 0.1, (10 * k_conf, 2))
    full = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    home = np.linalg.norm(pos - np.array([1.0, 1.5]), axis=1)
    row = np.arange(10) // 5
    nbr = np.array([[b for b in range(10) if b != a and row[b] == row[a]] for a in range(10)])
    start = np.arange(10 * 4).reshape(10, 4) * k_conf * k_conf
    off = np.arange(0, 10 * k_conf + 1, k_conf, dtype=np.int64)
    legs = np.concatenate([full[off[a]:off[a + 1], off[b]:off[b + 1]].ravel()
                           for a in range(10) for b in nbr[a]])
    sparse = ts.SparseLegs(off, nbr, start, legs, home, pts, 1e3)
    jump = 1e3 + np.linalg.norm(pts[:, None] - pts[None], axis=2)
    graded = full.copy()
    for a in range(10):
        for b in range(10):
            if row[a] != row[b]:
                graded[off[a]:off[a + 1], off[b]:off[b + 1]] = jump[a, b]
    assert ts.leg(sparse, 0, 1, 9, 0) == pytest.approx(jump[0, 9], rel=1e-12)
    out = ts.search(sparse, seed=0, kicks=300)
    assert out.cost == pytest.approx(_exact(graded, home, 10, k_conf), rel=1e-9)
    crossings = [(a, b) for a, b in zip(out.tour[1:-2], out.tour[2:-1], strict=True)
                 if row[a] != row[b]]
    assert len(crossings) == 1  # the other crossing goes through the home
    assert pts[crossings[0][0]][0] == pts[crossings[0][1]][0]  # straight across

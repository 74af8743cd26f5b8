"""The generalised-TSP branch and cut against brute force and a plain subtour MILP."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError, SubtaskOptError
from subtask_opt.tour.exact import _pair_cuts, gtsp_optimum, milp_optimum
from tests.conftest import SHARED_DATA

SHARED_GTSPLIB = SHARED_DATA / "gtsplib"


def _instance(seed: int, sizes: list[int], metric: bool) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric costs over nodes of clusters of the given sizes (Euclidean or random)."""
    rng = np.random.default_rng(seed)
    clusters = np.repeat(np.arange(len(sizes)), sizes)
    rng.shuffle(clusters)  # the solver must not rely on nodes grouped by cluster
    m = len(clusters)
    if metric:
        pts = rng.random((m, 2))
        cost = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    else:
        cost = rng.random((m, m)) * 10
        cost = cost + cost.T
        np.fill_diagonal(cost, 0.0)
    return cost, clusters


def _brute_force(cost: np.ndarray, clusters: np.ndarray) -> float:
    n = int(clusters.max()) + 1
    members = [np.flatnonzero(clusters == k) for k in range(n)]
    best = np.inf
    for rest in itertools.permutations(range(1, n)):
        order = (0, *rest)
        for nodes in itertools.product(*(members[k] for k in order)):
            tour = np.array(nodes)
            best = min(best, float(cost[tour, np.roll(tour, -1)].sum()))
    return best


def _check_answer(cost, clusters, value, order, nodes):
    n = int(clusters.max()) + 1
    assert sorted(order.tolist()) == list(range(n)) and order[0] == 0
    assert np.array_equal(clusters[nodes], order)
    assert value == pytest.approx(float(cost[nodes, np.roll(nodes, -1)].sum()), rel=1e-12)


@pytest.mark.parametrize("seed", range(8))
def test_equals_brute_force_on_small_instances(seed):
    rng = np.random.default_rng(100 + seed)
    sizes = rng.integers(1, 4, size=int(rng.integers(3, 8))).tolist()  # 3..7 clusters of 1..3
    cost, clusters = _instance(seed, sizes, metric=seed % 2 == 0)
    value, order, nodes = gtsp_optimum(cost, clusters)
    _check_answer(cost, clusters, value, order, nodes)
    assert value == pytest.approx(_brute_force(cost, clusters), rel=1e-9)


def _plain_gtsp_milp(cost: np.ndarray, clusters: np.ndarray) -> float:
    """A second formulation: degree rows, then cluster subtour cuts on integer answers only."""
    import highspy

    m, n = len(clusters), int(clusters.max()) + 1
    iu, ju = np.triu_indices(m, 1)
    keep = clusters[iu] != clusters[ju]
    iu, ju = iu[keep], ju[keep]
    ne = len(iu)
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("mip_rel_gap", 0.0)
    empty = np.array([], dtype=np.int32)
    h.addCols(ne + m, np.concatenate([cost[iu, ju], np.zeros(m)]), np.zeros(ne + m),
              np.ones(ne + m), 0, empty, empty, np.array([]))
    h.changeColsIntegrality(ne + m, np.arange(ne + m, dtype=np.int32),
                            np.full(ne + m, highspy.HighsVarType.kInteger))
    for k in range(n):
        idx = (ne + np.flatnonzero(clusters == k)).astype(np.int32)
        h.addRow(1.0, 1.0, len(idx), idx, np.ones(len(idx)))
    for v in range(m):
        idx = np.append(np.flatnonzero((iu == v) | (ju == v)), ne + v).astype(np.int32)
        vals = np.append(np.ones(len(idx) - 1), -2.0)
        h.addRow(0.0, 0.0, len(idx), idx, vals)
    for _ in range(200):
        h.run()
        assert h.getModelStatus() == highspy.HighsModelStatus.kOptimal
        x = np.asarray(h.getSolution().col_value)[:ne] > 0.5
        label = np.arange(n)  # clusters joined by the chosen edges
        for a, b in zip(clusters[iu[x]], clusters[ju[x]], strict=True):
            label[label == label[b]] = label[a]
        if len(np.unique(label)) == 1:
            return float(cost[iu[x], ju[x]].sum())
        for comp in np.unique(label):
            inside = np.isin(clusters, np.flatnonzero(label == comp))
            idx = np.flatnonzero(inside[iu] != inside[ju]).astype(np.int32)
            h.addRow(2.0, highspy.kHighsInf, len(idx), idx, np.ones(len(idx)))
    raise AssertionError("the plain MILP found no single tour in 200 rounds of cuts")


@pytest.mark.parametrize("seed", range(3))
def test_equals_plain_milp_on_medium_instances(seed):
    cost, clusters = _instance(seed, [2] * 9 + [1, 3], metric=True)
    value, order, nodes = gtsp_optimum(cost, clusters)
    _check_answer(cost, clusters, value, order, nodes)
    assert value == pytest.approx(_plain_gtsp_milp(cost, clusters), rel=1e-9)


def test_one_node_per_cluster_is_the_tsp():
    cost, clusters = _instance(7, [1] * 18, metric=True)
    value, _, nodes = gtsp_optimum(cost, clusters)
    assert value == pytest.approx(milp_optimum(cost)[0], rel=1e-9)
    assert len(nodes) == 18


def test_an_incumbent_only_prunes():
    cost, clusters = _instance(3, [2] * 12, metric=True)
    value = gtsp_optimum(cost, clusters)[0]
    bad = np.array([np.flatnonzero(clusters == k)[-1] for k in range(12)])  # any tour
    best = np.roll(gtsp_optimum(cost, clusters)[2][::-1], 5)  # the optimum, turned round
    for incumbent in (bad, best):
        answer = gtsp_optimum(cost, clusters, incumbent=incumbent)
        _check_answer(cost, clusters, *answer)
        assert answer[0] == pytest.approx(value, rel=1e-12)


def _brute_pair_minimum(w, y, clusters, i, j):
    """min over node sets S of x(delta(S)) + 2 y(C_i - S) + 2 y(C_j & S)."""
    m = len(clusters)
    best = np.inf
    for bits in range(1 << m):
        side = (bits >> np.arange(m)) & 1 == 1
        value = (w[side][:, ~side].sum() + 2 * y[(clusters == i) & ~side].sum()
                 + 2 * y[(clusters == j) & side].sum())
        best = min(best, value)
    return best


@pytest.mark.parametrize("seed", range(5))
def test_pair_cut_separation_is_exact(seed):
    rng = np.random.default_rng(seed)
    clusters = np.repeat(np.arange(4), [2, 3, 2, 2])  # grouped, as the kernel wants
    start = np.array([0, 2, 5, 7, 9])
    m = len(clusters)
    w = rng.random((m, m)) * (rng.random((m, m)) < 0.4)
    w = np.triu(w, 1)
    w = w + w.T
    w[clusters[:, None] == clusters[None, :]] = 0.0
    y = rng.random(m)
    for k in range(4):
        y[start[k]:start[k + 1]] /= y[start[k]:start[k + 1]].sum()
    pairs, values, sides = _pair_cuts(w, y, start, 1e-9)
    reported = {(int(i), int(j)): (v, s) for (i, j), v, s in zip(pairs, values, sides,
                                                                 strict=True)}
    for i, j in itertools.combinations(range(4), 2):
        expected = _brute_pair_minimum(w, y, clusters, i, j)
        if expected < 2 - 1e-6:
            value, side = reported[(i, j)]
            assert value == pytest.approx(expected, abs=1e-9)
            assert (w[side][:, ~side].sum() + 2 * y[(clusters == i) & ~side].sum()
                    + 2 * y[(clusters == j) & side].sum()) == pytest.approx(value, abs=1e-9)
        elif expected > 2 + 1e-6:
            assert (i, j) not in reported


def test_bad_inputs():
    cost, clusters = _instance(0, [2, 2, 2], metric=True)
    with pytest.raises(ParameterError, match="symmetric"):
        gtsp_optimum(cost + np.triu(np.ones_like(cost)), clusters)
    with pytest.raises(ParameterError, match="one per node"):
        gtsp_optimum(cost, clusters[:-1])
    with pytest.raises(ParameterError, match="every cluster"):
        gtsp_optimum(cost, np.where(clusters == 1, 5, clusters))
    with pytest.raises(ParameterError, match="every cluster"):
        gtsp_optimum(cost[:4, :4], np.array([0, 0, 1, 1]))
    with pytest.raises(ParameterError, match="time_limit"):
        gtsp_optimum(cost, clusters, time_limit=0)
    with pytest.raises(ParameterError, match="incumbent"):
        gtsp_optimum(cost, clusters, incumbent=np.flatnonzero(clusters != 2))
    with pytest.raises(ParameterError, match="incumbent"):
        gtsp_optimum(cost, clusters, incumbent=[0, 2, 99])


def test_time_limit_is_reported():
    cost, clusters = _instance(1, [2] * 40, metric=False)
    with pytest.raises(SubtaskOptError, match="not proven"):
        gtsp_optimum(cost, clusters, time_limit=1e-3)


@pytest.mark.parametrize("seed", range(6))
def test_lp_bound_never_passes_the_brute_force_optimum(seed):
    from subtask_opt.tour.bound import lower_bound
    from subtask_opt.tour.exact import gtsp_lp_bound

    rng = np.random.default_rng(300 + seed)
    sizes = rng.integers(1, 4, size=int(rng.integers(4, 8))).tolist()
    cost, clusters = _instance(seed, sizes, metric=seed % 2 == 0)
    optimum = _brute_force(cost, clusters)
    bound = gtsp_lp_bound(cost, clusters)
    assert bound <= optimum * (1 + 1e-9)
    # at least the Held-Karp bound of the cheapest arcs between the clusters, up to the
    # subgradient's own slack (its bound is of a relaxation of that LP)
    n = len(sizes)
    between = np.full((n, n), np.inf)
    for i in range(n):
        for j in range(n):
            between[i, j] = 0.0 if i == j else cost[np.ix_(clusters == i, clusters == j)].min()
    assert bound >= lower_bound(between, seed=0) * (1 - 1e-6)


@pytest.mark.skipif(not (SHARED_GTSPLIB / "11eil51.gtsp").is_file(),
                    reason="shared GTSPLIB data not present")
def test_lp_bound_of_overlapping_sets_beats_the_cluster_bound():
    from subtask_opt.tour.exact import gtsp_lp_bound, gtsp_set_optimum
    from subtask_opt.tour.gtsplib import read_gtsplib

    instance = read_gtsplib(SHARED_GTSPLIB / "11eil51.gtsp")
    optimum, _ = gtsp_set_optimum(instance.problem())  # branch and cut: 174
    bound = gtsp_lp_bound(instance.weights, instance.sets)
    assert bound <= optimum * (1 + 1e-9)
    assert bound > 0.9 * optimum  # the cheapest arcs between the sets bound it at 98
    with pytest.raises(ParameterError, match="symmetric"):
        gtsp_lp_bound(np.triu(np.ones((4, 4))), np.arange(4))

"""The pinned clustered kind (precedence with one node of every cluster chosen during the
search) against brute force, the clustered Held-Karp programme and the arc MILP; every
answer's precedence checked from the positions in its order, not by the solver's check."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.tour import pinned_clustered as pc
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.exact import clustered_held_karp, milp_pinned_clustered
from subtask_opt.tour.gtsplib import read_gtsplib, solve_gtsp
from subtask_opt.tour.problem import ClusteredProblem, GtspProblem
from subtask_opt.tour.solve import solve
from tests.conftest import SHARED_DATA

PCGTSP = SHARED_DATA / "pcgtsp"


def _instance(seed: int, n_sets: int, *, symmetric: bool, forbid: float = 0.0):
    """Vertices in sets of 1-3 (every set one at least), integer weights."""
    rng = np.random.default_rng(seed)
    sets = np.concatenate([np.arange(n_sets), rng.integers(0, n_sets, n_sets)])
    rng.shuffle(sets)
    m = len(sets)
    if symmetric:
        pts = rng.integers(0, 100, (m, 2))
        w = np.floor(np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1)) + 0.5)
    else:
        w = rng.integers(1, 100, (m, m)).astype(float)
    if forbid:
        w[rng.random((m, m)) < forbid] = np.inf
    np.fill_diagonal(w, 0.0)
    return w, sets


def _pairs(seed: int, n: int, count: int, start: int = 0) -> list[tuple[int, int]]:
    """Acyclic pairs a -> b (a before b in a random ranking), none into ``start``."""
    rng = np.random.default_rng(seed + 1000)
    rank = rng.permutation(n)
    out = set()
    for _ in range(count):
        a, b = (int(v) for v in rng.choice(n, 2, replace=False))
        if rank[a] > rank[b]:
            a, b = b, a
        if b != start:
            out.add((a, b))
    return sorted(out)


def _brute_force(w, sets, c: TourConstraints, start: int = 0) -> float:
    """The cheapest tour of the shape ``c`` (closed; open with a free or fixed end) from
    set ``start``, one vertex of every set, keeping the pairs: every order, every vertex."""
    n = int(sets.max()) + 1
    members = [np.flatnonzero(sets == k) for k in range(n)]
    best = math.inf
    for perm in itertools.permutations([k for k in range(n) if k != start]):
        order = (start, *perm)
        pos = {s: i for i, s in enumerate(order)}
        if any(pos[a] > pos[b] for a, b in c.precedence):
            continue
        if c.end is not None and order[-1] != c.end:
            continue
        for choice in itertools.product(*(members[s] for s in order)):
            v = np.array(choice)
            cost = float(w[v[:-1], v[1:]].sum())
            if c.tour == "closed":
                cost += float(w[v[-1], v[0]])
            best = min(best, cost)
    return best


def _keeps(order, c: TourConstraints, start: int = 0) -> bool:
    pos = {int(s): i for i, s in enumerate(order)}
    return (int(order[0]) == start and all(pos[a] < pos[b] for a, b in c.precedence)
            and (c.end is None or int(order[-1]) == c.end))


SHAPES = ("closed", "open", "open to an end")


def _shape(kind: str, pairs, n: int) -> TourConstraints:
    if kind == "closed":
        return TourConstraints(precedence=pairs)
    if kind == "open":
        return TourConstraints(tour="open", precedence=pairs)
    end = max(v for v in range(1, n) if all(a != v for a, _ in pairs))
    return TourConstraints(tour="open", end=end, precedence=pairs)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("symmetric", [True, False])
def test_gtsp_with_precedence_reaches_the_brute_force_optimum(seed, shape, symmetric):
    w, sets = _instance(seed, 7, symmetric=symmetric, forbid=0.0 if symmetric else 0.1)
    c = _shape(shape, _pairs(seed, 7, 4), 7)
    expected = _brute_force(w, sets, c)
    # lns_steps 0: the local search alone (the arm problems' search); None: with LNS
    result = solve(GtspProblem(w, sets, lns_steps=0 if seed % 2 else None), seed=seed,
                   constraints=c)
    assert _keeps(result.order, c)
    tour = result.configurations[result.order]
    assert np.array_equal(np.sort(sets[tour]), np.arange(7))
    legs = w[tour[:-1], tour[1:]].sum() + (w[tour[-1], tour[0]] if shape == "closed" else 0)
    assert result.total_time == pytest.approx(float(legs))
    assert result.total_time == pytest.approx(expected)


def _two_elbow_tensor(seed: int, n: int) -> np.ndarray:
    """An (N, 2, N, 2) symmetric leg-time tensor of two nodes per cluster (points)."""
    rng = np.random.default_rng(seed)
    centre = rng.random((n, 2))
    nodes = centre[:, None, :] + 0.08 * rng.standard_normal((n, 2, 2))
    flat = nodes.reshape(2 * n, 2)
    legs = np.hypot(*(flat[:, None] - flat[None]).transpose(2, 0, 1))
    return legs.reshape(n, 2, n, 2)


def _held_karp_closed(tensor: np.ndarray, first: int, pairs) -> float:
    """Closed tour from cluster ``first`` by the clustered Held-Karp programme: each node of
    ``first`` in turn is the start outside the other clusters."""
    n = tensor.shape[0]
    rest = [k for k in range(n) if k != first]
    index = {k: i for i, k in enumerate(rest)}
    legs = tensor[np.ix_(rest, [0, 1], rest, [0, 1])].reshape(2 * (n - 1), 2 * (n - 1))
    inner = np.array([(index[a], index[b]) for a, b in pairs if a != first],
                     dtype=np.int64).reshape(-1, 2)
    offsets = np.arange(0, 2 * n - 1, 2)
    best = math.inf
    for c0 in range(2):
        start = tensor[first, c0][rest].reshape(-1)
        back = tensor[rest, :, first, c0].reshape(-1)
        best = min(best, clustered_held_karp(legs, offsets, start, back, pairs=inner))
    return best


@pytest.mark.parametrize("seed", range(3))
def test_clustered_problem_with_precedence_matches_held_karp(seed):
    n = 11
    tensor = _two_elbow_tensor(seed, n)
    pairs = _pairs(seed, n, 8, start=2)
    c = TourConstraints(start=2, precedence=pairs)
    result = solve(ClusteredProblem(tensor), seed=seed, constraints=c)
    assert _keeps(result.order, c, start=2)
    assert result.total_time == pytest.approx(_held_karp_closed(tensor, 2, pairs), rel=1e-9)
    assert result.lower_bound is not None and result.lower_bound <= result.total_time


@pytest.mark.parametrize("seed", range(4))
def test_milp_pinned_clustered_equals_brute_force(seed):
    w, sets = _instance(seed + 50, 6, symmetric=False, forbid=0.1)
    pairs = _pairs(seed, 6, 3)
    last = 5 if seed % 2 and all(a != 5 for a, _ in pairs) else -1
    # a closed tour whose last set is pinned: brute force over the closed tours ending there
    n = 6
    members = [np.flatnonzero(sets == k) for k in range(n)]
    expected = math.inf
    for perm in itertools.permutations(range(1, n)):
        pos = {s: i for i, s in enumerate((0, *perm))}
        if any(pos[a] > pos[b] for a, b in pairs) or (last >= 0 and perm[-1] != last):
            continue
        for choice in itertools.product(*(members[s] for s in (0, *perm))):
            v = np.array(choice)
            expected = min(expected, float(w[v, np.roll(v, -1)].sum()))
    cost, order, nodes = milp_pinned_clustered(w, sets, 0, last, pairs)
    assert cost == pytest.approx(expected)
    assert order[0] == 0 and sorted(order.tolist()) == list(range(n))
    assert np.array_equal(sets[nodes], order)
    assert all(list(order).index(a) < list(order).index(b) for a, b in pairs)
    assert float(w[nodes, np.roll(nodes, -1)].sum()) == pytest.approx(cost)


def test_milp_agrees_with_the_search_on_twelve_elbow_clusters():
    n = 12
    tensor = _two_elbow_tensor(7, n)
    pairs = _pairs(7, n, 6)
    cost, _, _ = milp_pinned_clustered(tensor.reshape(2 * n, 2 * n), np.repeat(np.arange(n), 2),
                                       0, -1, pairs, time_limit=120)
    result = solve(ClusteredProblem(tensor), seed=3, constraints=TourConstraints(
        precedence=pairs))
    assert result.total_time == pytest.approx(cost, rel=1e-9)


def test_every_operator_keeps_the_pairs():
    from subtask_opt.ga.kinds import Kind

    w, sets = _instance(3, 9, symmetric=False)
    problem = GtspProblem(w, sets)
    pairs = np.array(_pairs(3, 9, 10), dtype=np.int64)
    data = pc.make_data(problem.configured_data().dist, problem.configured_data(), lns=3)
    aux = pc.make_pinned_clustered_aux(9, 0, 4 if all(a != 4 for a, _ in pairs) else -1, pairs)
    rng = np.random.default_rng(0)
    tours = []
    best = np.zeros(9, dtype=np.int64)
    for k in range(12):
        g = np.empty(9, dtype=np.int64)
        pc.randomize(g, data, aux, rng, best, 9 if k else 0)
        best = g.copy() if k == 0 else best
        tours.append(g)
    for a, b in itertools.combinations(range(len(tours)), 2):
        child = np.empty(9, dtype=np.int64)
        pc.crossover(tours[a], 9, tours[b], 9, data, aux, rng, child)
        tours.append(child)
    for t in tours:
        assert sorted(t.tolist()) == list(range(9))
        pos = {int(s): i for i, s in enumerate(t)}
        assert t[0] == 0 and (aux.last < 0 or t[-1] == aux.last)
        assert all(pos[a] < pos[b] for a, b in pairs.tolist())
        assert math.isfinite(pc.tour_cost(t, 9, data, aux))
    assert Kind.PINNED_CLUSTERED.name == "PINNED_CLUSTERED"


def test_precedence_closure_holds_every_implied_pair():
    closure = {tuple(p) for p in pc.precedence_closure(6, np.array([[0, 1], [1, 2], [4, 3]]))
               .tolist()}
    assert closure == {(0, 1), (1, 2), (0, 2), (4, 3)}


def test_same_seed_same_answer():
    w, sets = _instance(9, 10, symmetric=True)
    c = TourConstraints(precedence=_pairs(9, 10, 6))
    a = solve(GtspProblem(w, sets), seed=4, constraints=c)
    b = solve(GtspProblem(w, sets), seed=4, constraints=c)
    assert np.array_equal(a.order, b.order) and a.total_time == b.total_time
    assert np.array_equal(a.configurations, b.configurations)


@pytest.mark.skipif(not PCGTSP.is_dir(), reason="shared PCGTSP data not present")
@pytest.mark.parametrize(("name", "optimum"), [("ESC12", 1390), ("ESC25", 1383),
                                               ("rbg048a", 282)])
def test_pcgtsp_reaches_the_proven_optimum(name, optimum):
    from subtask_opt.base.stop import NoImprovement, TargetCost

    instance = read_gtsplib(PCGTSP / f"{name}.pcglns")
    # stop at the optimum (the Gurobi-proven values of reference.json) or after a stall
    solution = solve_gtsp(instance, time_limit=30.0, seed=1, runs=1,
                          stop=[TargetCost(optimum + 1e-9), NoImprovement(200)])
    assert instance.violations(solution.tour) == []
    assert solution.cost == optimum


@pytest.mark.parametrize("shape", SHAPES)
def test_certify_proves_the_precedence_optimum(shape):
    w, sets = _instance(21, 6, symmetric=False, forbid=0.1)
    c = _shape(shape, _pairs(21, 6, 3), 6)
    result = solve(GtspProblem(w, sets), seed=0, constraints=c, certify=True)
    assert result.total_time == pytest.approx(_brute_force(w, sets, c))
    assert result.certified == "optimal (proven)"
    tensor = _two_elbow_tensor(22, 6)
    clustered = solve(ClusteredProblem(tensor), seed=0, constraints=c, certify=True)
    assert clustered.certified == "optimal (proven)"
    flat = tensor.reshape(12, 12)
    assert clustered.total_time == pytest.approx(
        _brute_force(flat, np.repeat(np.arange(6), 2), c), rel=1e-9)

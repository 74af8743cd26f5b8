"""The lazily verified tour core (`tour.lazy`) against brute force over the true leg times."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.tour import sparse as ts
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.lazy import LazyLegsProblem, LegVerifier
from subtask_opt.tour.solve import SolverParams, solve

PENALTY = 1e3


def _points(seed: int, n: int, k: int):
    """n targets in the plane with k configurations each (points near the target); legs
    are distances, the home a point of its own."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(0, 1, (n, 2))
    pos = np.repeat(pts, k, axis=0) + rng.uniform(-0.15, 0.15, (n * k, 2))
    offsets = np.arange(0, n * k + 1, k, dtype=np.int64)
    legs = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    home = np.linalg.norm(pos - np.array([0.5, -0.2]), axis=1)
    return offsets, legs, home, pts


class _Corrections(LegVerifier):
    """Legs that really cost more (``factor``) or are impossible (``math.inf``)."""

    def __init__(self, true: dict[tuple[int, int], float], crowd_after: int | None = None):
        self.true = true
        self.asked: list[tuple[int, int]] = []
        self.crowd_after = crowd_after
        self.forgotten = 0

    def verify(self, a: int, b: int) -> float | None:
        assert a < b
        self.asked.append((a, b))
        return self.true.get((a, b))

    def crowded(self) -> bool:
        return self.crowd_after is not None and len(self.asked) > self.crowd_after

    def forget(self) -> None:
        self.forgotten += 1
        self.crowd_after = None  # once


def _true_costs(offsets, legs, home, true):
    """The leg times after every correction (impossible: inf)."""
    legs, home = legs.copy(), home.copy()
    for (a, b), value in true.items():
        if a < 0:
            home[b] = value
        else:
            legs[a, b] = legs[b, a] = value
    return legs, home


def _corrections(seed, offsets, legs, home, share=0.25):
    """A random quarter of the legs (home legs too) longer or impossible."""
    rng = np.random.default_rng(seed + 100)
    m = legs.shape[0]
    owner = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    true = {}
    for a in range(-1, m):
        for b in range(a + 1, m):
            if a >= 0 and owner[a] == owner[b]:
                continue
            if rng.random() < share:
                old = home[b] if a < 0 else legs[a, b]
                true[(a, b)] = math.inf if rng.random() < 0.5 else 2.5 * old
    return true


def _brute(offsets, legs, home, *, open_path=False, pairs=(), last=None):
    """The optimum over every order and configuration (inf legs impossible)."""
    n = len(offsets) - 1
    best = math.inf
    for order in itertools.permutations(range(n)):
        pos = {t: i for i, t in enumerate(order)}
        if any(pos[a] > pos[b] for a, b in pairs) or (last is not None and order[-1] != last):
            continue
        for choice in itertools.product(*[range(offsets[t], offsets[t + 1])
                                          for t in range(n)]):
            nodes = [choice[t] for t in order]
            cost = home[nodes[0]] + sum(legs[a, b] for a, b in zip(nodes[:-1], nodes[1:],
                                                                    strict=True))
            if not open_path:
                cost += home[nodes[-1]]
            best = min(best, cost)
    return best


def _dense(offsets, legs, home, verifier=None):
    legs = np.ascontiguousarray(legs, dtype=np.float64).copy()
    n = len(offsets) - 1
    dist = np.array([[0.0 if a == b else legs[offsets[a]:offsets[a + 1],
                                              offsets[b]:offsets[b + 1]].min()
                      for b in range(n)] for a in range(n)])
    cheapest = np.array([[legs[offsets[v]:offsets[v + 1], c].min() for c in range(len(home))]
                         for v in range(n)])
    return LazyLegsProblem(offsets, home.copy(), PENALTY, legs=legs, dist=dist,
                           cheapest=cheapest, verifier=verifier)


def _tour_cost(result, offsets, legs, home, open_path=False):
    nodes = [offsets[t] + result.configurations[t] for t in result.order]
    cost = home[nodes[0]] + sum(legs[a, b] for a, b in zip(nodes[:-1], nodes[1:], strict=True))
    return cost + (0.0 if open_path else home[nodes[-1]])


@pytest.mark.parametrize("seed", range(3))
def test_dense_answer_is_the_optimum_of_the_true_legs(seed):
    offsets, legs, home, _ = _points(seed, 6, 2)
    true = _corrections(seed, offsets, legs, home)
    verifier = _Corrections(true)
    problem = _dense(offsets, legs, home, verifier)
    before = problem.legs.copy()
    result = solve(problem, seed=seed)
    true_legs, true_home = _true_costs(offsets, legs, home, true)
    optimum = _brute(offsets, true_legs, true_home)
    assert result.total_time == pytest.approx(optimum, rel=1e-12)
    assert _tour_cost(result, offsets, true_legs, true_home) == pytest.approx(optimum)
    assert result.leg_times.sum() == pytest.approx(result.total_time)
    # the bound is the one of the optimistic legs, so it stays below the optimum
    assert result.lower_bound <= optimum * (1 + 1e-9)
    np.testing.assert_array_equal(problem.legs, before)  # corrections undone
    assert len(set(verifier.asked)) == len(verifier.asked) == result.counts["legs_checked"]
    assert result.counts["legs_infeasible"] == sum(k in true for k in verifier.asked)


def test_dense_with_shape_precedence_and_certificate():
    offsets, legs, home, _ = _points(7, 6, 2)
    true = _corrections(7, offsets, legs, home, share=0.15)
    true_legs, true_home = _true_costs(offsets, legs, home, true)
    pairs = ((4, 1), (2, 0))
    cons = TourConstraints(tour="open", precedence=pairs, end=3)
    result = solve(_dense(offsets, legs, home, _Corrections(true)), seed=1, constraints=cons,
                   certify=True)
    optimum = _brute(offsets, true_legs, true_home, open_path=True, pairs=pairs, last=3)
    assert result.total_time == pytest.approx(optimum, rel=1e-12)
    order = list(result.order)
    assert order[-1] == 3 and all(order.index(a) < order.index(b) for a, b in pairs)
    assert len(result.leg_times) == 6  # home -> 6 targets, no return
    assert result.certified.startswith("optimal (proven")


def test_a_crowded_verifier_switches_to_checking_answers():
    offsets, legs, home, _ = _points(3, 6, 2)
    true = _corrections(3, offsets, legs, home, share=0.4)
    verifier = _Corrections(true, crowd_after=2)
    result = solve(_dense(offsets, legs, home, verifier), seed=0)
    true_legs, true_home = _true_costs(offsets, legs, home, true)
    assert verifier.forgotten == 1
    assert result.counts["search_rounds"] > 1
    assert _tour_cost(result, offsets, true_legs, true_home) == pytest.approx(result.total_time)
    assert result.total_time == pytest.approx(_brute(offsets, true_legs, true_home), rel=1e-12)


def test_same_seed_same_answer():
    offsets, legs, home, _ = _points(4, 7, 3)
    true = _corrections(4, offsets, legs, home)
    a = solve(_dense(offsets, legs, home, _Corrections(true)), seed=11)
    b = solve(_dense(offsets, legs, home, _Corrections(true)), seed=11)
    np.testing.assert_array_equal(a.order, b.order)
    np.testing.assert_array_equal(a.configurations, b.configurations)
    assert a.total_time == b.total_time


def _sparse(offsets, legs, home, pts, verifier=None):
    """Every pair of targets a candidate block (so ``extend`` is never needed)."""
    n = len(offsets) - 1
    nbr = np.array([[b for b in range(n) if b != a] for a in range(n)], dtype=np.int64)
    start = np.zeros_like(nbr)
    blocks = []
    for a in range(n):
        for s, b in enumerate(nbr[a]):
            start[a, s] = sum(x.size for x in blocks)
            blocks.append(legs[offsets[a]:offsets[a + 1], offsets[b]:offsets[b + 1]].ravel())
    data = ts.SparseLegs(offsets, nbr, start, np.concatenate(blocks), home.copy(), pts,
                         PENALTY)
    d = np.array([[0.0 if a == b else legs[offsets[a]:offsets[a + 1],
                                           offsets[b]:offsets[b + 1]].min()
                   for b in range(n)] for a in range(n)])
    iu = np.triu_indices(n, 1)
    bound = (np.stack(iu, axis=1).astype(np.int64), d[iu], np.full(n, math.inf),
             np.minimum.reduceat(home, offsets[:-1]))

    def extend(pairs):
        raise AssertionError(f"every pair is a candidate, asked for {pairs}")

    return LazyLegsProblem(offsets, home.copy(), PENALTY, sparse=data, bound_inputs=bound,
                           extend=extend, verifier=verifier)


@pytest.mark.parametrize("seed", range(2))
def test_sparse_answer_is_the_optimum_of_the_true_legs(seed):
    offsets, legs, home, pts = _points(seed, 6, 2)
    true = _corrections(seed, offsets, legs, home)
    result = solve(_sparse(offsets, legs, home, pts, _Corrections(true)), seed=seed)
    true_legs, true_home = _true_costs(offsets, legs, home, true)
    optimum = _brute(offsets, true_legs, true_home)
    assert result.total_time == pytest.approx(optimum, rel=1e-12)
    assert _tour_cost(result, offsets, true_legs, true_home) == pytest.approx(optimum)
    assert result.lower_bound <= optimum * (1 + 1e-9)
    assert result.counts["kicks"] == result.generations


def test_bad_problems_and_options_are_refused():
    offsets, legs, home, pts = _points(0, 4, 2)
    with pytest.raises(ParameterError, match="offsets"):
        LazyLegsProblem(np.array([0, 2, 2, 4]), home, PENALTY, legs=legs)
    with pytest.raises(ParameterError, match="home_legs"):
        LazyLegsProblem(offsets, home[:-1], PENALTY, legs=legs)
    with pytest.raises(ParameterError, match="penalty"):
        LazyLegsProblem(offsets, home, math.inf, legs=legs)
    with pytest.raises(ParameterError, match="either dense legs or sparse"):
        LazyLegsProblem(offsets, home, PENALTY)
    frozen = legs.copy()
    frozen.setflags(write=False)
    with pytest.raises(ParameterError, match="writable"):
        _dense(offsets, legs, home).__class__(offsets, home, PENALTY, legs=frozen,
                                               dist=np.zeros((4, 4)), cheapest=np.zeros((4, 8)))
    for build in (_dense, lambda *a, verifier: _sparse(*a, pts, verifier=verifier)):
        with pytest.raises(ParameterError, match="verifier must be a LegVerifier"):
            build(offsets, legs, home, verifier=object())
    dense = _dense(offsets, legs, home)
    with pytest.raises(ParameterError, match="home configuration"):
        solve(dense, constraints=TourConstraints(home=(0.0, 0.0)))
    with pytest.raises(ParameterError, match="kicks applies"):
        solve(dense, params=SolverParams(kicks=3),
              constraints=TourConstraints(precedence=((0, 1),)))
    sparse = _sparse(offsets, legs, home, pts)
    with pytest.raises(ParameterError, match="certify"):
        solve(sparse, certify=True)
    with pytest.raises(ParameterError, match="SolverParams.runs"):
        solve(sparse, params=SolverParams(runs=2))
    with pytest.raises(ParameterError, match="closed tours"):
        solve(sparse, constraints=TourConstraints(tour="open"))
    with pytest.raises(ParameterError, match="seed"):
        solve(sparse, seed=-1, stop=MaxGenerations(1))

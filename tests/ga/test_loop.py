"""The GA loop: reproducibility, stopping, history, validation."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost
from subtask_opt.chromosomes import use
from subtask_opt.ga.config import GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import run_ga
from subtask_opt.tour.permutation import SEARCH_FAST, SEARCH_PAPER, make_aux, neighbour_table


def _matrix(seed: int = 0, n: int = 12) -> np.ndarray:
    pts = np.random.default_rng(seed).random((n, 2))
    return np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))


def _run(search=SEARCH_PAPER, seed=0, criteria=None, config=None, m=None, runs=1):
    m = _matrix() if m is None else m
    aux = make_aux(neighbour_table(m), nearest_fallback=search != SEARCH_PAPER, search=search)
    return run_ga(use(Kind.PERMUTATION), config or GAConfig(), m, aux, max_genes=m.shape[0],
                  seed=seed, criteria=criteria or [MaxGenerations(150)], runs=runs)


def test_same_seed_same_outcome():
    a, b = _run(seed=5), _run(seed=5)
    np.testing.assert_array_equal(a.genes, b.genes)
    np.testing.assert_array_equal(a.history.best_cost, b.history.best_cost)
    np.testing.assert_array_equal(a.history.restarts, b.history.restarts)
    assert a.restarts == b.restarts


def test_chunking_does_not_change_the_outcome():
    # A runtime criterion makes the driver run in growing chunks (64, 128, ...);
    # generation limits are enforced inside the kernel, so the run is the same.
    plain = _run(criteria=[MaxGenerations(300)], seed=2)
    chunked = _run(criteria=[MaxGenerations(300), MaxRuntime(600.0)], seed=2)
    np.testing.assert_array_equal(plain.genes, chunked.genes)
    np.testing.assert_array_equal(plain.history.best_cost, chunked.history.best_cost)


def test_history_is_monotone_and_complete():
    out = _run(criteria=[MaxGenerations(200)])
    h = out.history
    assert out.generations == h.generations == 200
    assert np.all(np.diff(h.best_cost) <= 0)
    assert np.all(h.mean_cost >= h.best_cost - 1e-12)
    assert h.best_cost[-1] == pytest.approx(out.cost)
    assert len(h.restarts) == out.restarts
    assert out.restarts > 0  # the paper's micro-GA converges and restarts


def test_no_improvement_stops_exactly_k_generations_after_the_last_gain():
    from subtask_opt.ga.loop import IMPROVEMENT_RTOL

    out = _run(search=SEARCH_FAST, criteria=[NoImprovement(7), MaxGenerations(10_000)])
    h = out.history
    # best before each generation: the initial population's, then each generation's; a
    # gain is more than a few ulps (the same tour summed from another start)
    before = np.concatenate([[h.initial_best], h.best_cost[:-1]])
    last_gain = max([0] + [g + 1 for g in range(h.generations)
                           if h.best_cost[g] < before[g] - IMPROVEMENT_RTOL * abs(before[g])])
    assert out.generations == last_gain + 7
    assert out.generations - h.generation_of_best() == 7


def test_target_cost_stops_as_soon_as_it_is_met():
    first = _run(search=SEARCH_FAST, criteria=[MaxGenerations(50)])
    out = _run(search=SEARCH_FAST,
               criteria=[TargetCost(first.cost * 1.5), MaxGenerations(50)])
    assert out.cost <= first.cost * 1.5
    assert out.generations <= 1


def test_best_genes_cost_matches_reported_cost():
    m = _matrix(3)
    out = _run(m=m)
    assert m[out.genes, np.roll(out.genes, -1)].sum() == pytest.approx(out.cost)


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"population": 1}, "population"),
    ({"elite": 5}, "elite"),
    ({"crossover_rate": 1.5}, "crossover_rate"),
    ({"mutation_rate": -0.1}, "mutation_rate"),
    ({"convergence_tol": float("nan")}, "convergence_tol"),
    ({"tournament": 1}, "tournament"),
    ({"mutation_horizon": 0}, "mutation_horizon"),
])
def test_bad_config_is_rejected_with_the_field_name(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        GAConfig(**kwargs)


def test_independent_runs_keep_the_best_and_count_through():
    one = _run(search=SEARCH_FAST, seed=4, criteria=[MaxGenerations(40)])
    three = _run(search=SEARCH_FAST, seed=4, criteria=[MaxGenerations(40)], runs=3)
    assert three.generations == three.history.generations == 3 * 40  # the limit is per run
    # the first run is the single run; the later ones start afresh after generations 40, 80
    np.testing.assert_array_equal(three.history.best_cost[:40], one.history.best_cost)
    assert {40, 80} <= set(three.history.restarts.tolist())
    assert three.restarts == len(three.history.restarts)
    assert three.cost <= one.cost
    assert np.all(np.diff(three.history.best_cost) <= 0)
    assert three.history.best_cost[-1] == pytest.approx(three.cost)
    m = _matrix()
    assert m[three.genes, np.roll(three.genes, -1)].sum() == pytest.approx(three.cost)
    again = _run(search=SEARCH_FAST, seed=4, criteria=[MaxGenerations(40)], runs=3)
    np.testing.assert_array_equal(three.genes, again.genes)
    np.testing.assert_array_equal(three.history.best_cost, again.history.best_cost)


def test_a_time_budget_or_a_met_target_ends_every_run():
    spent = _run(search=SEARCH_FAST, criteria=[MaxRuntime(1e-9), MaxGenerations(40)], runs=5)
    assert spent.generations <= 1  # the budget went in the first chunk of the first run
    first = _run(search=SEARCH_FAST, criteria=[MaxGenerations(40)])
    met = _run(search=SEARCH_FAST, criteria=[TargetCost(first.cost * 1.5), MaxGenerations(40)],
               runs=5)
    assert met.generations <= 1 and met.restarts == 0


@pytest.mark.parametrize("runs", [0, 1001, 2.0, True])
def test_bad_run_counts_are_rejected(runs):
    with pytest.raises(ParameterError, match="runs"):
        _run(runs=runs)


def test_compiled_entry_is_the_kernel_for_those_types_or_the_kernel_itself():
    from typing import NamedTuple

    from numba import njit

    from subtask_opt.ga.loop import compiled_entry

    class Pair(NamedTuple):
        a: float
        b: np.ndarray

    @njit
    def total(x, pair):
        return x + pair.a + pair.b.sum()

    args = (1.0, Pair(2.0, np.arange(3.0)))
    assert total(*args) == 6.0
    entry = compiled_entry(total, args)
    assert entry is not total and entry(*args) == 6.0
    assert entry(0.5, Pair(1.0, np.ones(2))) == 3.5  # any arguments of the same types
    assert compiled_entry(total, (1, args[1])) is total  # an int64 x was never compiled

    def plain(x, pair):  # NUMBA_DISABLE_JIT: kernels are plain functions
        return x

    assert compiled_entry(plain, args) is plain


def _run_lazy(m, on_best, seed=0):
    aux = make_aux(neighbour_table(m), nearest_fallback=True, search=SEARCH_FAST)
    return run_ga(use(Kind.PERMUTATION), GAConfig(), m, aux, max_genes=m.shape[0], seed=seed,
                  criteria=[NoImprovement(30), MaxGenerations(2000)], on_best=on_best)


def test_an_on_best_that_changes_nothing_leaves_the_run_as_it_was():
    m = _matrix(seed=3)
    shown = []

    def record(genes):
        shown.append(genes)
        return False

    plain = _run_lazy(m.copy(), None, seed=4)
    lazy = _run_lazy(m.copy(), record, seed=4)
    np.testing.assert_array_equal(plain.genes, lazy.genes)
    np.testing.assert_array_equal(plain.history.best_cost, lazy.history.best_cost)
    assert shown and np.array_equal(shown[-1], lazy.genes)  # every new best, the last too


@pytest.mark.parametrize("seed", range(3))
def test_costs_revealed_lazily_give_the_optimum_of_the_true_costs(seed):
    # the GA starts on cheap costs; on_best reveals the true cost of each of the best tour's
    # edges as it meets them (a lazy collision check): the answer is optimal for the true
    # costs (brute force) and its cost is its true cost
    import itertools

    n = 8
    rng = np.random.default_rng(seed)
    hidden = np.triu(rng.random((n, n)) < 0.3, 1)
    hidden |= hidden.T
    true = _matrix(seed=seed, n=n) + np.where(hidden, 5.0, 0.0)
    m = _matrix(seed=seed, n=n)  # what the GA knows at first
    revealed = set()

    def on_best(genes):
        changed = False
        for a, b in zip(genes, np.roll(genes, -1), strict=True):
            key = (min(a, b), max(a, b))
            if key not in revealed:
                revealed.add(key)
                if m[a, b] != true[a, b]:
                    m[a, b] = m[b, a] = true[a, b]
                    changed = True
        return changed

    out = _run_lazy(m, on_best, seed=seed)
    cost = float(true[out.genes, np.roll(out.genes, -1)].sum())
    assert cost == pytest.approx(out.cost)
    best = min(float(true[list(t), np.roll(list(t), -1)].sum())
               for t in ((0, *p) for p in itertools.permutations(range(1, n))))
    assert cost == pytest.approx(best)
    assert any(hidden[k] for k in revealed)  # the search did meet hidden costs

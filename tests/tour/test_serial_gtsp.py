"""The generalised TSP decode and search (ragged configurations, home) against brute force,
and the closed-form joint leg times against ruckig and a direct formula."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.chromosomes import use
from subtask_opt.kinematics.joint_moves import (
    joint_leg_square,
    joint_leg_times,
    joint_limits,
    ruckig_leg_time,
)
from subtask_opt.tour import clustered as gc
from subtask_opt.tour.configurations import pack_layers
from subtask_opt.tour.permutation import make_aux, neighbour_table


def _random_instance(rng: np.random.Generator, n: int, kmax: int, n_joints: int = 3):
    """Random configurations per target (ragged), trapezoid legs, a home configuration."""
    counts = rng.integers(1, kmax + 1, size=n)
    flat = rng.uniform(-3, 3, size=(int(counts.sum()), n_joints))
    offsets = np.concatenate([[0], np.cumsum(counts)])
    lim = joint_limits(rng.uniform(0.5, 2, n_joints), rng.uniform(1, 5, n_joints))
    home = rng.uniform(-3, 3, size=n_joints)
    legs = joint_leg_times(flat, flat, lim)
    return flat, offsets, legs, joint_leg_times(home, flat, lim)[0], \
        joint_leg_times(flat, home, lim)[:, 0]


def _brute_force(offsets, legs, home_out, home_in) -> float:
    """Every order x every configuration choice (home -> targets -> home)."""
    n = len(offsets) - 1
    perms = np.array(list(itertools.permutations(range(n))))
    best = math.inf
    for choice in itertools.product(*[range(offsets[i], offsets[i + 1]) for i in range(n)]):
        c = np.array(choice)[perms]  # (P, n) flat configuration indices in visiting order
        cost = home_out[c[:, 0]] + home_in[c[:, -1]] + legs[c[:, :-1], c[:, 1:]].sum(axis=1)
        best = min(best, float(cost.min()))
    return best


def _run_ga(data, n: int, seed: int) -> np.ndarray:
    from subtask_opt.base.stop import MaxGenerations, NoImprovement
    from subtask_opt.ga.config import GAConfig
    from subtask_opt.ga.kinds import Kind
    from subtask_opt.ga.loop import run_ga

    aux = make_aux(neighbour_table(data.dist), nearest_fallback=True, search=data.search)
    out = run_ga(use(Kind.CONFIGURED_PERMUTATION), GAConfig(), data, aux, max_genes=n, seed=seed,
                 criteria=[NoImprovement(30), MaxGenerations(20_000)])
    return out.genes.astype(np.int64)


@pytest.mark.parametrize(("n", "kmax", "seed"), [(5, 3, 0), (6, 3, 1), (7, 2, 2), (7, 3, 3)])
def test_gtsp_with_home_equals_brute_force(n: int, kmax: int, seed: int) -> None:
    _, offsets, legs, home_out, home_in = _random_instance(np.random.default_rng(seed), n, kmax)
    data = pack_layers(legs, offsets, home_out=home_out, home_in=home_in)
    genes = _run_ga(data, n, seed)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(genes, n, data, configs)
    assert cost == pytest.approx(_brute_force(offsets, legs, home_out, home_in), rel=1e-12)
    # the decoded configurations really give that cost
    c = offsets[genes] + configs[genes]
    direct = home_out[c[0]] + legs[c[:-1], c[1:]].sum() + home_in[c[-1]]
    assert cost == pytest.approx(direct, rel=1e-12)


def test_decode_is_the_best_choice_for_a_fixed_order() -> None:
    rng = np.random.default_rng(7)
    n = 6
    _, offsets, legs, home_out, home_in = _random_instance(rng, n, 4)
    data = pack_layers(legs, offsets, home_out=home_out, home_in=home_in)
    order = rng.permutation(n)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(order.astype(np.int64), n, data, configs)
    best = math.inf
    for choice in itertools.product(*[range(offsets[i], offsets[i + 1]) for i in order]):
        c = np.array(choice)
        best = min(best, home_out[c[0]] + legs[c[:-1], c[1:]].sum() + home_in[c[-1]])
    assert cost == pytest.approx(best, rel=1e-12)


def test_closed_tour_without_home_equals_brute_force() -> None:
    rng = np.random.default_rng(11)
    n = 6
    _, offsets, legs, _, _ = _random_instance(rng, n, 3)
    data = pack_layers(legs, offsets)
    genes = _run_ga(data, n, 0)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(genes, n, data, configs)
    best = math.inf
    perms = [(0, *p) for p in itertools.permutations(range(1, n))]
    for perm in perms:
        for choice in itertools.product(*[range(offsets[i], offsets[i + 1]) for i in perm]):
            c = np.array(choice)
            best = min(best, legs[c, np.roll(c, -1)].sum())
    assert cost == pytest.approx(best, rel=1e-12)


def test_penalised_legs_are_avoided() -> None:
    rng = np.random.default_rng(5)
    n = 5
    _, offsets, legs, home_out, home_in = _random_instance(rng, n, 2)
    legs = legs.copy()
    # forbid every leg out of target 0's configurations into target 1's
    legs[offsets[0]:offsets[1], offsets[1]:offsets[2]] = np.inf
    data = pack_layers(legs, offsets, home_out=home_out, home_in=home_in)
    genes = _run_ga(data, n, 1)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(genes, n, data, configs)
    assert cost == pytest.approx(_brute_force(offsets, legs, home_out, home_in), rel=1e-12)
    pos = {int(g): k for k, g in enumerate(genes)}
    assert pos[1] != pos[0] + 1


def _with_near(data, k: int | None = None):
    """``data`` with neighbour lists over targets + home (node N) by the cheapest legs."""
    n = data.dist.shape[0]
    closeness = np.zeros((n + 1, n + 1))
    closeness[:n, :n] = data.dist
    closeness[n, :n] = closeness[:n, n] = np.minimum.reduceat(data.home_out, data.offsets[:-1])
    return data._replace(near=neighbour_table(closeness, k))


def _home_tour_cost(ext, data, configs) -> float:
    """Time of the closed tour ``ext`` over targets + home (node N) with fixed configurations."""
    n = len(ext) - 1
    flat = [-1 if u == n else data.offsets[u] + configs[u] for u in ext]
    total = 0.0
    for a, b in zip(flat, flat[1:] + flat[:1], strict=True):
        total += (data.home_out[b] if a < 0 else data.home_in[a] if b < 0
                  else data.legs[a, b])
    return total


@pytest.mark.parametrize(("n", "kmax", "seed"), [(5, 3, 0), (7, 3, 3), (7, 2, 4)])
def test_symmetric_search_with_neighbour_lists_equals_brute_force(n: int, kmax: int,
                                                                  seed: int) -> None:
    _, offsets, legs, home_out, home_in = _random_instance(np.random.default_rng(seed), n, kmax)
    assert np.array_equal(legs, legs.T) and np.array_equal(home_out, home_in)
    data = _with_near(pack_layers(legs, offsets, home_out=home_out, home_in=home_in), 4)
    genes = _run_ga(data, n, seed)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(genes, n, data, configs)
    assert cost == pytest.approx(_brute_force(offsets, legs, home_out, home_in), rel=1e-12)


def _closed_tour_cost(tour, data, configs) -> float:
    """Time of the closed tour ``tour`` over the targets alone with fixed configurations."""
    flat = [data.offsets[u] + configs[u] for u in tour]
    return float(sum(data.legs[a, b] for a, b in zip(flat, flat[1:] + flat[:1], strict=True)))


@pytest.mark.parametrize("tight", [True, False])
@pytest.mark.parametrize("home", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_relocate_pass_gain_is_real_and_leaves_no_improving_relocation(seed: int, home: bool,
                                                                      tight: bool) -> None:
    # tight: the bound from each configuration's cheapest leg to a target (serial arms)
    rng = np.random.default_rng(seed)
    n = 8
    _, offsets, legs, home_out, home_in = _random_instance(rng, n, 3)
    if home:
        data = _with_near(pack_layers(legs, offsets, home_out=home_out, home_in=home_in))
        cost_of, nodes, home_node = _home_tour_cost, n + 1, n
    else:
        data = pack_layers(legs, offsets)
        data = data._replace(near=neighbour_table(data.dist))
        cost_of, nodes, home_node = _closed_tour_cost, n, -1
    data = data._replace(cheapest=gc.block_minima(data.legs, data.offsets)[1] if tight
                         else np.zeros((0, 0)))
    counts = np.diff(offsets)
    configs = np.array([rng.integers(0, k) for k in counts], dtype=np.int64)
    ext = rng.permutation(nodes).astype(np.int64)
    for _ in range(100):
        before = cost_of(list(ext), data, configs)
        gain = gc.relocate_pass(ext, data, configs, home_node)
        assert sorted(ext) == list(range(nodes))
        assert before - cost_of(list(ext), data, configs) == pytest.approx(gain, abs=1e-9)
        if gain <= 0.0:
            break
    # brute force: no target moved anywhere, in any of its configurations, shortens the tour
    cost = cost_of(list(ext), data, configs)
    for v in range(n):
        rest = [u for u in ext if u != v]
        for place in range(len(rest)):
            for k in range(counts[v]):
                c = configs.copy()
                c[v] = k
                tour = rest[:place + 1] + [v] + rest[place + 1:]
                assert cost_of(tour, data, c) >= cost - 1e-9


@pytest.mark.parametrize(("n", "kmax", "seed"), [(7, 3, 5), (9, 2, 6)])
def test_closed_symmetric_search_with_neighbour_lists_equals_brute_force(n: int, kmax: int,
                                                                         seed: int) -> None:
    # symmetric legs without home (the planar arms): neighbour lists, relocations and,
    # from 8 targets on, kicks; brute force over every order from target 0 x every choice
    _, offsets, legs, _, _ = _random_instance(np.random.default_rng(seed), n, kmax)
    assert np.array_equal(legs, legs.T)
    data = pack_layers(legs, offsets)
    data = data._replace(near=neighbour_table(data.dist, 4))
    genes = _run_ga(data, n, seed)
    configs = np.zeros(n, dtype=np.int64)
    cost = gc.decode(genes, n, data, configs)
    perms = np.array([(0, *p) for p in itertools.permutations(range(1, n))])
    best = math.inf
    for choice in itertools.product(*[range(offsets[i], offsets[i + 1]) for i in range(n)]):
        c = np.array(choice)[perms]
        best = min(best, float(legs[c, np.roll(c, -1, axis=1)].sum(axis=1).min()))
    assert cost == pytest.approx(best, rel=1e-12)


@pytest.mark.parametrize("seed, kmax", [(0, 2), (1, 2), (2, 3)])
def test_configuration_kicks_return_the_best_configured_time_and_never_lengthen(
        seed: int, kmax: int) -> None:
    rng = np.random.default_rng(seed)
    n = 9
    _, offsets, legs, _, _ = _random_instance(rng, n, kmax)
    data = pack_layers(legs, offsets)
    data = data._replace(near=neighbour_table(data.dist, 4))
    genes = rng.permutation(n).astype(np.int64)

    def best_time(order) -> float:  # brute force over every configuration choice
        choices = itertools.product(*[range(offsets[i], offsets[i + 1]) for i in order])
        return min(float(legs[c, np.roll(c, -1)].sum()) for c in map(np.array, choices))

    before = best_time(genes)
    aux = make_aux(neighbour_table(data.dist), nearest_fallback=True, search=data.search)
    cost = gc.configuration_kicks(genes, n, data, aux, np.random.default_rng(seed), 20)
    assert sorted(genes) == list(range(n))
    assert cost == pytest.approx(best_time(genes), rel=1e-12)
    assert cost <= before + 1e-9


def test_block_minima_and_square_legs_match_numpy() -> None:
    rng = np.random.default_rng(3)
    flat, offsets, legs, _, _ = _random_instance(rng, 6, 4)
    lim = joint_limits([1.0, 0.7, 1.57], [5.0, 4.25, 8.0])
    square = joint_leg_square(flat, lim)
    assert np.array_equal(square, joint_leg_times(flat, flat, lim))
    assert np.array_equal(square, square.T)
    dist, cheapest, top = gc.block_minima(legs, offsets)
    expected = np.minimum.reduceat(np.minimum.reduceat(legs, offsets[:-1], axis=0),
                                   offsets[:-1], axis=1)
    np.fill_diagonal(expected, 0.0)
    assert np.array_equal(dist, expected)
    assert np.array_equal(cheapest, np.minimum.reduceat(legs, offsets[:-1], axis=1).T)
    assert top == legs.max()


def test_pack_layers_rejects_bad_offsets() -> None:
    with pytest.raises(InputDataError, match="offsets"):
        pack_layers(np.zeros((4, 4)), [0, 2, 2, 4])
    with pytest.raises(ParameterError, match="home_out and home_in"):
        pack_layers(np.zeros((4, 4)), [0, 2, 4], home_out=np.zeros(4))


# ---------------------------------------------------------------- leg times


def _straight_line_time(dq: np.ndarray, v: np.ndarray, a: np.ndarray) -> float:
    """Fastest rest-to-rest straight joint line, by bisection on the duration (an oracle).

    A duration T is feasible when the symmetric trapezoid of the path parameter
    with the smallest peak speed that covers it in T keeps every joint within its limits.
    """
    d = np.abs(dq)
    if not d.any():
        return 0.0

    def feasible(t: float) -> bool:
        # path parameter 0 -> 1 in time t with acceleration phase tau: peak speed s1 and
        # acceleration s1 / tau, where 1 = s1 (t - tau); pick the largest feasible tau
        for tau in np.linspace(1e-9, t / 2, 4001):
            s1 = 1.0 / (t - tau)
            if np.all(s1 * d <= v * (1 + 1e-12)) and np.all(s1 / tau * d <= a * (1 + 1e-12)):
                return True
        return False

    lo, hi = 0.0, 100.0
    for _ in range(50):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if feasible(mid) else (mid, hi)
    return hi


def test_trapezoid_matrix_matches_a_bisection_oracle() -> None:
    rng = np.random.default_rng(0)
    lim = joint_limits([1.0, 0.7, 1.57], [5.0, 4.25, 8.0])
    qa = rng.uniform(-3, 3, size=(2, 3))
    qb = np.vstack([rng.uniform(-3, 3, size=(2, 3)), qa[0] + [0.01, -0.02, 0.005]])
    m = joint_leg_times(qa, qb, lim)
    assert m.shape == (2, 3)
    for r in range(2):
        for c in range(3):
            oracle = _straight_line_time(qb[c] - qa[r], lim.velocity, lim.acceleration)
            assert m[r, c] == pytest.approx(oracle, rel=2e-3)


def test_trapezoid_equals_ruckig_without_jerk_and_is_below_it_with_jerk() -> None:
    rng = np.random.default_rng(1)
    v, a = np.array([1.0, 0.7, 0.7, 1.0, 0.7, 1.57]), np.array([5, 4.25, 4.25, 5.25, 6, 8.0])
    lim = joint_limits(v, a)
    for _ in range(10):
        q0, q1 = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
        closed = joint_leg_times(q0, q1, lim)[0, 0]
        assert ruckig_leg_time(q0, q1, v, a) == pytest.approx(closed, rel=1e-6)
        assert ruckig_leg_time(q0, q1, v, a, np.full(6, 20.0)) > closed


def test_joint_limits_name_the_bad_field() -> None:
    with pytest.raises(ParameterError, match="JointLimits.acceleration"):
        joint_limits([1.0, 1.0], [1.0, 0.0])
    with pytest.raises(ParameterError, match="same length"):
        joint_limits([1.0, 1.0], [1.0])


@pytest.mark.parametrize("home", [True, False])
def test_refreshed_fixed_matrix_equals_a_rebuilt_one(home: bool) -> None:
    # the incremental update after relocations against building the matrix again
    rng = np.random.default_rng(7)
    n = 9
    _, offsets, legs, home_out, home_in = _random_instance(rng, n, 3)
    data = (pack_layers(legs, offsets, home_out=home_out, home_in=home_in) if home
            else pack_layers(legs, offsets))
    counts = np.diff(offsets)
    configs = np.array([rng.integers(0, k) for k in counts], dtype=np.int64)
    fixed = gc._fixed_matrix(data, configs)
    fixed_configs = configs.copy()
    for _ in range(5):
        changed = rng.choice(n, size=3, replace=False)
        configs[changed] = [rng.integers(0, counts[v]) for v in changed]
        gc.refresh_fixed(fixed, data, configs, fixed_configs)
        np.testing.assert_array_equal(fixed, gc._fixed_matrix(data, configs))
        np.testing.assert_array_equal(fixed_configs, configs)


def test_configuration_kicks_are_two_per_kick_up_to_the_cap() -> None:
    assert gc.configuration_kick_count(1) == 2
    assert gc.configuration_kick_count(3) == 6
    assert gc.configuration_kick_count(100) == gc.CONFIGURATION_KICKS_MAX
    assert gc.CONFIGURATION_KICKS_MAX < 2 * 100  # N/10 kicks at 1000 targets are capped

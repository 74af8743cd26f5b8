"""The benchmark's peers against brute force: layered shortest path, 2-opt / Or-opt local
optimality, Noon-Bean + LKH on tiny GTSPs, RoboTSP's two stages, and bad inputs."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.peers import (
    elkai_gtsp,
    layered_shortest_path,
    local_search,
    manipulability,
    max_joint_metric,
    nearest_neighbour_tour,
    noon_bean_matrix,
    or_opt,
    robotsp_method,
    sequence_cost,
    tour_cost,
    tsp_cspace,
    two_opt,
)

VMAX = np.array([3.0, 2.0, 2.5, 4.0])


def _instance(seed: int, n: int, kmax: int, dof: int = 4):
    rng = np.random.default_rng(seed)
    layers = [rng.uniform(-3, 3, size=(int(rng.integers(1, kmax + 1)), dof)) for _ in range(n)]
    home = rng.uniform(-1, 1, size=dof)
    return layers, home


def _asymmetric(seed: int):
    """A leg time that is not symmetric: a joint-space metric plus a direction-dependent term."""
    w = np.random.default_rng(seed).uniform(0.0, 1.0, size=4)

    def leg(qa, qb):
        base = max_joint_metric(VMAX)(qa, qb)
        return base + np.maximum(qb @ w - (qa @ w)[:, None], 0.0)

    return leg


def _path_cost(home, configs, leg) -> float:
    """Independent evaluation: sum of leg times along home -> configs -> home."""
    path = [home, *configs, home]
    return sum(float(leg(path[k][None], path[k + 1][None])[0, 0]) for k in range(len(path) - 1))


def _brute_gtsp(layers, home, leg):
    best = np.inf
    for order in itertools.permutations(range(len(layers))):
        for choice in itertools.product(*(range(layers[i].shape[0]) for i in order)):
            cost = _path_cost(home, [layers[i][c] for i, c in zip(order, choice, strict=True)], leg)
            best = min(best, cost)
    return best


# ----------------------------------------------------------------- layered shortest path

@pytest.mark.parametrize("seed", range(6))
def test_layered_shortest_path_equals_brute_force(seed):
    layers, home = _instance(seed, n=5, kmax=3)
    order = np.random.default_rng(100 + seed).permutation(5)
    leg = max_joint_metric(VMAX) if seed % 2 else _asymmetric(seed)
    choice, cost = layered_shortest_path(layers, home, order, leg)
    brute = min(_path_cost(home, [layers[i][c] for i, c in zip(order, combo, strict=True)], leg)
                for combo in itertools.product(*(range(layers[i].shape[0]) for i in order)))
    assert cost == pytest.approx(brute, rel=1e-12)
    # the returned choice (indexed by target) realises that cost
    assert _path_cost(home, [layers[i][choice[i]] for i in order], leg) == pytest.approx(brute)
    assert sequence_cost(layers, home, order, choice, leg) == pytest.approx(brute)


def test_max_joint_metric_closed_form():
    qa = np.array([[0.0, 0.0, 0.0, 0.0]])
    qb = np.array([[1.5, -1.0, 0.5, 4.0], [0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(max_joint_metric(VMAX)(qa, qb), [[1.0, 0.0]])


# ----------------------------------------------------------------- local search

def _two_opt_deltas(d, t):
    base = tour_cost(d, t)
    n = len(t)
    for i in range(n - 1):
        for j in range(i + 1, n):
            moved = t.copy()
            moved[i + 1:j + 1] = moved[i + 1:j + 1][::-1]
            yield tour_cost(d, moved) - base


def _or_opt_deltas(d, t, max_segment=3):
    base = tour_cost(d, t)
    n = len(t)
    for length in range(1, max_segment + 1):
        for i in range(1, n - length + 1):
            seg = list(t[i:i + length])
            rest = [x for x in t if x not in seg]
            for q in range(len(rest)):
                for s in (seg, seg[::-1]):
                    moved = np.array(rest[:q + 1] + s + rest[q + 1:])
                    yield tour_cost(d, moved) - base


@pytest.mark.parametrize("symmetric", [True, False])
def test_two_opt_leaves_no_improving_move(symmetric):
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 1, size=(25, 2))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    if not symmetric:
        d = d + rng.uniform(0, 0.3, size=d.shape)
    start = nearest_neighbour_tour(d, 4)
    t = two_opt(d, start)
    assert t[0] == 4 and sorted(t) == list(range(25))
    assert tour_cost(d, t) <= tour_cost(d, start) + 1e-12
    assert min(_two_opt_deltas(d, t)) > -1e-9


def test_two_opt_untangles_a_crossing():
    # a square visited 0, 2, 1, 3 crosses itself; 2-opt must give the perimeter
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    assert tour_cost(d, two_opt(d, np.array([0, 2, 1, 3]))) == pytest.approx(4.0)


@pytest.mark.parametrize("symmetric", [True, False])
def test_or_opt_and_local_search_leave_no_improving_move(symmetric):
    rng = np.random.default_rng(5)
    pts = rng.uniform(0, 1, size=(14, 2))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    if not symmetric:
        d = d + rng.uniform(0, 0.3, size=d.shape)
    t = or_opt(d, np.arange(14))
    assert t[0] == 0 and min(_or_opt_deltas(d, t)) > -1e-9
    t = local_search(d, np.arange(14))
    assert t[0] == 0
    assert min(_or_opt_deltas(d, t)) > -1e-9 and min(_two_opt_deltas(d, t)) > -1e-9


# ----------------------------------------------------------------- Noon-Bean + LKH

def test_noon_bean_matrix_structure():
    cost = np.arange(25, dtype=float).reshape(5, 5)
    cluster = np.array([0, 1, 1, 2, 2])
    mat, succ, s = noon_bean_matrix(cost, cluster, resolution=24.0)
    np.testing.assert_array_equal(succ, [0, 2, 1, 4, 3])
    assert s == 1.0
    big = 24 * 4 + 1
    assert mat[1, 2] == 0 and mat[2, 1] == 0  # the zero cycle inside cluster 1
    assert mat[1, 3] == cost[2, 3] + big  # leaving from 1 charges its successor 2
    assert mat[0, 1] == cost[0, 1] + big


@pytest.mark.parametrize("seed", range(5))
def test_elkai_gtsp_equals_brute_force(seed):
    pytest.importorskip("elkai")
    n = 3 + seed % 3  # 3..5 targets
    layers, home = _instance(seed, n=n, kmax=3)
    leg = max_joint_metric(VMAX) if seed % 2 else _asymmetric(seed)
    order, choice = elkai_gtsp(layers, home, leg, seed=0)
    assert sorted(order) == list(range(n))
    found = _path_cost(home, [layers[i][choice[i]] for i in order], leg)
    nodes = np.vstack([home[None]] + layers)
    top = leg(nodes, nodes).max()
    tol = (n + 1) * top / min(1e4, 2e6 / (n + 2))  # integer rounding of the arcs
    assert found <= _brute_gtsp(layers, home, leg) + tol


def test_elkai_gtsp_same_seed_same_answer():
    pytest.importorskip("elkai")
    layers, home = _instance(11, n=12, kmax=4)
    leg = max_joint_metric(VMAX)
    a = elkai_gtsp(layers, home, leg, seed=7)
    b = elkai_gtsp(layers, home, leg, seed=7)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_elkai_gtsp_search_limits_still_give_a_valid_answer():
    pytest.importorskip("elkai")
    layers, home = _instance(12, n=15, kmax=4)
    order, choice = elkai_gtsp(layers, home, max_joint_metric(VMAX), max_trials=1,
                               time_limit=5.0)
    assert sorted(order) == list(range(15))
    assert all(0 <= choice[i] < layers[i].shape[0] for i in range(15))


def test_elkai_gtsp_repairs_a_tour_that_splits_a_cluster(monkeypatch):
    """A tour LKH stopped early on (a cluster's configurations not in one run) is read as
    the order of first visits, with the configurations chosen exactly for that order."""
    from subtask_opt.tour import peers

    layers = [np.full((2, 4), float(i)) + np.arange(2)[:, None] for i in range(4)]
    home = np.zeros(4)
    # nodes: 0 home, then two per target (1-2: target 0, 3-4: target 1, ...); target 0's
    # two configurations are visited apart, around target 2's
    split = np.array([0, 1, 5, 6, 2, 3, 4, 7, 8])
    monkeypatch.setattr(peers, "_lkh_tour", lambda *a, **k: split)
    leg = max_joint_metric(VMAX)
    order, choice = elkai_gtsp(layers, home, leg)
    np.testing.assert_array_equal(order, [0, 2, 1, 3])
    expected, _ = layered_shortest_path(layers, home, order, leg)
    np.testing.assert_array_equal(choice, expected)


def test_elkai_gtsp_single_configuration():
    order, choice = elkai_gtsp([np.zeros((1, 4))], np.ones(4), max_joint_metric(VMAX))
    np.testing.assert_array_equal(order, [0])
    np.testing.assert_array_equal(choice, [0])


# ----------------------------------------------------------------- RoboTSP and TSP C-space

def test_robotsp_method_two_stages():
    rng = np.random.default_rng(2)
    pos = rng.uniform(-0.3, 0.3, size=(9, 3))
    layers, home = _instance(2, n=9, kmax=3)
    hp = np.array([0.3, 0.3, 0.3])
    order, choice = robotsp_method(pos, layers, home, VMAX, home_position=hp)
    assert order[0] == int(np.argmin(np.linalg.norm(pos - hp, axis=1)))
    assert sorted(order) == list(range(9))
    d = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    assert min(_two_opt_deltas(d, order)) > -1e-9  # stage 1: a 2-opt tour of the holes
    # stage 2: the best configurations for that order under the 1/vmax metric
    _, best = layered_shortest_path(layers, home, order, max_joint_metric(VMAX))
    assert sequence_cost(layers, home, order, choice, max_joint_metric(VMAX)) == \
        pytest.approx(best)


def test_robotsp_method_direction_by_true_time():
    rng = np.random.default_rng(4)
    pos = rng.uniform(-0.3, 0.3, size=(7, 3))
    layers, home = _instance(4, n=7, kmax=2)
    leg = _asymmetric(4)
    order, choice = robotsp_method(pos, layers, home, VMAX, leg)
    plain, _ = robotsp_method(pos, layers, home, VMAX)
    reverse = np.concatenate([plain[:1], plain[1:][::-1]])
    assert order[0] == plain[0]
    costs = []
    for o in (plain, reverse):
        c, _ = layered_shortest_path(layers, home, o, max_joint_metric(VMAX))
        costs.append(sequence_cost(layers, home, o, c, leg))
    assert sequence_cost(layers, home, order, choice, leg) == pytest.approx(min(costs))


def test_tsp_cspace_picks_best_manipulability_then_a_local_optimum():
    layers, home = _instance(8, n=10, kmax=4)
    scores = [np.random.default_rng(i).uniform(size=layer.shape[0])
              for i, layer in enumerate(layers)]
    leg = max_joint_metric(VMAX)
    order, choice = tsp_cspace(layers, home, scores, leg)
    np.testing.assert_array_equal(choice, [int(np.argmax(s)) for s in scores])
    nodes = np.vstack([home[None]] + [layer[c][None] for layer, c in
                                     zip(layers, choice, strict=True)])
    d = leg(nodes, nodes)
    tour = np.concatenate([[0], order + 1])
    assert min(_two_opt_deltas(d, tour)) > -1e-9 and min(_or_opt_deltas(d, tour)) > -1e-9
    # a callable score gives the same as the arrays it would produce
    by_call = tsp_cspace(layers, home, lambda q: q[:, 0], leg)[1]
    np.testing.assert_array_equal(by_call, [int(np.argmax(layer[:, 0])) for layer in layers])


@pytest.mark.parametrize("symmetric", [True, False])
def test_tsp_cspace_with_lkh_equals_brute_force(symmetric):
    pytest.importorskip("elkai")
    layers, home = _instance(9, n=7, kmax=3)
    leg = max_joint_metric(VMAX) if symmetric else _asymmetric(9)
    order, choice = tsp_cspace(layers, home, lambda q: q[:, 1], leg, solver="elkai", seed=3)
    chosen = [layer[c] for layer, c in zip(layers, choice, strict=True)]
    best = min(_path_cost(home, [chosen[i] for i in perm], leg)
               for perm in itertools.permutations(range(7)))
    nodes = np.vstack([home[None], *chosen])
    tol = 8 * leg(nodes, nodes).max() / 1e5  # integer rounding of the arcs
    assert _path_cost(home, [chosen[i] for i in order], leg) <= best + tol


@pytest.mark.parametrize("n", [1, 2, 3])
def test_peers_on_one_to_three_targets_equal_brute_force(n):
    layers, home = _instance(20 + n, n=n, kmax=3)
    leg = _asymmetric(n)
    pos = np.random.default_rng(n).uniform(size=(n, 3))
    order, choice = robotsp_method(pos, layers, home, VMAX, leg)
    assert sorted(order) == list(range(n))
    _, best = layered_shortest_path(layers, home, order, max_joint_metric(VMAX))
    assert sequence_cost(layers, home, order, choice, max_joint_metric(VMAX)) == \
        pytest.approx(best)
    order, choice = tsp_cspace(layers, home, lambda q: q[:, 2], leg)
    chosen = [layer[c] for layer, c in zip(layers, choice, strict=True)]
    best = min(_path_cost(home, [chosen[i] for i in perm], leg)
               for perm in itertools.permutations(range(n)))
    assert _path_cost(home, [chosen[i] for i in order], leg) == pytest.approx(best)


def test_manipulability_zero_at_a_singularity():
    from subtask_opt.kinematics.serial import load_serial_arm

    arm = load_serial_arm("ur5")
    q = np.array([[0.0, -1.2, 1.4, -1.0, 1.2, 0.3],   # generic
                  [0.0, -1.2, 0.0, -1.0, 1.2, 0.3],   # elbow straight
                  [0.0, -1.2, 1.4, -1.0, 0.0, 0.3]])  # wrist 5 at 0: axes 4 and 6 align
    m = manipulability(arm, q)
    jac = arm.jacobian(q[0])
    assert m[0] == pytest.approx(abs(np.linalg.det(jac)), rel=1e-9) and m[0] > 1e-3
    assert m[1] < 1e-9 and m[2] < 1e-9


# ----------------------------------------------------------------- bad inputs

@pytest.mark.parametrize("call,error,match", [
    (lambda L, h: layered_shortest_path([], h, [], max_joint_metric(VMAX)),
     ParameterError, "layers must be a non-empty list"),
    (lambda L, h: layered_shortest_path([np.zeros((0, 4))], h, [0], max_joint_metric(VMAX)),
     InputDataError, r"target 0 has no configuration"),
    (lambda L, h: layered_shortest_path([np.zeros((2, 3))], h, [0], max_joint_metric(VMAX)),
     ParameterError, r"layers\[0\] has 3 joint values per configuration, home has 4"),
    (lambda L, h: layered_shortest_path(L, h, [0, 0, 1], max_joint_metric(VMAX)),
     ParameterError, "tour must be a permutation"),
    (lambda L, h: layered_shortest_path(L, h, [0, 1, 2], lambda a, b: np.zeros((1, 1))),
     ParameterError, "leg_time returned shape"),
    (lambda L, h: layered_shortest_path(L, h, [0, 1, 2], lambda a, b: -np.ones(
        (len(a), len(b)))), ParameterError, "finite times >= 0"),
    (lambda L, h: layered_shortest_path(L, [np.nan] * 4, [0, 1, 2], max_joint_metric(VMAX)),
     ParameterError, "home must be finite"),
    (lambda L, h: max_joint_metric([1.0, 0.0]), ParameterError, "vmax must be > 0"),
    (lambda L, h: robotsp_method(np.zeros((2, 3)), L, h, VMAX), ParameterError,
     r"positions must have shape \(3, 3\)"),
    (lambda L, h: robotsp_method(np.zeros((3, 3)), L, h, VMAX[:3]), ParameterError,
     "vmax must hold 4 values"),
    (lambda L, h: robotsp_method(np.zeros((3, 3)), L, h, VMAX, home_position=[0, 0]),
     ParameterError, "home_position must have 3 values"),
    (lambda L, h: tsp_cspace(L, h, [np.ones(2)], max_joint_metric(VMAX)), ParameterError,
     "one array per layer"),
    (lambda L, h: tsp_cspace(L, h, lambda q: np.ones(1), max_joint_metric(VMAX)),
     ParameterError, "manipulability of target 0"),
    (lambda L, h: tsp_cspace(L, h, lambda q: q[:, 0], max_joint_metric(VMAX), solver="lkh"),
     ParameterError, "solver must be 'local' or 'elkai'"),
    (lambda L, h: elkai_gtsp(L, h, max_joint_metric(VMAX), max_nodes=3), ParameterError,
     "exceed max_nodes=3"),
    (lambda L, h: elkai_gtsp(L, h, max_joint_metric(VMAX), seed=-1), ParameterError, "seed"),
    (lambda L, h: elkai_gtsp(L, h, max_joint_metric(VMAX), max_trials=0), ParameterError,
     "max_trials"),
    (lambda L, h: elkai_gtsp(L, h, max_joint_metric(VMAX), time_limit=0.0), ParameterError,
     "time_limit"),
    (lambda L, h: two_opt(np.zeros((3, 4)), [0, 1, 2]), ParameterError, "dist must be square"),
    (lambda L, h: elkai_gtsp(L, h, "fast"), ParameterError, "leg_time must be a callable"),
])
def test_bad_input(call, error, match):
    layers = [np.zeros((2, 4)), np.ones((1, 4)), np.full((3, 4), 0.5)]
    with pytest.raises(error, match=match):
        call(layers, np.zeros(4))

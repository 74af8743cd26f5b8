"""Tour shapes and precedence: the GA against brute force, the exact oracles, bad input."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.arm.planar_problem import PlanarProblem, solve
from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.constraints import (
    TourConstraints,
    canonical,
    find_cycle,
    read_precedence,
)
from subtask_opt.tour.exact import (
    exact_constrained,
    held_karp_pinned,
    milp_pinned,
)
from subtask_opt.tour.problem import MatrixProblem

VARIANTS = ("closed", "open_free", "open_fixed", "home", "open_home")


@dataclass(frozen=True)
class Instance:
    matrix: np.ndarray
    constraints: TourConstraints


def random_instance(seed: int, n_low: int = 4, n_high: int = 10) -> Instance:
    """A seeded matrix problem with a random shape and random acyclic precedence."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(n_low, n_high + 1))
    if rng.random() < 0.5:  # Euclidean (symmetric) or arbitrary asymmetric costs
        xy = rng.random((n, 2)) * 10
        m = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    else:
        m = rng.integers(1, 100, size=(n, n)).astype(float)
        np.fill_diagonal(m, 0.0)
    variant = VARIANTS[seed % len(VARIANTS)]
    start = int(rng.integers(0, n))
    end = None
    home = None
    if variant == "open_fixed":
        end = int((start + 1 + rng.integers(0, n - 1)) % n)
    if variant in ("home", "open_home"):
        home, start = start, None
    if variant == "open_home" and rng.random() < 0.5:  # an open path from home to a set end
        end = int((home + 1 + rng.integers(0, n - 1)) % n)
    # a random DAG: pairs that follow a random ranking, never into the start, out of the
    # end, or touching the home
    rank = rng.permutation(n)
    density = rng.choice([0.0, 0.1, 0.3])
    pairs = []
    for a, b in itertools.combinations(rank.tolist(), 2):
        if rng.random() < density and b != start and a != end and home not in (a, b):
            pairs.append((a, b))
    tour = "open" if variant.startswith("open") else "closed"
    return Instance(m, TourConstraints(tour=tour, start=start, end=end, home=home,
                                       precedence=pairs))


def brute_force(m: np.ndarray, c: TourConstraints) -> float:
    """The optimum in the user's terms, by trying every order (an independent oracle)."""
    n = m.shape[0]
    home = c.home if isinstance(c.home, int) else None
    start = 0 if c.start is None else c.start
    subtasks = [v for v in range(n) if v != home]
    best = math.inf
    for perm in itertools.permutations(subtasks):
        if home is None and perm[0] != start:
            continue
        if c.end is not None and perm[-1] != c.end:
            continue
        pos = {v: k for k, v in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in c.precedence):
            continue
        cost = sum(m[perm[k], perm[k + 1]] for k in range(len(perm) - 1))
        if home is not None:
            cost += m[home, perm[0]] + (m[perm[-1], home] if c.tour == "closed" else 0.0)
        elif c.tour == "closed":
            cost += m[perm[-1], perm[0]]
        best = min(best, cost)
    return best


def user_cost(m: np.ndarray, c: TourConstraints, order: np.ndarray) -> float:
    """The cost of ``order`` in the user's terms, computed from scratch."""
    o = [int(v) for v in order]
    cost = sum(m[o[k], o[k + 1]] for k in range(len(o) - 1))
    if isinstance(c.home, int):
        back = m[o[-1], c.home] if c.tour == "closed" else 0.0
        return float(cost + m[c.home, o[0]] + back)
    return float(cost + (m[o[-1], o[0]] if c.tour == "closed" else 0.0))


def assert_keeps(order: np.ndarray, m: np.ndarray, c: TourConstraints) -> None:
    n = m.shape[0]
    home = c.home if isinstance(c.home, int) else None
    expected = sorted(v for v in range(n) if v != home)
    assert sorted(order.tolist()) == expected
    if home is None:
        assert order[0] == (0 if c.start is None else c.start)
    if c.end is not None:
        assert order[-1] == c.end
    pos = {int(v): k for k, v in enumerate(order)}
    for a, b in c.precedence:
        assert pos[a] < pos[b], (a, b)


SMALL = list(range(200))


def test_held_karp_pinned_equals_brute_force_on_small_instances() -> None:
    checked = 0
    for seed in SMALL:
        inst = random_instance(seed)
        if inst.matrix.shape[0] > 8:
            continue
        cost, order = exact_constrained(inst.matrix, inst.constraints, method="held_karp")
        assert cost == pytest.approx(brute_force(inst.matrix, inst.constraints), rel=1e-12)
        assert_keeps(order, inst.matrix, inst.constraints)
        assert user_cost(inst.matrix, inst.constraints, order) == pytest.approx(cost)
        checked += 1
    assert checked >= 80


@pytest.mark.parametrize("seed", SMALL[::7])
def test_milp_equals_brute_force(seed: int) -> None:
    inst = random_instance(seed, n_high=8)
    cost, order = exact_constrained(inst.matrix, inst.constraints, method="milp")
    assert cost == pytest.approx(brute_force(inst.matrix, inst.constraints), rel=1e-9)
    assert_keeps(order, inst.matrix, inst.constraints)


@pytest.mark.parametrize("seed", SMALL)
def test_ga_finds_the_constrained_optimum(seed: int) -> None:
    inst = random_instance(seed)
    m, c = inst.matrix, inst.constraints
    result = solve(MatrixProblem(m), seed=7, constraints=c)
    assert_keeps(result.order, m, c)
    assert result.total_time == pytest.approx(user_cost(m, c, result.order), rel=1e-12)
    assert result.total_time == pytest.approx(float(np.sum(result.leg_times)), rel=1e-12)
    if m.shape[0] <= 8:
        optimum = brute_force(m, c)
    else:  # Held-Karp, itself checked against brute force above
        optimum = exact_constrained(m, c, method="held_karp")[0]
    assert result.total_time == pytest.approx(optimum, rel=1e-9)
    assert result.lower_bound is not None
    assert result.lower_bound <= optimum * (1 + 1e-9)


def test_leg_counts_follow_the_shape() -> None:
    m = random_instance(1).matrix
    n = m.shape[0]
    closed = solve(MatrixProblem(m), seed=0, constraints=TourConstraints(start=2))
    open_ = solve(MatrixProblem(m), seed=0, constraints=TourConstraints(tour="open", start=2))
    home = solve(MatrixProblem(m), seed=0, constraints=TourConstraints(home=2))
    away = solve(MatrixProblem(m), seed=0, constraints=TourConstraints(tour="open", home=2))
    assert len(away.order) == n - 1 and 2 not in away.order and len(away.leg_times) == n - 1
    assert away.leg_times[0] == m[2, away.order[0]]
    assert len(closed.leg_times) == n and closed.order[0] == 2
    assert len(open_.leg_times) == n - 1 and open_.order[0] == 2
    assert len(home.order) == n - 1 and 2 not in home.order and len(home.leg_times) == n
    # a free end never costs more than coming back
    assert open_.total_time <= closed.total_time + 1e-12


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), n=st.integers(20, 60),
       variant=st.sampled_from(VARIANTS), density=st.sampled_from([0.02, 0.1, 0.3]))
def test_larger_answers_keep_every_constraint(seed: int, n: int, variant: str,
                                              density: float) -> None:
    rng = np.random.default_rng(seed)
    m = rng.random((n, n)) * 10
    np.fill_diagonal(m, 0.0)
    start = int(rng.integers(0, n))
    end = int((start + 1 + rng.integers(0, n - 1)) % n) if variant == "open_fixed" else None
    home = start if variant in ("home", "open_home") else None
    if home is not None:
        start = None  # type: ignore[assignment]
    rank = rng.permutation(n).tolist()
    pairs = [(a, b) for a, b in itertools.combinations(rank, 2)
             if rng.random() < density and b != start and a != end and home not in (a, b)]
    c = TourConstraints(tour="open" if variant.startswith("open") else "closed", start=start,
                        end=end, home=home, precedence=pairs)
    result = solve(MatrixProblem(m), seed=seed, constraints=c)
    assert_keeps(result.order, m, c)
    assert result.total_time == pytest.approx(user_cost(m, c, result.order), rel=1e-12)
    assert result.lower_bound is not None and result.lower_bound <= result.total_time + 1e-9


def test_same_seed_same_answer() -> None:
    inst = random_instance(11, n_low=30, n_high=30)
    c = TourConstraints(tour="open", start=3, end=5, precedence=[(1, 2), (2, 9), (7, 4)])
    a = solve(MatrixProblem(inst.matrix), seed=5, constraints=c)
    b = solve(MatrixProblem(inst.matrix), seed=5, constraints=c)
    np.testing.assert_array_equal(a.order, b.order)
    assert a.total_time == b.total_time and a.generations == b.generations


def test_certify_proves_the_constrained_optimum() -> None:
    inst = random_instance(6, n_low=9, n_high=9)
    result = solve(MatrixProblem(inst.matrix), seed=1, constraints=inst.constraints,
                   certify=True)
    assert result.certified == "optimal (proven)"


def test_held_karp_pinned_reports_no_tour_for_a_pair_into_the_start() -> None:
    m = np.ones((4, 4))
    cost, order = held_karp_pinned(m, 0, -1, [(2, 0)])
    assert cost == math.inf and order.size == 0


def test_milp_pinned_agrees_with_held_karp_on_an_asymmetric_matrix() -> None:
    rng = np.random.default_rng(4)
    m = rng.random((11, 11))
    pairs = [(3, 1), (1, 7), (9, 2)]
    hk, tour_hk = held_karp_pinned(m, 4, 6, pairs)
    mi, tour_mi = milp_pinned(m, 4, 6, pairs)
    assert mi == pytest.approx(hk, rel=1e-9)
    for t in (tour_hk, tour_mi):
        assert t[0] == 4 and t[-1] == 6


def test_the_open_path_transform_costs_exactly_the_path() -> None:
    rng = np.random.default_rng(0)
    m = rng.random((6, 6))
    canon = canonical(m, TourConstraints(tour="open", start=2), default_start=0)
    tour = np.array([2, 0, 5, 1, 4, 3])
    closed = float(np.sum(canon.matrix[tour, np.roll(tour, -1)]))
    assert closed == pytest.approx(sum(m[tour[k], tour[k + 1]] for k in range(5)))


# --- arm problems -------------------------------------------------------------------

@pytest.fixture(scope="module")
def arm_problem():
    from subtask_opt.arm.tasks import random_subtasks
    from subtask_opt.kinematics.planar import load_planar_arm

    arm = load_planar_arm("planar_2r")
    subtasks = random_subtasks(arm, 7, seed=3)
    return arm, subtasks


def test_arm_home_point_matches_brute_force(arm_problem) -> None:
    from subtask_opt.arm.targets import Targets

    arm, subtasks = arm_problem
    home = (0.35, -0.05)
    assert arm.reachable(home)
    c = TourConstraints(home=home, precedence=[(0, 4), (4, 2)])
    problem = PlanarProblem(subtasks, arm, time_model="trapezoid")
    result = solve(problem, seed=2, constraints=c)
    # the oracle: the same arm problem with the home built as an 8th row by hand
    with_home = PlanarProblem(Targets(np.vstack([subtasks.points, home])), arm,
                              time_model="trapezoid")
    as_matrix = TourConstraints(home=7, precedence=c.precedence)
    assert result.total_time == pytest.approx(brute_force(with_home.matrix, as_matrix),
                                              rel=1e-9)
    assert sorted(result.order.tolist()) == list(range(7))
    assert result.to_dict()["home"] == [0.35, -0.05]


def test_arm_open_path_with_optimized_configurations_keeps_constraints(arm_problem) -> None:
    arm, subtasks = arm_problem
    c = TourConstraints(tour="open", start=1, end=5, precedence=[(3, 0)])
    result = solve(PlanarProblem(subtasks, arm), seed=0, constraints=c)
    assert result.order[0] == 1 and result.order[-1] == 5
    pos = {int(v): k for k, v in enumerate(result.order)}
    assert pos[3] < pos[0]
    assert len(result.leg_times) == 6
    assert result.lower_bound is not None and result.lower_bound <= result.total_time


def test_unreachable_home_is_refused(arm_problem) -> None:
    arm, subtasks = arm_problem
    with pytest.raises(InputDataError, match=r"home point \(5, 5\) is unreachable: is beyond"):
        solve(PlanarProblem(subtasks, arm, time_model="trapezoid"),
              constraints=TourConstraints(home=(5.0, 5.0)))


# --- bad input ----------------------------------------------------------------------

def test_a_precedence_cycle_is_named() -> None:
    with pytest.raises(InputDataError, match=r"cycle: 2 -> 5 -> 7 -> 2"):
        TourConstraints(precedence=[(0, 1), (2, 5), (5, 7), (7, 2)])
    assert find_cycle([(0, 1), (1, 2)]) is None


def test_a_closed_tour_ends_at_a_chosen_subtask_only_before_a_home() -> None:
    # the problem's own home (a serial arm) or the constraints'
    with pytest.raises(ParameterError, match="end=3 needs tour='open' or a home"):
        TourConstraints(end=3).check_size(5, matrix_home=True)
    TourConstraints(end=3).check_size(5, matrix_home=True, own_home=True)
    m = np.arange(36, dtype=float).reshape(6, 6)
    canon = canonical(m, TourConstraints(end=3, home=5), default_start=0)
    assert canon.first == 5 and canon.last == -1
    assert {(v, 3) for v in (0, 1, 2, 4)} <= {tuple(p) for p in canon.pairs.tolist()}


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"tour": "circle"}, "tour must be one of closed, open"),
    ({"tour": "open", "start": 2, "end": 2}, "from subtask 2 to itself"),
    ({"home": 1, "start": 2}, "home and start=2 contradict"),
    ({"start": -1}, "start must be a non-negative integer"),
    ({"precedence": [(1, 1)]}, "subtask 1 before itself"),
    ({"precedence": [(1, 2, 3)]}, "is a pair"),
    ({"home": (1.0, math.nan)}, "finite point"),
])
def test_contradictory_or_malformed_options_are_refused(kwargs, message) -> None:
    with pytest.raises((ParameterError, InputDataError), match=message):
        TourConstraints(**kwargs)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"precedence": [(0, 9)]}, r"names subtask 9; subtasks are numbered 0..4"),
    ({"start": 5}, r"start is subtask 5; subtasks are numbered 0..4"),
    ({"tour": "open", "end": 7}, r"end is subtask 7"),
    ({"home": 8}, r"home is node 8; nodes are numbered 0..4"),
    ({"home": (0.1, 0.2)}, "home is a node index"),
    ({"home": 2, "precedence": [(2, 3)]}, "which is the home"),
    ({"start": 1, "precedence": [(3, 1)]}, "before the start 1"),
    ({"tour": "open", "end": 4, "precedence": [(4, 0)]}, "after the end 4"),
    ({"precedence": [(3, 0)]}, "before the start 0"),
])
def test_constraints_that_do_not_fit_the_problem_are_refused(kwargs, message) -> None:
    m = np.ones((5, 5)) - np.eye(5)
    with pytest.raises((ParameterError, InputDataError), match=message):
        solve(MatrixProblem(m), constraints=TourConstraints(**kwargs))


def test_problem_first_and_start_must_agree() -> None:
    m = np.ones((5, 5)) - np.eye(5)
    with pytest.raises(ParameterError, match="first=1 and the constraints' start=2"):
        solve(MatrixProblem(m, first=1), constraints=TourConstraints(start=2))
    with pytest.raises(ParameterError, match="constraints must be a TourConstraints"):
        solve(MatrixProblem(m), constraints=[(0, 1)])  # type: ignore[arg-type]


def test_read_precedence(tmp_path) -> None:
    good = tmp_path / "p.txt"
    good.write_text("# comment\n0,3\n\n 2 , 1 \n")
    assert read_precedence(good) == ((0, 3), (2, 1))
    bad = tmp_path / "bad.txt"
    bad.write_text("0,3\n1;2\n")
    with pytest.raises(InputDataError, match=r"line 2: expected 'a,b'"):
        read_precedence(bad)


@pytest.mark.parametrize("end", [None, 4])
def test_symmetric_path_matrix_turns_the_best_path_into_the_best_tour(end) -> None:
    from subtask_opt.tour.constraints import symmetric_path_matrix
    from subtask_opt.tour.exact import held_karp

    rng = np.random.default_rng(2)
    xy = rng.random((7, 2))
    m = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    tour_matrix, offset = symmetric_path_matrix(m, 1, end)
    np.testing.assert_array_equal(tour_matrix, tour_matrix.T)
    c = TourConstraints(tour="open", start=1, end=end)
    assert held_karp(tour_matrix)[0] - offset == pytest.approx(brute_force(m, c), rel=1e-12)

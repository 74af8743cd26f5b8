"""Fuzzy via-point selection: memberships (eq. 3-6), decision (eq. 7, Table 1), kinematics,
and the navigator on synthetic scans."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.geometry import wrap_angle
from subtask_opt.planners.reactive.fuzzy import (
    MAX_WEIGHT,
    FuzzyNavigator,
    FuzzyParams,
    fuzzy_decision,
    mu_clearance,
    mu_repulsion,
    mu_target,
    reciprocal_matrix,
    repulsive_potential,
    saaty_weights,
    table1,
)
from subtask_opt.planners.reactive.sonar import SonarRing
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc

# The paper's Table 1: seven candidates, three goals.
TABLE1 = np.array([
    [0.1, 0.2, 0.1, 0.4, 0.5, 0.25, 0.3],    # muG1
    [0.2, 0.5, 0.05, 0.5, 0.1, 0.3, 0.2],    # muG2
    [0.3, 0.6, 0.4, 0.7, 0.3, 0.6, 0.3],     # muG3
]).T
TABLE1_D = [0.1, 0.2, 0.05, 0.4, 0.1, 0.25, 0.2]


def test_table1_decision_is_candidate_4_with_mu_d_0_4():
    idx, mu_d = fuzzy_decision(TABLE1)
    assert idx + 1 == 4
    assert mu_d[idx] == 0.4
    assert mu_d.tolist() == TABLE1_D


def test_decision_respects_admissibility_and_breaks_ties_first():
    adm = np.ones(7, dtype=bool)
    adm[3] = False
    idx, _ = fuzzy_decision(TABLE1, adm)
    assert idx == 5          # next best muD = 0.25
    idx, _ = fuzzy_decision(np.array([[0.5, 0.6], [0.6, 0.5]]))
    assert idx == 0


def test_table1_report_prints_the_papers_numbers_beside_ours():
    report = table1()
    assert report.matches and not report.weighted and report.choice == 4
    np.testing.assert_array_equal(report.memberships, TABLE1)
    assert report.paper_mu_d == tuple(TABLE1_D)
    text = "\n".join(report.lines())
    assert "muD paper" in text and "muD ours" in text and "matches the paper" in text
    d = report.to_dict()
    assert d["mu_d"] == TABLE1_D and d["paper_choice"] == 4 and d["matches"] is True


def test_table1_with_weights_is_the_min_of_powered_memberships():
    w = (2.0, 0.5, 1.0)
    report = table1(w)
    expected = [min(TABLE1[i, j] ** w[j] for j in range(3)) for i in range(7)]
    np.testing.assert_allclose(report.mu_d, expected, rtol=1e-15)
    assert report.weighted and report.choice == int(np.argmax(expected)) + 1
    assert not report.matches          # G1 squared: candidate 4 gets 0.16, not 0.4


_MEMBERSHIPS = st.lists(st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3), min_size=1,
                        max_size=12).map(np.array)


@settings(max_examples=60, deadline=None)
@given(mu=_MEMBERSHIPS)
def test_unit_weights_are_the_plain_min(mu):
    idx_plain, d_plain = fuzzy_decision(mu)
    idx_w, d_w = fuzzy_decision(mu, weights=(1.0, 1.0, 1.0))
    np.testing.assert_array_equal(d_w, d_plain)
    assert idx_w == idx_plain
    # the plain min, by brute force over candidates and goals
    brute = [min(row) for row in mu.tolist()]
    assert d_plain.tolist() == brute
    assert idx_plain == brute.index(max(brute))


@settings(max_examples=60, deadline=None)
@given(mu=_MEMBERSHIPS, w=st.lists(st.floats(0.05, 20.0), min_size=3, max_size=3))
def test_weighted_decision_is_the_min_of_powers(mu, w):
    _, d = fuzzy_decision(mu, weights=w)
    brute = [min(mu[i, j] ** w[j] for j in range(3)) for i in range(mu.shape[0])]
    np.testing.assert_allclose(d, brute, rtol=1e-12, atol=0.0)


@settings(max_examples=60, deadline=None)
@given(v=st.lists(st.floats(0.01, 100.0), min_size=1, max_size=7))
def test_saaty_weights_of_a_consistent_matrix_are_its_eigenvector(v):
    # a consistent matrix a_ij = v_i / v_j has rank 1: a v = m v, so its principal
    # eigenvector is v itself; the weights are v scaled to sum to m
    v = np.array(v)
    m = v.size
    w, ci = saaty_weights(v[:, None] / v[None, :])
    np.testing.assert_allclose(w, m * v / v.sum(), rtol=1e-9)
    assert math.isclose(w.sum(), m, rel_tol=1e-12)
    assert ci == pytest.approx(0.0, abs=1e-9)


def test_saaty_weights_of_equal_importance_are_ones_and_give_the_plain_min():
    w, ci = saaty_weights(np.ones((3, 3)))
    np.testing.assert_allclose(w, 1.0, rtol=1e-12)
    assert ci == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(table1(w).mu_d, TABLE1_D, rtol=1e-12)


def test_saaty_consistency_index_of_an_inconsistent_matrix():
    # 3 > 1 > 3 > ... a cycle: lambda_max of [[1, k, 1/k], [1/k, 1, k], [k, 1/k, 1]] is
    # 1 + k + 1/k (the eigenvector is all ones by symmetry of the cycle)
    k = 3.0
    a = np.array([[1, k, 1 / k], [1 / k, 1, k], [k, 1 / k, 1]])
    w, ci = saaty_weights(a)
    np.testing.assert_allclose(w, 1.0, rtol=1e-9)
    assert ci == pytest.approx((1 + k + 1 / k - 3) / 2, rel=1e-9)


def test_reciprocal_matrix_from_the_upper_triangle():
    a = reciprocal_matrix([3.0, 5.0, 2.0])
    np.testing.assert_allclose(a, [[1, 3, 5], [1 / 3, 1, 2], [1 / 5, 1 / 2, 1]])
    with pytest.raises(InputDataError, match="m \\(m - 1\\) / 2"):
        reciprocal_matrix([1.0, 2.0])
    with pytest.raises(InputDataError, match="> 0"):
        reciprocal_matrix([1.0, 0.0, 2.0])


@pytest.mark.parametrize("bad, words", [
    (np.ones((2, 3)), "square"), (np.array([[1.0, -2.0], [-0.5, 1.0]]), "> 0"),
    (np.array([[1.0, 2.0], [2.0, 1.0]]), "reciprocal"), ("abc", "square"),
    (np.array([[1.0, np.inf], [0.0, 1.0]]), "finite"), (np.zeros((0, 0)), "square"),
])
def test_saaty_rejects_bad_matrices(bad, words):
    with pytest.raises(InputDataError, match=words):
        saaty_weights(bad)


@pytest.mark.parametrize("weights", [(1.0, 1.0), (0.0, 1.0, 1.0), (1.0, -2.0, 1.0),
                                     (1.0, float("nan"), 1.0), (1.0, MAX_WEIGHT * 2, 1.0),
                                     (True, 1.0, 1.0), ("1", 1.0, 1.0), 3.0])
def test_bad_weights_raise(weights):
    with pytest.raises(ParameterError, match="weights"):
        FuzzyParams(weights=weights)
    with pytest.raises(ParameterError, match="weights"):
        table1(weights)


def test_weights_change_the_navigators_choice_only_through_mu_d():
    # equal weights: the decision equals the unweighted navigator's
    pose, ranges, goal = np.zeros(3), np.full(18, 2.5), np.array([5.0, 1.0])
    ranges[6:10] = 0.9
    a = _nav().decide(pose, ranges, goal)
    b = _nav(weights=(1.0, 1.0, 1.0)).decide(pose, ranges, goal)
    assert (a.v, a.omega) == (b.v, b.omega)
    c = _nav(weights=(4.0, 1.0, 1.0)).decide(pose, ranges, goal)
    assert c.mu[3] == pytest.approx(min(c.mu[0] ** 4.0, c.mu[1], c.mu[2]))


@pytest.mark.parametrize("bad", [np.zeros((0, 3)), np.array([0.1, 0.2]),
                                 np.array([[0.1, 1.2]]), np.array([[np.nan, 0.2]])])
def test_decision_rejects_bad_memberships(bad):
    with pytest.raises(InputDataError):
        fuzzy_decision(bad)


def test_mu_clearance_sigmoid_and_open_space():
    u = np.array([0.2, 0.6, 1.4])
    mu = mu_clearance(u, 0.6, 10.0, 2.5)
    np.testing.assert_allclose(mu, 1.0 / (1.0 + np.exp(-10.0 * (u - 0.6))))
    assert mu[1] == 0.5
    np.testing.assert_array_equal(mu_clearance(np.full(4, 2.5), 0.6, 10.0, 2.5), 1.0)


def test_repulsive_potential_and_mu_repulsion():
    scans = np.array([[2.5, 2.5, 1.5], [0.5, 2.5, 2.5]])
    f = repulsive_potential(scans, 2.5)
    np.testing.assert_allclose(f, [1.0, 2.0])
    mu = mu_repulsion(f, 30.0, 0.0)
    np.testing.assert_allclose(mu, 1.0 / (1.0 + f / 30.0))
    assert mu[0] > mu[1]             # more obstacle area, less satisfied
    assert mu_repulsion(np.array([29.0]), 30.0, 1.0)[0] == 0.5
    np.testing.assert_array_equal(mu_repulsion(np.zeros(3), 30.0, 1.0), 1.0)


def test_mu_target_is_a_linear_rank_from_0_9_to_0_1():
    d = np.array([3.0, 1.0, 2.0, 5.0])
    np.testing.assert_allclose(mu_target(d), [0.5, 0.9, 0.7, 0.1])
    np.testing.assert_array_equal(mu_target(np.full(3, 2.0)), 0.9)


# ------------------------------------------------------------------ kinematics

def test_arc_closed_forms():
    straight = integrate_arc(np.array([1.0, 2.0, 0.5]), 0.4, 0.0, 2.0)
    np.testing.assert_allclose(straight, [1.0 + 0.8 * math.cos(0.5), 2.0 + 0.8 * math.sin(0.5),
                                          0.5])
    # a quarter circle of radius 1 turning left from the origin facing +x ends at (1, 1)
    quarter = integrate_arc(np.zeros(3), 1.0, 1.0, math.pi / 2)
    np.testing.assert_allclose(quarter, [1.0, 1.0, math.pi / 2], atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(v=st.floats(0.0, 1.0), om=st.floats(-2.0, 2.0), th=st.floats(-3.0, 3.0))
def test_arc_matches_fine_euler_integration(v, om, th):
    pose = np.array([0.3, -0.2, th])
    exact = integrate_arc(pose, v, om, 0.5)
    x, y, h = pose
    n = 20000
    for _ in range(n):   # midpoint Euler, a second method
        hm = h + 0.5 * om * 0.5 / n
        x += v * math.cos(hm) * 0.5 / n
        y += v * math.sin(hm) * 0.5 / n
        h += om * 0.5 / n
    np.testing.assert_allclose(exact[:2], [x, y], atol=1e-9)
    assert abs(wrap_angle(exact[2] - h)) < 1e-9
    vec = integrate_arc(pose, np.array([v, v]), np.array([om, om]), 0.5)
    np.testing.assert_allclose(vec[0], exact, atol=1e-12)


def test_commands_grid_and_limits():
    robot = Unicycle(max_speed=0.3, max_turn_rate=1.2)
    v, om = robot.commands(9, 4)
    assert v.shape == om.shape == (36,)
    np.testing.assert_allclose(np.unique(v), [0.0, 0.1, 0.2, 0.3])
    assert np.isclose(om.min(), -1.2) and np.isclose(om.max(), 1.2) and np.any(om == 0.0)
    assert robot.clip(5.0, -9.0) == (0.3, -1.2)
    assert robot.clip(-1.0, 0.5) == (0.0, 0.5)


@pytest.mark.parametrize("field", ["max_speed", "max_turn_rate", "dt", "radius"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), "1", 1j])
def test_non_positive_robot_limits_raise(field, value):
    with pytest.raises(ParameterError, match=field):
        Unicycle(**{field: value})


def test_more_than_half_a_turn_per_period_is_refused():
    Unicycle(max_turn_rate=math.pi, dt=1.0)
    with pytest.raises(ParameterError, match="max_turn_rate must be <= pi / dt"):
        Unicycle(max_turn_rate=math.pi + 1e-9, dt=1.0)


@pytest.mark.parametrize("kwargs, field", [
    ({"c1": 0.0}, "c1"), ({"d1": -1.0}, "d1"), ({"d2": 0.0}, "d2"), ({"d3": -0.1}, "d3"),
    ({"n_headings": 0}, "n_headings"), ({"n_speeds": 1.5}, "n_speeds"),
    ({"virtual_target_distance": 0.0}, "virtual_target_distance"),
    ({"safety_margin": -0.01}, "safety_margin"), ({"follow_distance": 0.0}, "follow_distance"),
    ({"max_follow_steps": 0}, "max_follow_steps"), ({"trap_steps": -1}, "trap_steps"),
    ({"n_headings": 10**6}, "n_headings"), ({"n_speeds": "4"}, "n_speeds"),
])
def test_bad_fuzzy_parameters_raise(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        FuzzyParams(**kwargs)


# ------------------------------------------------------------------ navigator

def _nav(**kw) -> FuzzyNavigator:
    return FuzzyNavigator(Unicycle(), SonarRing(max_range=2.5), FuzzyParams(**kw))


def test_open_space_goes_full_speed_at_the_goal():
    nav = _nav()
    d = nav.decide(np.array([0.0, 0.0, 0.0]), np.full(18, 2.5), np.array([5.0, 0.0]))
    assert d.v == nav.robot.max_speed and d.omega == 0.0
    np.testing.assert_allclose(d.mu, [1.0, 1.0, 0.9, 0.9])
    assert not d.escaping


def test_turns_toward_a_goal_on_the_left():
    nav = _nav()
    d = nav.decide(np.array([0.0, 0.0, 0.0]), np.full(18, 2.5), np.array([0.0, 5.0]))
    assert d.omega == nav.robot.max_turn_rate


def test_never_drives_into_a_wall_it_sees():
    # every beam sees a wall just beyond the body: only turning in place is admissible
    nav = _nav()
    d = nav.decide(np.zeros(3), np.full(18, 0.3), np.array([5.0, 0.0]))
    assert d.v == 0.0


def test_a_near_wall_on_the_right_is_not_turned_into():
    ranges = np.full(18, 2.5)
    ranges[:6] = 0.45
    nav = _nav()
    d = nav.decide(np.zeros(3), ranges, np.array([5.0, -1.0]))   # goal slightly right
    assert d.omega >= 0 and d.v > 0
    free = nav.decide(np.zeros(3), np.full(18, 2.5), np.array([5.0, -1.0]))
    assert free.omega < 0                                          # which it would do


def test_local_minimum_starts_wall_following_and_ends():
    nav = _nav(trap_steps=0)
    goal = np.array([0.0, -5.0])
    # heading +y, goal behind, one echo 0.7 away at +5 degrees: trapped
    ranges = np.full(18, 2.5)
    ranges[9] = 0.7
    d = nav.decide(np.array([0.0, 0.0, math.pi / 2]), ranges, goal)
    assert d.escaping
    # the virtual target lies virtual_target_distance along the wall tangent (90 degrees
    # from the echo direction, on the side nearer the heading) from the point
    # follow_distance off the wall
    u = math.radians(95.0)
    foot = (0.7 - 0.8) * np.array([math.cos(u), math.sin(u)])
    tangent = np.array([math.cos(u - math.pi / 2), math.sin(u - math.pi / 2)])
    np.testing.assert_allclose(d.target, foot + 1.0 * tangent, atol=1e-12)
    # heading at the goal with nothing in view, and closer than at the start: episode over
    d = nav.decide(np.array([0.0, -1.0, -math.pi / 2]), np.full(18, 2.5), goal)
    assert not d.escaping
    np.testing.assert_array_equal(d.target, goal)


def test_no_escape_variant_never_wall_follows():
    nav = _nav(trap_steps=0, escape=False)
    ranges = np.full(18, 2.5)
    ranges[7:11] = 0.7
    for _ in range(3):
        d = nav.decide(np.array([0.0, 0.0, math.pi / 2]), ranges, np.array([0.0, -5.0]))
        assert not d.escaping
    assert nav.name == "fuzzy-no-escape"

"""Fuzzy via-point selection: memberships (eq. 3-6), decision (eq. 7, Table 1), kinematics,
and the navigator on synthetic scans."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.planners.reactive.fuzzy import (
    FuzzyNavigator,
    FuzzyParams,
    fuzzy_decision,
    mu_clearance,
    mu_repulsion,
    mu_target,
    repulsive_potential,
)
from subtask_opt.planners.reactive.sonar import SonarRing
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc, wrap_angle

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
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan")])
def test_non_positive_robot_limits_raise(field, value):
    with pytest.raises(ParameterError, match=field):
        Unicycle(**{field: value})


@pytest.mark.parametrize("kwargs, field", [
    ({"c1": 0.0}, "c1"), ({"d1": -1.0}, "d1"), ({"d2": 0.0}, "d2"), ({"d3": -0.1}, "d3"),
    ({"n_headings": 0}, "n_headings"), ({"n_speeds": 1.5}, "n_speeds"),
    ({"virtual_target_distance": 0.0}, "virtual_target_distance"),
    ({"safety_margin": -0.01}, "safety_margin"), ({"follow_distance": 0.0}, "follow_distance"),
    ({"max_follow_steps": 0}, "max_follow_steps"), ({"trap_steps": -1}, "trap_steps"),
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

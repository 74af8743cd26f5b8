"""Sonar ring: ray casting against polygon worlds, seeded noise, scan prediction."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.planners.polygon.world import PolygonWorld
from subtask_opt.planners.reactive.sonar import SonarRing, predict_scan, scene_edges, to_robot_frame

BOX = PolygonWorld((0.0, 0.0, 4.0, 4.0), (), name="box")
CLUTTER = PolygonWorld((0.0, 0.0, 6.0, 6.0), (
    np.array([[1.0, 1.0], [2.0, 1.2], [1.5, 2.2]]),
    np.array([[3.5, 3.5], [5.0, 3.5], [5.0, 5.0], [3.5, 5.0]]),
    np.array([[4.0, 0.8], [5.2, 1.5], [4.4, 2.4]]),
), name="clutter")


def test_beam_layout_matches_the_paper_ring():
    ring = SonarRing()
    assert ring.n_beams == 18
    np.testing.assert_allclose(np.degrees(ring.angles), np.arange(-85.0, 86.0, 10.0))
    assert math.isclose(ring.spacing, math.radians(10.0))


def test_ranges_in_an_empty_box_match_the_closed_form():
    # robot at the centre facing +x: the wall x = 4 is 2 away along the heading, a beam at
    # angle a meets it at 2 / cos(a) while |a| < 45 degrees, else the wall y = 0 or y = 4
    ring = SonarRing(max_range=10.0)
    pose = np.array([2.0, 2.0, 0.0])
    ranges = ring.scan(scene_edges(BOX), pose)
    a = ring.angles
    expected = np.where(np.abs(a) < math.pi / 4, 2.0 / np.cos(a), 2.0 / np.abs(np.sin(a)))
    np.testing.assert_allclose(ranges, expected, rtol=1e-12)


def test_out_of_range_reads_max_range():
    ring = SonarRing(max_range=1.0)
    ranges = ring.scan(scene_edges(BOX), np.array([2.0, 2.0, 0.3]))
    np.testing.assert_array_equal(ranges, np.full(18, 1.0))


@settings(max_examples=30, deadline=None)
@given(x=st.floats(0.3, 5.7), y=st.floats(0.3, 5.7), th=st.floats(-math.pi, math.pi))
def test_every_echo_lies_on_a_wall_and_the_beam_before_it_is_free(x, y, th):
    pose = np.array([x, y, th])
    assume(CLUTTER.is_free(pose[:2]))
    ring = SonarRing(max_range=3.0)
    ranges = ring.scan(scene_edges(CLUTTER), pose)
    assert np.all((ranges >= 0) & (ranges <= 3.0))
    ends = ring.hit_points(pose, ranges)
    for r, end in zip(ranges, ends, strict=True):
        short = pose[:2] + 0.999 * (end - pose[:2])
        assert CLUTTER.segment_free(pose[:2], short)   # nothing hit before the echo
        if r < 3.0:
            assert CLUTTER.distance_to_obstacles(end) < 1e-9   # the echo is on a wall


def test_noise_is_seeded_and_only_on_echoes():
    ring = SonarRing(max_range=2.5, noise_std=0.05)
    edges = scene_edges(CLUTTER)
    pose = np.array([0.5, 0.5, 0.7])
    a = ring.scan(edges, pose, np.random.default_rng(3))
    b = ring.scan(edges, pose, np.random.default_rng(3))
    c = ring.scan(edges, pose, np.random.default_rng(4))
    clean = SonarRing(max_range=2.5).scan(edges, pose)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    none = clean >= 2.5
    np.testing.assert_array_equal(a[none], clean[none])
    assert np.all((a >= 0) & (a <= 2.5))
    with pytest.raises(ParameterError, match="rng"):
        ring.scan(edges, pose)


def test_prediction_translates_a_perpendicular_wall():
    # 19 beams over 190 degrees: one beam straight ahead, facing a wall 1.5 away
    ring = SonarRing(n_beams=19, fov_deg=190.0, max_range=3.0)
    world = PolygonWorld((0.0, 0.0, 10.0, 10.0), (np.array([[4.5, 2.0], [5.0, 2.0], [5.0, 8.0],
                                                             [4.5, 8.0]]),))
    pose = np.array([3.0, 5.0, 0.0])
    ranges = ring.scan(scene_edges(world), pose)
    assert math.isclose(ranges[9], 1.5)
    cand = np.array([[3.2, 5.0, 0.0], [3.0, 5.0, 0.0]])
    pred, clearance = predict_scan(ring, ranges, pose, cand)
    assert math.isclose(pred[0, 9], 1.3, abs_tol=1e-12)
    np.testing.assert_allclose(pred[1], ranges, atol=1e-12)   # staying put changes nothing
    assert math.isclose(clearance[0], 1.3, abs_tol=1e-12)


def test_prediction_of_a_rotation_in_a_round_room_shifts_the_view():
    # turning by k beam spacings: beam j now looks where beam j + k looked (the wall of a
    # round room of radius 2); beams turned past the old field of view see open space
    ring = SonarRing(max_range=3.0)
    ranges = np.full(18, 2.0)
    pose = np.array([1.0, 1.0, 0.2])
    for k in (-2, -1, 1, 3):
        pred, _ = predict_scan(ring, ranges, pose, np.array([[1.0, 1.0, 0.2 + k * ring.spacing]]))
        inside = (np.arange(18) + k >= 0) & (np.arange(18) + k < 18)
        np.testing.assert_allclose(pred[0], np.where(inside, 2.0, 3.0), atol=1e-12)


def test_unseen_space_is_open():
    ring = SonarRing(max_range=2.0)
    pred, clearance = predict_scan(ring, np.full(18, 2.0), np.zeros(3),
                                   np.array([[0.3, 0.1, 0.5], [0.0, 0.0, -1.0]]))
    np.testing.assert_array_equal(pred, 2.0)
    assert np.all(np.isinf(clearance))


@settings(max_examples=25, deadline=None)
@given(ranges=st.lists(st.floats(0.05, 2.5), min_size=18, max_size=18),
       dx=st.floats(-0.3, 0.3), dy=st.floats(-0.3, 0.3), dth=st.floats(-1.0, 1.0))
def test_predicted_readings_stay_in_range(ranges, dx, dy, dth):
    ring = SonarRing(max_range=2.5)
    pred, clearance = predict_scan(ring, np.array(ranges), np.array([1.0, 2.0, 0.4]),
                                   np.array([[1.0 + dx, 2.0 + dy, 0.4 + dth]]))
    assert np.all((pred >= 0) & (pred <= 2.5))
    assert clearance[0] >= 0


def test_robot_frame_round_trip():
    pose = np.array([1.0, -2.0, 0.7])
    p = np.array([[2.0, 0.5], [-1.0, 3.0]])
    q = to_robot_frame(pose, p)
    c, s = math.cos(0.7), math.sin(0.7)
    back = pose[:2] + q @ np.array([[c, s], [-s, c]])
    np.testing.assert_allclose(back, p, atol=1e-12)


@pytest.mark.parametrize("kwargs, field", [
    ({"max_range": 0.0}, "max_range"), ({"max_range": -1.0}, "max_range"),
    ({"n_beams": 0}, "n_beams"), ({"fov_deg": 0.0}, "fov_deg"), ({"fov_deg": 400.0}, "fov_deg"),
    ({"noise_std": -0.1}, "noise_std"), ({"overlap": 0.5}, "overlap"),
    ({"noise_std": 2.6}, "noise_std"), ({"n_beams": 3601}, "n_beams"),
    ({"max_range": float("inf")}, "max_range"), ({"n_beams": 18.0}, "n_beams"),
    ({"max_range": 1e7}, "max_range"),
])
def test_bad_sonar_parameters_raise(kwargs, field):
    with pytest.raises(ParameterError, match=field):
        SonarRing(**kwargs)


def test_bad_prediction_shapes_raise():
    ring = SonarRing()
    with pytest.raises(InputDataError, match="ranges"):
        predict_scan(ring, np.ones(5), np.zeros(3), np.zeros((1, 3)))
    with pytest.raises(InputDataError, match="candidates"):
        predict_scan(ring, np.ones(18), np.zeros(3), np.zeros((2, 2)))

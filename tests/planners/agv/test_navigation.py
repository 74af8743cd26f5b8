"""Corners (rules 2-x), navigation (rules 3-x) and route sections (rules 1-5)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from subtask_opt.base.errors import NoPathError, ParameterError
from subtask_opt.planners.agv.navigation import (
    build_tree,
    detect_corners,
    landmarks,
    navigate,
    near_points,
    room_corners,
    segment_route,
)
from subtask_opt.planners.agv.quadtree import WHITE
from subtask_opt.planners.grid.distance_transform import DTParams
from subtask_opt.planners.grid.distance_transform import plan as grid_plan
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.agv.test_quadtree import _crosses_obstacle, _maps


def _printed_rules_2(occ: np.ndarray) -> np.ndarray:
    """Rules 2-2 ... 2-6 exactly as printed (rows, columns; '0' = free)."""
    h, w = occ.shape
    g = np.pad(occ.astype(int), 1, constant_values=0)
    edge = np.zeros_like(occ)
    for r in range(h):
        for c in range(w):
            R, C = r + 1, c + 1
            if g[R, C] == 0:  # rule 2-2
                continue
            if g[R - 1, C - 1] == 0 and g[R, C] == 0 and g[R + 1, C] == 0:  # 2-3
                continue
            if g[R, C - 1] == 0 and g[R, C] == 0 and g[R, C + 1] == 0:  # 2-4
                continue
            if g[R - 1, C - 1] == 0 and g[R, C] == 0 and g[R + 1, C + 1] == 0:  # 2-5
                continue
            if g[R - 1, C + 1] == 0 and g[R, C] == 0 and g[R + 1, C - 1] == 0:  # 2-6
                continue
            edge[r, c] = True  # ELSE
    return edge


def test_printed_rules_2_3_to_2_6_never_fire():
    rng = np.random.default_rng(4)
    occ = rng.random((15, 17)) < 0.4
    # as printed, every obstacle cell is an edge: the reading is needed
    np.testing.assert_array_equal(_printed_rules_2(occ), occ)
    assert detect_corners(occ).sum() < occ.sum()


def test_rectangle_has_four_corners_and_four_near_points():
    occ = np.zeros((10, 10), dtype=bool)
    occ[3:6, 2:8] = True
    corners = detect_corners(occ)
    assert sorted(map(tuple, np.argwhere(corners))) == [(3, 2), (3, 7), (5, 2), (5, 7)]
    pts = near_points(occ)
    assert sorted(map(tuple, pts.astype(int))) == [(1, 2), (1, 6), (8, 2), (8, 6)]
    # the landmarks are the rectangle's four outer vertices
    assert sorted(map(tuple, landmarks(occ))) == [(1.5, 2.5), (1.5, 5.5), (7.5, 2.5),
                                                  (7.5, 5.5)]


def test_wall_ends_are_corners_and_diagonal_lines_are_not():
    occ = np.zeros((7, 7), dtype=bool)
    occ[1, 1:6] = True
    assert sorted(map(tuple, np.argwhere(detect_corners(occ)))) == [(1, 1), (1, 5)]
    diag = np.eye(7, dtype=bool)
    assert sorted(map(tuple, np.argwhere(detect_corners(diag)))) == [(0, 0), (6, 6)]


def test_goal_in_sight_is_reached_straight_else_via_near_points():
    occ = np.zeros((12, 12), dtype=bool)
    tree = build_tree(occ)
    assert navigate(tree, occ, (0, 0), (11, 11)).tolist() == [[11, 11]]
    occ[2:12, 5] = True
    tree = build_tree(occ)
    sub = navigate(tree, occ, (1, 10), (10, 10))
    pts = {tuple(p) for p in near_points(occ)}
    assert all(tuple(p) in pts for p in sub[:-1]) and sub[-1].tolist() == [10, 10]
    assert not _crosses_obstacle(occ, np.vstack([[1, 10], sub]))


def test_navigation_raises_when_the_goal_is_enclosed():
    occ = np.zeros((8, 8), dtype=bool)
    occ[3:6, 3] = occ[3:6, 5] = occ[3, 3:6] = occ[5, 3:6] = True
    with pytest.raises(NoPathError):
        navigate(build_tree(occ), occ, (0, 0), (4, 4))


def _covers(sections, route) -> None:
    """Sections tile each leg in order: consecutive ends meet, legs start and end
    at the route's points."""
    for leg, (a, b) in enumerate(zip(route[:-1], route[1:], strict=True)):
        mine = [s for s in sections if s.leg == leg]
        assert mine and mine[0].start == tuple(a) and mine[-1].end == tuple(b)
        for s, t in zip(mine[:-1], mine[1:], strict=True):
            assert s.end == t.start


def test_a_leg_inside_one_free_leaf_is_not_split():
    occ = np.zeros((16, 16), dtype=bool)
    tree = build_tree(occ)
    route = np.array([[1.0, 1.0], [14.0, 14.0]])
    secs = segment_route(route, tree)
    assert [(s.road, s.leaves) for s in secs] == [("known", (0,))]
    assert int(tree.nodes[0, 3]) == WHITE


def test_sections_split_at_turns_and_where_the_road_narrows():
    occ = np.zeros((16, 16), dtype=bool)
    occ[7, 0:6] = occ[7, 10:16] = occ[9, 0:6] = occ[9, 10:16] = True  # a gap at x 6..9
    tree = build_tree(occ)
    route = np.array([[2.0, 2.0], [8.0, 3.0], [8.0, 13.0], [13.0, 13.0]])
    secs = segment_route(route, tree, open_leaf=4)
    _covers(secs, route)
    legs = {s.leg for s in secs}
    assert legs == {0, 1, 2}  # rule 3: a section ends at every turn
    middle = [s.road for s in secs if s.leg == 1]
    # rule 4, by hand: x = 8 runs through the 4x4 white leaf (8, 0), the small
    # leaves around the gap (rows 4 ... 11), then the 4x4 white leaf (8, 12)
    assert middle == ["open", "narrow", "open"]
    cut = [s.end for s in secs if s.leg == 1][:2]
    assert 3.5 <= cut[0][1] <= 4.0 and 11.5 <= cut[1][1] <= 12.0
    # every leaf a section names is a leaf the leg passes
    for s in secs:
        for lf in s.leaves:
            assert tree.leaf[lf]


def test_segment_route_rejects_bad_open_leaf():
    tree = build_tree(np.zeros((4, 4), dtype=bool))
    with pytest.raises(ParameterError, match="open_leaf"):
        segment_route(np.zeros((2, 2)), tree, open_leaf=0)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_maps())
def test_navigation_finds_a_route_iff_the_grid_planner_does(case):
    """Oracle: the 8-connected distance transform of the grid family."""
    occ, start, goal = case
    world = GridWorld(occ)
    grid = grid_plan(world, start, goal, params=DTParams("octile"))
    tree = build_tree(occ)
    try:
        sub = navigate(tree, occ, start, goal)
    except NoPathError:
        assert not grid.success
        return
    assert grid.success
    route = np.vstack([np.array(start, dtype=float), sub])
    assert route[-1].tolist() == list(goal)
    assert not _crosses_obstacle(occ, route)
    assert all(tree.segment_free(a, b) for a, b in zip(route[:-1], route[1:], strict=True))


def test_room_corners_are_the_free_corners_of_the_map():
    occ = np.zeros((4, 6), dtype=bool)
    occ[3, 5] = True
    assert sorted(map(tuple, room_corners(occ))) == [(-0.5, -0.5), (-0.5, 3.5), (5.5, -0.5)]


def test_routes_keep_the_wall_clearance():
    """Every leg of a planned route (near points, rule 3-1 and the one-leaf
    fallback) keeps more than the clearance from walls, by shapely; without a
    clearance some routes graze a corner."""
    from subtask_opt.planners.agv.scenarios import random_agv_scenario
    from subtask_opt.planners.agv.simulation import AgvParams, plan_route
    from tests.planners.agv.collision_oracle import wall_clearance

    grazing = 0
    for seed in range(910_000, 910_040):
        sc = random_agv_scenario(seed, n_obstacles=0)
        route = plan_route(sc.world, sc.start, sc.goal, sc.params, states=sc.states)
        assert wall_clearance(sc.world.occupancy, route) > sc.params.wall_clearance, seed
        bare = plan_route(sc.world, sc.start, sc.goal, AgvParams(wall_clearance=0.0),
                          states=sc.states)
        grazing += wall_clearance(sc.world.occupancy, bare) < sc.params.wall_clearance
    assert grazing > 0

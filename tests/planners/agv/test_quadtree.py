"""Quadtree decomposition and the planner over its free leaves."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.base.results import Outcome
from subtask_opt.planners.agv.quadtree import (
    BLACK,
    GREY,
    WHITE,
    QuadtreeParams,
    compare_with_grid,
    decompose,
    plan,
)
from subtask_opt.planners.grid.distance_transform import DTParams
from subtask_opt.planners.grid.distance_transform import plan as grid_plan
from subtask_opt.planners.grid.world import GridWorld


def _crosses_obstacle(occ: np.ndarray, path: np.ndarray, step: float = 0.01) -> bool:
    """Independent check: sample every segment densely; a sample strictly
    inside a blocked cell (or outside the grid) is a crossing."""
    h, w = occ.shape
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(2, int(np.ceil(np.hypot(*(b - a)) / step)) + 1)
        pts = a + np.linspace(0, 1, n)[:, None] * (b - a)
        cells = np.floor(pts + 0.5).astype(int)
        inside = np.abs(pts - cells).max(axis=1) < 0.5 - 1e-9
        x, y = cells[:, 0], cells[:, 1]
        if np.any((x < 0) | (x >= w) | (y < 0) | (y >= h)):
            return True
        if np.any(occ[y[inside], x[inside]]):
            return True
    return False


def test_leaves_partition_the_grid_with_pure_colours():
    rng = np.random.default_rng(1)
    occ = rng.random((13, 21)) < 0.3
    tree = decompose(occ)
    covered = np.zeros(occ.shape, dtype=int)
    for x0, y0, size, colour, _ in tree.leaves:
        block = occ[y0:y0 + size, x0:x0 + size]
        covered[y0:y0 + size, x0:x0 + size] += 1
        if colour == WHITE:
            assert not block.any()
        else:
            assert colour == BLACK and (block.all() or block.shape != (size, size))
    np.testing.assert_array_equal(covered, 1)
    assert tree.count(GREY) == 0  # min_size 1: every grey node is split


def test_empty_map_is_one_white_leaf_and_min_size_leaves_grey():
    tree = decompose(np.zeros((8, 8), dtype=bool))
    assert tree.leaves.tolist() == [[0, 0, 8, WHITE, 0]]
    occ = np.zeros((8, 8), dtype=bool)
    occ[0, 0] = True
    coarse = decompose(occ, QuadtreeParams(min_size=4))
    assert coarse.count(GREY) == 1 and coarse.count(WHITE) == 3


def test_path_around_a_wall_and_straightening_shortens():
    occ = np.zeros((16, 16), dtype=bool)
    occ[2:16, 7] = True
    world = GridWorld(occ)
    res = plan(world, (1, 14), (14, 14))
    assert res.success and not _crosses_obstacle(occ, res.path)
    assert res.length <= res.info["raw_length"] + 1e-9
    assert res.length >= np.hypot(6, 13) * 2 - 1e-6  # must go over the wall top
    assert res.path[0].tolist() == [1, 14] and res.path[-1].tolist() == [14, 14]


def test_no_path_and_bad_points():
    occ = np.zeros((8, 8), dtype=bool)
    occ[:, 4] = True
    world = GridWorld(occ)
    res = plan(world, (0, 0), (7, 7))
    assert not res.success and "no path" in res.message and res.outcome == Outcome.NO_PATH
    with pytest.raises(ParameterError, match="seed"):
        plan(world, (0, 0), (3, 3), seed=-1)
    with pytest.raises(ParameterError, match="stop"):
        plan(world, (0, 0), (3, 3), stop=5)
    with pytest.raises(UnreachableError, match="goal"):
        plan(world, (0, 0), (4, 3))
    with pytest.raises(UnreachableError, match="start"):
        plan(world, (9, 0), (7, 7))
    with pytest.raises(ParameterError, match="min_size"):
        QuadtreeParams(min_size=3)


def test_compare_with_grid_reports_both():
    rng = np.random.default_rng(2)
    occ = rng.random((20, 20)) < 0.2
    occ[0, 0] = occ[19, 19] = False
    rows = compare_with_grid(GridWorld(occ), (0, 0), (19, 19), repeats=1)
    assert set(rows) == {"quadtree", "grid"}
    assert rows["grid"]["success"] and rows["quadtree"]["success"]
    assert rows["quadtree"]["nodes"] < rows["grid"]["nodes"] == int((~occ).sum())


@st.composite
def _maps(draw):
    h = draw(st.integers(2, 14))
    w = draw(st.integers(2, 14))
    density = draw(st.floats(0.0, 0.5))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    occ = rng.random((h, w)) < density
    free = np.argwhere(~occ)
    if len(free) < 2:
        occ[0, 0] = occ[h - 1, w - 1] = False
        free = np.argwhere(~occ)
    i, j = rng.choice(len(free), size=2, replace=False)
    (sy, sx), (gy, gx) = free[i], free[j]
    return occ, (int(sx), int(sy)), (int(gx), int(gy))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_maps())
def test_quadtree_finds_a_path_iff_the_grid_planner_does(case):
    occ, start, goal = case
    world = GridWorld(occ)
    ours = plan(world, start, goal)
    grid = grid_plan(world, start, goal, params=DTParams("octile"))
    assert ours.success == grid.success
    if ours.success:
        assert not _crosses_obstacle(occ, ours.path)
        assert ours.path[0].tolist() == list(start) and ours.path[-1].tolist() == list(goal)
        assert ours.length <= ours.info["raw_length"] + 1e-9
        assert ours.length >= np.hypot(goal[0] - start[0], goal[1] - start[1]) - 1e-9


def _brute_segment_free(occ: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Oracle of the closed-square rule with exact fractions: the segment is
    blocked when it meets the closed square of a blocked or outside cell."""
    from fractions import Fraction as F

    h, w = occ.shape
    x0, y0, x1, y1 = (F(float(v)) for v in (*a, *b))
    for cy in range(-1, h + 1):
        for cx in range(-1, w + 1):
            if 0 <= cx < w and 0 <= cy < h and not occ[cy, cx]:
                continue
            t0, t1 = F(0), F(1)
            ok = True
            for p, q in ((x0 - x1, x0 - (cx - F(1, 2))), (x1 - x0, cx + F(1, 2) - x0),
                         (y0 - y1, y0 - (cy - F(1, 2))), (y1 - y0, cy + F(1, 2) - y0)):
                if p == 0:
                    ok &= q >= 0
                elif p < 0:
                    t0 = max(t0, q / p)
                else:
                    t1 = min(t1, q / p)
            if ok and t0 <= t1:
                return False
    return True


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_maps(), st.integers(0, 2**31 - 1))
def test_tree_segment_check_is_the_grid_rule(case, seed):
    """One line-of-sight rule: the quadtree query equals the grid family's
    exact kernel between cell centres, and an exact-fraction oracle anywhere."""
    from subtask_opt.planners.grid._kernels import segment_hits

    occ, start, goal = case
    tree = decompose(occ)
    h, w = occ.shape
    assert tree.segment_free(start, goal) == (
        segment_hits(occ, start[0], start[1], goal[0], goal[1], True) == 0)
    rng = np.random.default_rng(seed)
    a = rng.uniform(-0.4, [w - 0.6, h - 0.6])
    b = rng.uniform(-0.4, [w - 0.6, h - 0.6])
    if rng.random() < 0.3:  # half-integers: segments grazing cell corners
        a, b = np.round(a * 2) / 2, np.round(b * 2) / 2
    assert tree.segment_free(a, b) == _brute_segment_free(occ, a, b)


def test_tree_segment_check_grazing_a_corner_is_blocked():
    occ = np.zeros((3, 3), dtype=bool)
    occ[0, 1] = True
    tree = decompose(occ)
    assert not tree.segment_free((0, 0), (1, 1))  # touches the corner (0.5, 0.5)
    assert tree.segment_free((0, 1), (2, 1))      # half a cell below the block's edge
    assert not tree.segment_free((0, 0.5), (2, 0.5))  # runs along the block's edge


def test_the_independent_check_sees_a_crossing():
    occ = np.zeros((3, 3), dtype=bool)
    occ[1, 1] = True
    assert _crosses_obstacle(occ, np.array([[0.0, 0.0], [2.0, 2.0]]))
    assert not _crosses_obstacle(occ, np.array([[0.0, 0.0], [0.0, 2.0], [2.0, 2.0]]))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_maps(), st.integers(0, 2**31 - 1), st.floats(0.0, 1.2))
def test_tree_segment_clearance_is_the_distance_to_the_blocked_area(case, seed, clearance):
    """With a clearance, a segment is free when its distance (shapely) to the
    blocked cells' squares and to the outside of the grid exceeds it."""
    from shapely.geometry import LineString

    from tests.planners.agv.collision_oracle import walls

    occ, _, _ = case
    tree = decompose(occ)
    h, w = occ.shape
    rng = np.random.default_rng(seed)
    blocked = walls(occ)
    for _ in range(10):
        a = rng.uniform(-0.4, [w - 0.6, h - 0.6])
        b = a + rng.normal(0.0, 2.0, 2) if rng.random() < 0.5 else rng.uniform(
            -0.4, [w - 0.6, h - 0.6])
        seg = LineString([a, b]) if not np.array_equal(a, b) else LineString([a, a + 1e-9])
        gap = 0.0 if seg.intersects(blocked) else seg.distance(blocked)
        if abs(gap - clearance) < 1e-9:
            continue  # a tie, decided by rounding either way
        assert tree.segment_free(a, b, clearance) == (gap > clearance), (a, b, gap)


def test_tree_segment_clearance_by_hand():
    occ = np.zeros((5, 5), dtype=bool)
    occ[2, 2] = True  # square [1.5, 2.5]^2
    tree = decompose(occ)
    assert tree.segment_free((0, 1), (4, 1), 0.49)  # half a cell from its face
    assert not tree.segment_free((0, 1), (4, 1), 0.5)
    # past the corner (1.5, 1.5) at distance sqrt(0.5): along x + y = 2, closest at (1, 1)
    assert tree.segment_free((0.4, 1.6), (1.6, 0.4), 0.70)
    assert not tree.segment_free((0.4, 1.6), (1.6, 0.4), 0.71)
    assert tree.segment_free((0.4, 3), (0.4, 2), 0.89)  # the border at x = -0.5
    assert not tree.segment_free((0.4, 3), (0.4, 2), 0.9)

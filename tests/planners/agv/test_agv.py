"""AGV simulation: corners, navigation, the t-second check, scenarios, suite."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, NoPathError, ParameterError, UnreachableError
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.agv.scenarios import (
    PAPER_SCENARIOS,
    get_scenario,
    load_scenario,
    random_scenario,
    run_suite,
)
from subtask_opt.planners.agv.simulation import (
    AgvParams,
    AgvScenario,
    MovingObstacle,
    detect_corners,
    navigate,
    near_points,
    plan_route,
    simulate,
)
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.agv.test_quadtree import _crosses_obstacle


@pytest.fixture(scope="module")
def paper_runs():
    return {name: simulate(f()) for name, f in PAPER_SCENARIOS.items()}


# -- corners and navigation -------------------------------------------------------------
def test_rectangle_has_four_corners_and_four_near_points():
    occ = np.zeros((10, 10), dtype=bool)
    occ[3:6, 2:8] = True
    corners = detect_corners(occ)
    assert sorted(map(tuple, np.argwhere(corners))) == [(3, 2), (3, 7), (5, 2), (5, 7)]
    pts = near_points(occ)
    assert sorted(map(tuple, pts.astype(int))) == [(1, 2), (1, 6), (8, 2), (8, 6)]


def test_wall_ends_are_corners_and_diagonal_lines_are_not():
    occ = np.zeros((7, 7), dtype=bool)
    occ[1, 1:6] = True  # horizontal wall: two ends
    assert sorted(map(tuple, np.argwhere(detect_corners(occ)))) == [(1, 1), (1, 5)]
    diag = np.eye(7, dtype=bool)
    assert sorted(map(tuple, np.argwhere(detect_corners(diag)))) == [(0, 0), (6, 6)]


def test_goal_in_sight_is_reached_straight_else_via_near_points():
    occ = np.zeros((12, 12), dtype=bool)
    assert navigate(occ, (0, 0), (11, 11)).tolist() == [[11, 11]]
    occ[2:12, 5] = True
    sub = navigate(occ, (1, 10), (10, 10))
    pts = {tuple(p) for p in near_points(occ)}
    assert all(tuple(p) in pts for p in sub[:-1]) and sub[-1].tolist() == [10, 10]
    route = np.vstack([[1, 10], sub])
    assert not _crosses_obstacle(occ, route)


def test_navigation_raises_when_the_goal_is_enclosed():
    occ = np.zeros((8, 8), dtype=bool)
    occ[3:6, 3] = occ[3:6, 5] = occ[3, 3:6] = occ[5, 3:6] = True
    with pytest.raises(NoPathError):
        navigate(occ, (0, 0), (4, 4))


def test_prediction_kernel_matches_a_python_oracle():
    rng = np.random.default_rng(0)
    pts = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    cum = np.array([0.0, 3.0, 7.0])
    obs = rng.uniform(-2, 6, size=(3, 2))
    vel = rng.uniform(-1, 1, size=(3, 2))
    sep, j, k = K.predict_min_separation(pts, cum, 0.5, 1.0, 2.0, 0.25, 16, obs, vel)
    best = math.inf
    s, v = 0.0, 0.5
    for step in range(1, 17):
        v = min(v + 0.5, 1.0)
        s = min(s + v * 0.25, 7.0)
        p = np.array([s, 0.0]) if s <= 3 else np.array([3.0, s - 3.0])
        d = np.hypot(*(p - (obs + vel * step * 0.25)).T)
        if d.min() < best:
            best, bj, bk = d.min(), int(d.argmin()), step
    assert sep == pytest.approx(best) and (j, k) == (bj, bk)


def test_obstacle_positions_follow_path_and_start_time():
    ob = MovingObstacle([(0, 0), (4, 0), (4, 3)], speed=2.0, start_time=1.0)
    pos = ob.positions(np.array([0.0, 1.0, 2.0, 4.0, 10.0]))
    np.testing.assert_allclose(pos, [[0, 0], [0, 0], [2, 0], [4, 2], [4, 3]])


# -- the paper's experiments ------------------------------------------------------------
def test_paper_scenarios_succeed_without_collision(paper_runs):
    for name, run in paper_runs.items():
        assert run.success, name
        assert run.min_separation >= run.params.collision_distance or not run.events, name
        assert run.delay_s >= -1e-9, name
        assert not _crosses_obstacle(run.world.occupancy, run.trajectory), name


def test_paper_obstacles_move_in_free_space():
    for name, make in PAPER_SCENARIOS.items():
        sc = make()
        occ = np.array(sc.world.occupancy)
        for ob in sc.obstacles:
            for a, b in zip(ob.path[:-1], ob.path[1:], strict=True):
                assert K.segment_free(occ, a[0], a[1], b[0], b[1]), name


def test_experiment_1_moves_corner_to_corner(paper_runs):
    run = paper_runs["1"]
    assert "brake" not in run.kinds() and run.kinds().count("subgoal") >= 2
    pts = {tuple(p) for p in near_points(run.world.occupancy)}
    assert all(tuple(p) in pts for p in run.planned_route[1:-1])
    assert run.delay_s == 0.0


def test_experiment_2_1_yields_to_one_and_passes_the_other(paper_runs):
    run = paper_runs["2-1"]
    crossings = [e.detail for e in run.events if e.kind == "crossing"]
    assert crossings == ["obstacle 0: obstacle_first", "obstacle 1: agv_first"]
    kinds = run.kinds()
    assert kinds.index("brake") < kinds.index("speed_up")
    assert "obstacle 0" in run.first("brake").detail
    assert "obstacle 1" in run.first("speed_up").detail


def test_experiment_2_2_waits_then_replans_and_recovers(paper_runs):
    run = paper_runs["2-2"]
    kinds = run.kinds()
    for k in ("wait", "static", "replan", "recovery"):
        assert k in kinds, k
    assert kinds.index("wait") < kinds.index("static") <= kinds.index("replan") \
        < kinds.index("recovery")
    waited = run.first("static").time - run.first("wait").time
    assert waited == pytest.approx(run.params.static_after_s, abs=0.5)
    assert run.static_cells.any()
    # after recovery the AGV is back on a point of its planned route
    rec = run.first("recovery").detail.strip("()").split(",")
    rec_xy = np.array([float(v) for v in rec])
    seg = run.planned_route[-2:]
    d = seg[1] - seg[0]
    f = np.clip((rec_xy - seg[0]) @ d / (d @ d), 0, 1)
    assert np.hypot(*(seg[0] + f * d - rec_xy)) < 1.0


def test_experiment_2_3_passes_behind_and_recovers(paper_runs):
    run = paper_runs["2-3"]
    kinds = run.kinds()
    assert "obstacle 0: simultaneous" in [e.detail for e in run.events if e.kind == "crossing"]
    assert kinds.index("sidestep") < kinds.index("recovery")


def test_switching_the_check_off_collides_in_experiment_2_1():
    run = simulate(PAPER_SCENARIOS["2-1"]().with_params(collision_check=False))
    assert run.outcome == "collision"
    run = simulate(PAPER_SCENARIOS["2-3"]().with_params(collision_check=False))
    assert run.outcome == "collision" and run.kinds()[-1] == "collision"


# -- random suite and reproducibility ---------------------------------------------------
def test_random_suite_small_no_collisions_and_check_matters():
    on = run_suite(20, 100)
    assert on.collisions == 0 and on.success >= 19 and math.isfinite(on.mean_delay_s)
    off = run_suite(20, 100, params=AgvParams(collision_check=False))
    assert off.collisions > 0


def test_same_seed_same_run():
    a, b = random_scenario(42), random_scenario(42)
    np.testing.assert_array_equal(a.world.occupancy, b.world.occupancy)
    ra, rb = simulate(a), simulate(b)
    np.testing.assert_array_equal(ra.trajectory, rb.trajectory)
    assert ra.events == rb.events
    assert not np.array_equal(random_scenario(43).world.occupancy, a.world.occupancy)


def test_random_obstacles_cross_the_route():
    sc = random_scenario(5, n_obstacles=3)
    route = plan_route(sc.world, sc.start, sc.goal, sc.params)
    assert 1 <= len(sc.obstacles) <= 3
    for ob in sc.obstacles:
        a, b = ob.path[0], ob.path[-1]
        # the obstacle's segment intersects the route polyline
        hit = False
        for p, q in zip(route[:-1], route[1:], strict=True):
            m = np.array([b - a, p - q]).T
            if abs(np.linalg.det(m)) > 1e-12:
                t, s = np.linalg.solve(m, p - a)
                hit |= 0 <= t <= 1 and 0 <= s <= 1
        assert hit


# -- bad input ------------------------------------------------------------------------------
def test_bad_params_and_obstacles():
    with pytest.raises(ParameterError, match="dt"):
        AgvParams(dt=0)
    with pytest.raises(ParameterError, match="v_brake"):
        AgvParams(v_max=0.9)
    with pytest.raises(ParameterError, match="safety_distance"):
        AgvParams(safety_distance=0.5)
    with pytest.raises(ParameterError, match="collision_check"):
        AgvParams(collision_check=1)
    with pytest.raises(ParameterError, match="unknown AgvParams"):
        AgvParams.from_dict({"speed": 2})
    with pytest.raises(InputDataError, match="path"):
        MovingObstacle([])
    with pytest.raises(ParameterError, match="speed"):
        MovingObstacle([(0, 0)], speed=-1)
    with pytest.raises(ParameterError, match="start_time"):
        MovingObstacle([(0, 0)], start_time=float("nan"))


def test_blocked_or_outside_start_and_goal():
    occ = np.zeros((10, 10), dtype=bool)
    occ[5, 5] = True
    world = GridWorld(occ)
    with pytest.raises(UnreachableError, match="start"):
        AgvScenario("x", world, (5, 5), (0, 0))
    with pytest.raises(UnreachableError, match="goal"):
        AgvScenario("x", world, (0, 0), (10, 0))
    with pytest.raises(InputDataError, match="leaves"):
        AgvScenario("x", world, (0, 0), (9, 9), (MovingObstacle([(0, 0), (20, 0)]),))


def test_json_scenario_and_its_errors(tmp_path):
    good = {"name": "corridor", "map": ["..........", "....@@....", ".........."],
            "start": [0, 1], "goal": [9, 1],
            "obstacles": [{"path": [[5, 2], [5, 0]], "start_time": 3.0}],
            "params": {"sensor_range": 6.0}}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(good))
    sc = load_scenario(path)
    assert sc.params.sensor_range == 6.0 and len(sc.obstacles) == 1
    assert simulate(sc).outcome in ("success", "collision", "timeout")
    for bad, match in (({**good, "start": [4, 1]}, "start"),
                       ({**good, "image": "nope.png", "map": None}, "cannot read image"),
                       ({k: v for k, v in good.items() if k != "map"}, "'image' or a 'map'"),
                       ({**good, "image": "m.png", "density_factor": 500}, "density_factor")):
        if "map" in bad and bad["map"] is None:
            del bad["map"]
        path.write_text(json.dumps(bad))
        if bad.get("image") == "m.png":
            from PIL import Image

            Image.fromarray(np.full((20, 20), 255, dtype=np.uint8)).save(tmp_path / "m.png")
            del bad["map"]
            path.write_text(json.dumps(bad))
        with pytest.raises((InputDataError, ParameterError, UnreachableError), match=match):
            load_scenario(path)
    path.write_text("{not json")
    with pytest.raises(InputDataError, match="not valid JSON"):
        load_scenario(path)
    with pytest.raises(ParameterError, match="unknown scenario"):
        get_scenario("9-9")


def test_obstacle_parked_in_a_corridor_ends_in_timeout_not_collision():
    world = GridWorld.from_ascii("@@@@@@@@@@\n..........\n@@@@@@@@@@")
    sc = AgvScenario("corridor", world, (0, 1), (9, 1), (MovingObstacle([(6, 1)]),),
                     AgvParams(max_time_s=30.0))
    run = simulate(sc)
    assert run.outcome == "timeout" and "blocked" in run.kinds()
    assert run.min_separation >= sc.params.collision_distance
    assert math.isnan(run.delay_s)


def test_json_start_must_be_a_cell(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"map": ["...."], "start": 3, "goal": [3, 0]}))
    with pytest.raises(UnreachableError, match="start"):
        load_scenario(path)
    path.write_text(json.dumps({"map": ["...."], "start": [0, 0], "goal": [3, 0],
                                "params": [1]}))
    with pytest.raises(InputDataError, match="mapping"):
        load_scenario(path)

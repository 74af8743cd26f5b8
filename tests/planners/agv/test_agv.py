"""AGV simulation: the planner protocol, the paper's experiments, crossing
rules, drift and check points, the suite, and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.agv.navigation import near_points
from subtask_opt.planners.agv.scenarios import (
    PAPER_SCENARIOS,
    random_agv_scenario,
    run_agv_suite,
)
from subtask_opt.planners.agv.simulation import (
    MAX_RUN_BYTES,
    AgvParams,
    AgvScenario,
    MovingObstacle,
    plan,
    plan_route,
    run_size,
    simulate,
)
from subtask_opt.planners.base import get_planner, planners
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.agv.test_quadtree import _crosses_obstacle


@pytest.fixture(scope="module")
def paper_runs():
    return {name: simulate(f()) for name, f in PAPER_SCENARIOS.items()}


# -- planner protocol -------------------------------------------------------------------
def test_agv_planners_are_registered():
    found = planners("agv")
    assert {"agv", "quadtree"} <= set(found)
    assert found["agv"].plan is plan
    assert get_planner("agv", "agv").stochastic


def test_plan_on_a_grid_world_reaches_the_goal():
    occ = np.zeros((12, 12), dtype=bool)
    occ[2:12, 5] = True
    res = plan(GridWorld(occ), (1, 10), (10, 10))
    assert isinstance(res, PlanResult) and res.success and res.outcome == Outcome.SUCCESS
    assert res.path[0].tolist() == [1, 10] and res.path[-1].tolist() == [10, 10]
    assert not _crosses_obstacle(occ, res.path)
    # over the wall top: at least the two straight pieces start -> (5, 1) corner -> goal
    assert res.length >= math.hypot(4, 9) * 2 - 1e-6
    assert res.to_dict()["info"]["events"][-1]["kind"] == "goal"


def test_plan_reports_no_path_as_an_outcome():
    occ = np.zeros((8, 8), dtype=bool)
    occ[:, 4] = True
    res = plan(GridWorld(occ), (0, 0), (7, 7))
    assert not res.success and res.outcome == Outcome.NO_PATH
    assert "no_path" in res.message and res.path.shape == (0, 2)


def test_plan_checks_seed_and_stop():
    world = GridWorld(np.zeros((4, 4), dtype=bool))
    for bad in (-1, 2**63, 1.5, "3", True):
        with pytest.raises(ParameterError, match="seed"):
            plan(world, (0, 0), (3, 3), seed=bad)
    with pytest.raises(ParameterError, match="stop"):
        plan(world, (0, 0), (3, 3), stop=10)
    with pytest.raises(ParameterError, match="AgvParams"):
        plan(world, (0, 0), (3, 3), params={"dt": 0.1})


def test_plan_on_a_scenario_collides_without_the_check():
    sc = PAPER_SCENARIOS["2-3"]().with_params(collision_check=False)
    res = plan(sc, sc.start, sc.goal)
    assert res.outcome == Outcome.COLLISION and not res.success
    assert "collision" in res.message


# -- routing on the paper's structures --------------------------------------------------
def test_route_avoids_mixed_cells():
    # a free corridor with a mixed (01) cell in the straight line: the route bends round it
    occ = np.zeros((5, 9), dtype=bool)
    states = np.zeros((5, 9), dtype=np.uint8)
    states[2, 4] = 1  # mixed
    world = GridWorld(occ)
    route = plan_route(world, (0, 2), (8, 2), states=states)
    straight = plan_route(world, (0, 2), (8, 2))
    assert straight.tolist() == [[0, 2], [8, 2]]
    assert len(route) > 2
    mixed = states != 0
    assert not _crosses_obstacle(mixed, route)


def test_start_on_a_mixed_cell_is_refused():
    states = np.zeros((3, 3), dtype=np.uint8)
    states[0, 0] = 1
    with pytest.raises(UnreachableError, match="mixed"):
        AgvScenario("x", GridWorld(np.zeros((3, 3), dtype=bool)), (0, 0), (2, 2),
                    states=states)
    states[0, 0] = 2  # says blocked, the world says free
    with pytest.raises(InputDataError, match="disagree"):
        AgvScenario("x", GridWorld(np.zeros((3, 3), dtype=bool)), (1, 1), (2, 2),
                    states=states)


def test_paper_maps_have_mixed_cells_only_in_experiment_1():
    sc = PAPER_SCENARIOS["1"]()
    assert np.any(sc.states == 1)
    run = simulate(sc)
    assert not _crosses_obstacle(sc.states != 0, run.trajectory)


def test_prediction_kernel_matches_a_python_oracle():
    """The look-ahead's least separation over the continuous motion from the
    first step on: an oracle samples every step 2,000 times."""
    rng = np.random.default_rng(0)
    pts = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    cum = np.array([0.0, 3.0, 7.0])

    def agv_at(s):
        return np.array([s, 0.0]) if s <= 3 else np.array([3.0, s - 3.0])

    for _ in range(20):
        obs = rng.uniform(-2, 6, size=(3, 2))
        vel = rng.uniform(-2, 2, size=(3, 2))
        sep, j, k = K.predict_min_separation(pts, cum, K.Motion(0.5, 1.0, 2.0, 0.25, 16),
                                             obs, vel)
        best, bj, bk = math.inf, -1, -1
        s, v = 0.0, 0.5
        for step in range(1, 17):
            v = min(v + 0.5, 1.0)
            s_new = min(s + v * 0.25, 7.0)
            # the AGV moves straight from its last step point to this one (a chord)
            a, b = agv_at(s), agv_at(s_new)
            f = np.linspace(0.0, 1.0, 2001) if step > 1 else np.ones(1)
            t = (step - 1 + f) * 0.25
            p = a + f[:, None] * (b - a)
            for jj in range(3):
                d = np.hypot(*(p - (obs[jj] + vel[jj] * t[:, None])).T).min()
                if d < best:
                    best, bj, bk = d, jj, step
            s = s_new
        assert sep == pytest.approx(best, abs=1e-5) and (j, k) == (bj, bk)


def test_obstacle_positions_follow_path_and_start_time():
    ob = MovingObstacle([(0, 0), (4, 0), (4, 3)], speed=2.0, start_time=1.0)
    pos = ob.positions(np.array([0.0, 1.0, 2.0, 4.0, 10.0]))
    np.testing.assert_allclose(pos, [[0, 0], [0, 0], [2, 0], [4, 2], [4, 3]])


# -- the paper's experiments ------------------------------------------------------------
def test_paper_scenarios_succeed_without_collision(paper_runs):
    for name, run in paper_runs.items():
        assert run.outcome == Outcome.SUCCESS, name
        d = run.obstacle_positions - run.trajectory[None]
        if len(d):
            assert np.hypot(d[..., 0], d[..., 1]).min() >= run.params.collision_distance, name
        assert run.delay_s >= 0.0, name
        assert not _crosses_obstacle(run.world.occupancy, run.trajectory), name


def test_paper_obstacles_move_in_free_space():
    for name, make in PAPER_SCENARIOS.items():
        sc = make()
        for ob in sc.obstacles:
            assert not _crosses_obstacle(sc.world.occupancy, ob.path), name


def test_experiment_1_moves_corner_to_corner(paper_runs):
    run = paper_runs["1"]
    assert "brake" not in run.kinds() and run.kinds().count("subgoal") >= 2
    pts = {tuple(p) for p in near_points(PAPER_SCENARIOS["1"]().routing_map)}
    assert all(tuple(p) in pts for p in run.planned_route[1:-1])
    assert run.delay_s == 0.0


def test_experiment_2_1_obstacles_move_at_one_unit_per_second():
    sc = PAPER_SCENARIOS["2-1"]()
    for ob in sc.obstacles:
        p = ob.positions(np.array([ob.start_time + 1.0, ob.start_time + 2.0]))
        assert np.hypot(*(p[1] - p[0])) == pytest.approx(1.0)


def test_experiment_2_1_yields_to_one_and_keeps_speed_ahead_of_the_other(paper_runs):
    run = paper_runs["2-1"]
    crossings = [e.detail for e in run.events if e.kind == "crossing"]
    assert crossings == ["obstacle 0: obstacle_first", "obstacle 1: agv_first"]
    assert "obstacle 0" in run.first("brake").detail
    assert "speed_up" not in run.kinds()
    # rule 5-2-1: from the crossing with obstacle 1 on, the normal speed is kept
    t1 = next(e.time for e in run.events if e.detail == "obstacle 1: agv_first")
    after = run.speeds[run.times >= t1 + 1.0]
    np.testing.assert_allclose(after[:-1], run.params.v_nominal)
    assert run.speeds.max() <= run.params.v_nominal + 1e-12


def test_speed_up_to_pass_is_an_option():
    run = simulate(PAPER_SCENARIOS["2-1"]().with_params(speed_up_to_pass=True))
    assert "obstacle 1" in run.first("speed_up").detail
    assert run.speeds.max() == pytest.approx(run.params.v_max)


def test_experiment_2_2_obstacle_crosses_left_to_right_then_blocks(paper_runs):
    run = paper_runs["2-2"]
    sc = PAPER_SCENARIOS["2-2"]()
    ob = sc.obstacles[0]
    crossing = run.first("crossing")
    assert crossing.detail == "obstacle 0: obstacle_first"
    # the obstacle is moving when the AGV sees the crossing ...
    k = int(np.searchsorted(run.times, crossing.time))
    step = run.obstacle_positions[0, k + 1] - run.obstacle_positions[0, k]
    assert np.hypot(*step) > 0
    # ... from the AGV's left to its right: the AGV heads +x, its left is -y (y down)
    heading = run.trajectory[k + 1] - run.trajectory[k]
    cross = heading[0] * step[1] - heading[1] * step[0]
    assert heading[0] > 0 and cross > 0
    # it ends past the route line (it crossed it), next to the route
    a, b = sc.obstacles[0].path[0], ob.path[-1]
    route = run.planned_route
    seg = route[-2:]
    d = seg[1] - seg[0]
    side = [d[0] * (q[1] - seg[0][1]) - d[1] * (q[0] - seg[0][0]) for q in (a, b)]
    assert side[0] * side[1] < 0
    kinds = run.kinds()
    for kind in ("wait", "static", "replan", "recovery"):
        assert kind in kinds, kind
    assert kinds.index("crossing") < kinds.index("wait") < kinds.index("static") \
        <= kinds.index("replan") < kinds.index("recovery")
    waited = run.first("static").time - run.first("wait").time
    assert waited == pytest.approx(run.params.static_after_s, abs=0.5)
    assert run.static_cells.any()


def test_experiment_2_3_passes_behind_and_recovers(paper_runs):
    run = paper_runs["2-3"]
    kinds = run.kinds()
    assert "obstacle 0: simultaneous" in [e.detail for e in run.events if e.kind == "crossing"]
    assert kinds.index("sidestep") < kinds.index("recovery")
    # the quadtree check of the leg after the sidestep finds the obstacle in its leaves
    assert any(e.kind == "section" and "obstacle(s) [0]" in e.detail for e in run.events)


def test_switching_the_check_off_collides_in_experiment_2_3():
    run = simulate(PAPER_SCENARIOS["2-3"]().with_params(collision_check=False))
    assert run.outcome == Outcome.COLLISION and run.kinds()[-1] == "collision"


# -- drift and check points -------------------------------------------------------------
def test_no_drift_means_true_equals_believed(paper_runs):
    for run in paper_runs.values():
        np.testing.assert_array_equal(run.trajectory, run.believed)
        assert "check_point" not in run.kinds()


def test_check_points_reduce_the_drift_error():
    sc = PAPER_SCENARIOS["1"]().with_params(drift=True, drift_heading_sd_deg=3.0)
    with_cp, without = [], []
    for seed in range(6):
        with_cp.append(simulate(sc, seed=seed).mean_drift_error)
        without.append(simulate(sc.with_params(check_points=False), seed=seed)
                       .mean_drift_error)
    assert np.mean(with_cp) < np.mean(without)
    run = simulate(sc, seed=0)
    assert "check_point" in run.kinds()


def test_eq3_fix_is_exact_without_heading_error():
    # drift only in scale: the believed heading is right, so a fix by eq. (3)
    # lands within the pixel quantisation of the image column
    sc = PAPER_SCENARIOS["1"]().with_params(drift=True, drift_heading_sd_deg=0.0,
                                            drift_walk_deg=0.0, drift_scale_sd=0.05)
    run = simulate(sc, seed=3)
    fixes = [i for i, e in enumerate(run.events) if e.kind == "check_point"]
    assert fixes
    for i in fixes:
        k = int(np.searchsorted(run.times, run.events[i].time)) + 1
        if k < len(run.times):
            # one step after a fix the error is what one step of scale error adds
            assert run.drift_error[k] <= 0.05 * run.params.dt * run.params.v_max + 0.02


def test_after_a_check_point_the_agv_returns_to_its_planned_leg():
    sc = PAPER_SCENARIOS["1"]().with_params(drift=True)
    for seed in range(4):
        run = simulate(sc, seed=seed)
        route = run.planned_route
        fixes = [e.time for e in run.events if e.kind == "check_point"]
        assert fixes
        returned = 0
        for t in fixes:
            k = int(np.searchsorted(run.times, t - 1e-9))
            window = run.believed[k:k + int(round((sc.params.track_lookahead + 1.0)
                                                  / sc.params.dt)) + 1]
            off = [min(_point_segment_distance(q, a, b) for a, b in zip(route[:-1], route[1:],
                                                                        strict=True))
                   for q in window]
            returned += min(off) < 1e-6
        assert returned == len(fixes), seed


def _point_segment_distance(q, a, b):
    d = b - a
    f = min(1.0, max(0.0, float((q - a) @ d) / float(d @ d)))
    return float(np.hypot(*(a + f * d - q)))


def test_two_corners_give_the_pose_without_the_heading():
    from subtask_opt.planners.agv.simulation import _two_corner_fix

    rng = np.random.default_rng(11)
    for _ in range(200):
        pos = rng.uniform(0, 20, 2)
        heading = rng.uniform(-math.pi, math.pi)
        marks = pos + rng.uniform(-8, 8, size=(3, 2))
        rel = marks - pos
        th = np.array([math.remainder(math.atan2(r[1], r[0]) - heading, math.tau)
                       for r in rel])
        seen = [(i, float(th[i]), float(np.hypot(*rel[i]))) for i in range(3)]
        fix = _two_corner_fix(marks, seen, 1e-3)
        pairs = [abs(math.sin(th[b] - th[a])) for a in range(3) for b in range(a + 1, 3)]
        if max(pairs) < math.sin(math.radians(20)):
            assert fix is None
            continue
        est, h, _, err, _ = fix
        np.testing.assert_allclose(est, pos, atol=1e-7)
        assert math.remainder(h - heading, math.tau) == pytest.approx(0.0, abs=1e-7)
        assert err > 0


def test_drift_is_seeded():
    sc = PAPER_SCENARIOS["1"]().with_params(drift=True)
    a, b = simulate(sc, seed=7), simulate(sc, seed=7)
    np.testing.assert_array_equal(a.trajectory, b.trajectory)
    c = simulate(sc, seed=8)
    assert not np.array_equal(a.trajectory, c.trajectory)


# -- random suite and reproducibility ---------------------------------------------------
def test_random_suite_small_and_the_check_matters():
    on = run_agv_suite(12, 100, params=AgvParams())
    off = run_agv_suite(12, 100, params=AgvParams(collision_check=False))
    assert on.collisions < off.collisions
    assert on.runs == 12 and len(on.outcomes) == 12 and not on.drift


def test_suite_reports_drift_with_and_without_check_points():
    rep = run_agv_suite(4, 0)
    assert rep.drift and len(rep.drift_errors) == len(rep.drift_errors_no_check) == 4
    assert rep.mean_drift_error == pytest.approx(np.mean(rep.drift_errors))


def test_same_seed_same_run():
    a, b = random_agv_scenario(42), random_agv_scenario(42)
    np.testing.assert_array_equal(a.world.occupancy, b.world.occupancy)
    ra, rb = simulate(a, seed=1), simulate(b, seed=1)
    np.testing.assert_array_equal(ra.trajectory, rb.trajectory)
    assert ra.events == rb.events
    assert not np.array_equal(random_agv_scenario(43).world.occupancy, a.world.occupancy)


def test_random_obstacles_cross_the_route():
    sc = random_agv_scenario(5, n_obstacles=3)
    route = plan_route(sc.world, sc.start, sc.goal, sc.params, states=sc.states)
    assert 1 <= len(sc.obstacles) <= 3
    for ob in sc.obstacles:
        a, b = ob.path[0], ob.path[-1]
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
    with pytest.raises(ParameterError, match="dt"):
        AgvParams(dt="0.25")
    with pytest.raises(ParameterError, match="v_brake"):
        AgvParams(v_max=0.9)
    with pytest.raises(ParameterError, match="safety_distance"):
        AgvParams(safety_distance=0.5)
    with pytest.raises(ParameterError, match="collision_check"):
        AgvParams(collision_check=1)
    with pytest.raises(ParameterError, match="horizon_s"):
        AgvParams(horizon_s=float("nan"))
    with pytest.raises(ParameterError, match="sonar_min_m"):
        AgvParams(sonar_min_m=3.0)
    with pytest.raises(ParameterError, match="pass_distance"):
        AgvParams(pass_distance=0.5)
    with pytest.raises(ParameterError, match="pass_distance"):
        AgvParams(pass_distance=2.0)
    for name in ("wall_clearance", "back_off", "track_lookahead"):
        with pytest.raises(ParameterError, match=name):
            AgvParams(**{name: -0.1})
    with pytest.raises(ParameterError, match="unknown AgvParams"):
        AgvParams.from_dict({"speed": 2})
    with pytest.raises(InputDataError, match="path"):
        MovingObstacle([])
    with pytest.raises(ParameterError, match="speed"):
        MovingObstacle([(0, 0)], speed=-1)
    with pytest.raises(ParameterError, match="start_time"):
        MovingObstacle([(0, 0)], start_time=float("nan"))


def test_tiny_dt_or_huge_max_time_is_refused_before_allocating():
    with pytest.raises(ParameterError, match="steps"):
        AgvParams(dt=1e-9)
    with pytest.raises(ParameterError, match="steps"):
        AgvParams(max_time_s=1e12)
    # within the step limit, but many obstacles: the byte estimate refuses
    p = AgvParams(dt=0.001, horizon_s=1.0, max_time_s=1999.0)
    steps, size = run_size(p, 100)
    assert size > MAX_RUN_BYTES and steps == 1_999_001
    world = GridWorld(np.zeros((5, 5), dtype=bool))
    obstacles = tuple(MovingObstacle([(4, 4)]) for _ in range(100))
    with pytest.raises(ParameterError, match="GiB"):
        AgvScenario("big", world, (0, 0), (1, 1), obstacles, p)


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


def test_obstacle_parked_in_a_corridor_ends_in_timeout_not_collision():
    world = GridWorld.from_ascii("@@@@@@@@@@\n..........\n@@@@@@@@@@")
    sc = AgvScenario("corridor", world, (0, 1), (9, 1), (MovingObstacle([(6, 1)]),),
                     AgvParams(max_time_s=30.0))
    run = simulate(sc)
    assert run.outcome == Outcome.TIMEOUT and "blocked" in run.kinds()
    assert run.min_separation >= sc.params.collision_distance
    assert math.isnan(run.delay_s)


def test_a_pass_between_two_samples_is_a_collision():
    """A fast obstacle crosses the AGV half-way through a step: at both samples
    it is a cell away, in between it runs through the AGV."""
    world = GridWorld(np.zeros((21, 30), dtype=bool))
    params = AgvParams(collision_check=False, max_time_s=40.0)
    free = simulate(AgvScenario("free", world, (1, 10), (28, 10), params=params))
    k = int(np.searchsorted(free.times, 8.0))
    x_mid = float(free.trajectory[k:k + 2, 0].mean())
    t_mid = float(free.times[k:k + 2].mean())
    ob = MovingObstacle([(x_mid, 0), (x_mid, 20)], speed=8.0, start_time=t_mid - 10 / 8)
    sc = AgvScenario("fast", world, (1, 10), (28, 10), (ob,), params)
    at_samples = np.hypot(*(ob.positions(free.times[k:k + 2]) - free.trajectory[k:k + 2]).T)
    assert at_samples.min() > params.collision_distance
    run = simulate(sc)
    assert run.outcome == Outcome.COLLISION and run.time_s == pytest.approx(free.times[k + 1])
    assert run.min_separation < 0.05


def test_backing_off_from_an_obstacle_that_comes_at_the_waiting_agv():
    """The AGV waits behind an obstacle parked on its route; a second one
    drives at the spot where it waits. Braking, stopping or speeding up cannot
    avoid it; backing off along the way it came does."""
    world = GridWorld(np.zeros((21, 30), dtype=bool))
    parked = MovingObstacle([(12, 10)])
    alone = simulate(AgvScenario("parked", world, (1, 10), (28, 10), (parked,),
                                 AgvParams(max_time_s=60.0)))
    k = int(np.flatnonzero(alone.speeds[1:] == 0)[0]) + 1
    x_wait = float(alone.trajectory[k, 0])
    # reaches the waiting spot 10 s after it starts, while the AGV still waits
    comes = MovingObstacle([(x_wait, 0), (x_wait, 20)], start_time=float(alone.times[k]) - 3.0)
    runs = {}
    for back_off in (0.0, 2.0):
        sc = AgvScenario("trap", world, (1, 10), (28, 10), (parked, comes),
                         AgvParams(back_off=back_off, max_time_s=120.0))
        runs[back_off] = simulate(sc)
    assert runs[0.0].outcome == Outcome.COLLISION
    assert runs[2.0].outcome == Outcome.SUCCESS and "back_off" in runs[2.0].kinds()
    d = runs[2.0].obstacle_positions - runs[2.0].trajectory[None]
    assert np.hypot(d[..., 0], d[..., 1]).min() >= runs[2.0].params.collision_distance


def test_obstacle_parking_on_the_goal_is_a_timeout_not_an_input_error():
    world = GridWorld(np.zeros((9, 12), dtype=bool))
    # crosses the AGV's line, then parks on the goal
    ob = MovingObstacle([(9, 0), (9, 4)], start_time=2.0)
    sc = AgvScenario("parked", world, (1, 4), (9, 4), (ob,), AgvParams(max_time_s=40.0))
    run = simulate(sc)
    assert run.outcome == Outcome.TIMEOUT
    blocked = [e.detail for e in run.events if e.kind == "blocked"]
    assert blocked and "goal" in blocked[0]
    assert run.min_separation >= sc.params.collision_distance

"""Closed-loop runs: the paper's scenarios, the U-trap acceptance, a small random suite,
run records, reproducibility, end conditions, bad inputs and the figures."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.planners.polygon.world import PolygonWorld
from subtask_opt.planners.reactive.baselines import VFFNavigator, VFFParams, VFHNavigator, VFHParams
from subtask_opt.planners.reactive.fuzzy import NavDecision
from subtask_opt.planners.reactive.scenarios import (
    PAPER_SCENARIOS,
    RandomSuiteParams,
    paper_scenario,
    random_scenario,
    random_suite,
    resolve_world,
)
from subtask_opt.planners.reactive.simulation import (
    SimParams,
    benchmark,
    plan,
    run_suite,
    simulate,
    suite_summary,
)
from subtask_opt.planners.reactive.sonar import SonarRing
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc


def _run(name: str, navigator: str, **kw):
    sc = paper_scenario(name)
    return sc, simulate(sc.world, sc.start, sc.goal, navigator, **kw)


@pytest.mark.parametrize("name", PAPER_SCENARIOS)
def test_fuzzy_reaches_the_goal_in_the_paper_scenarios(name):
    sc, run = _run(name, "fuzzy")
    assert run.outcome == "success", run.summary()
    assert np.hypot(*(run.poses[-1, :2] - sc.goal)) <= run.goal_tolerance
    assert run.min_clearance > 0


def test_u_trap_needs_the_escape():
    _, trapped = _run("u-trap", "fuzzy-no-escape")
    assert trapped.outcome in ("stall", "timeout"), trapped.summary()
    # it never got past the bottom of the U (y = 7.1 inside, the goal is at y = 10)
    assert trapped.poses[:, 1].max() < 7.1
    _, escaped = _run("u-trap", "fuzzy")
    assert escaped.outcome == "success", escaped.summary()
    assert np.any(escaped.escaping)


def test_run_record_is_consistent():
    sc, run = _run("simple", "fuzzy")
    robot = Unicycle()
    # every pose follows from the previous one and the recorded command
    for i in range(run.steps):
        v, om = run.commands[i]
        np.testing.assert_allclose(run.poses[i + 1], integrate_arc(run.poses[i], v, om, robot.dt),
                                   atol=1e-12)
    assert run.commands[:, 0].max() <= robot.max_speed + 1e-12
    assert np.abs(run.commands[:, 1]).max() <= robot.max_turn_rate + 1e-12
    assert run.scans.shape == (run.steps + 1, 18)
    assert run.mu.shape == (run.steps, 4)
    np.testing.assert_allclose(run.mu[:, 3], run.mu[:, :3].min(axis=1))
    assert math.isclose(run.path_length,
                        float(np.sum(np.hypot(*np.diff(run.poses[:, :2], axis=0).T))))
    assert run.time == run.steps * robot.dt
    # the recorded clearance is a lower bound of the clearance at every pose
    clear = min(sc.world.distance_to_obstacles(p[:2]) for p in run.poses) - robot.radius
    assert run.min_clearance <= clear + 1e-12
    res = run.to_plan_result()
    assert res.success and res.path.shape == (run.steps + 1, 2)
    d = run.to_dict()
    assert d["outcome"] == "success" and len(d["poses"]) == run.steps + 1


def test_same_seed_same_run_with_noisy_sonar():
    sonar = SonarRing(noise_std=0.03)
    _, a = _run("corridor", "fuzzy", sonar=sonar, seed=5)
    _, b = _run("corridor", "fuzzy", sonar=sonar, seed=5)
    _, c = _run("corridor", "fuzzy", sonar=sonar, seed=6)
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.scans, b.scans)
    assert a.poses.shape != c.poses.shape or not np.array_equal(a.poses, c.poses)


def test_small_random_suite_fuzzy_succeeds_without_collisions():
    scenarios = random_suite(12, seed=11)
    runs = run_suite(scenarios, ["fuzzy", "vfh"], seed=11)
    table = suite_summary(runs)
    assert table["fuzzy"]["collisions"] == 0
    assert table["fuzzy"]["success"] >= 11
    assert table["vfh"]["runs"] == 12


def test_benchmark_table_has_the_requested_columns():
    table = benchmark(2, 3, navigators=["fuzzy", "vff"])
    for row in table.values():
        assert {"runs", "success", "collisions", "timeouts", "mean_path_ratio",
                "mean_min_clearance"} <= set(row)
        assert row["runs"] == 2
    assert table["fuzzy"]["mean_path_ratio"] >= 1.0


class _Straight:
    """A navigator that ignores its sensors and drives straight ahead."""

    name = "straight"

    def reset(self) -> None: ...

    def decide(self, pose, ranges, goal) -> NavDecision:
        return NavDecision(v=10.0, omega=0.0)


class _Still:
    name = "still"

    def reset(self) -> None: ...

    def decide(self, pose, ranges, goal) -> NavDecision:
        return NavDecision(v=0.0, omega=0.0)


def test_collision_stall_and_timeout_end_the_run():
    sc = paper_scenario("u-trap")
    hit = simulate(sc.world, sc.start, sc.goal, _Straight())
    assert hit.outcome == "collision"
    assert hit.min_clearance < 0
    # the straight line from (5, 1) meets the U's bottom at y = 7.1 - radius
    assert 7.1 - 0.2 - 0.3 < hit.poses[-1, 1] < 7.1
    stuck = simulate(sc.world, sc.start, sc.goal, _Still(), params=SimParams(stall_steps=5))
    assert stuck.outcome == "stall" and stuck.steps == 5
    short = simulate(sc.world, sc.start, sc.goal, "fuzzy", params=SimParams(max_steps=7))
    assert short.outcome == "timeout" and short.steps == 7


def test_plan_entry_point_returns_a_plan_result():
    sc = paper_scenario("simple")
    res = plan(sc.world, sc.start, sc.goal, navigator="vfh")
    assert res.planner == "vfh" and res.path.shape[1] == 2
    assert res.info["outcome"] in ("success", "collision", "stall", "timeout")


@pytest.mark.parametrize("start, goal, exc, words", [
    ((3.2, 6.0, 0.0), (5.0, 10.0), UnreachableError, "start"),        # inside the U's wall
    ((5.0, 7.3, 0.0), (5.0, 10.0), UnreachableError, "start"),        # body overlaps the wall
    ((5.0, 0.1, 0.0), (5.0, 10.0), UnreachableError, "start"),        # body crosses the boundary
    ((5.0, 1.0, 0.0), (5.0, 12.0), UnreachableError, "goal"),         # outside the world
    ((5.0, 1.0, 0.0), (6.8, 6.0), UnreachableError, "goal"),          # inside an obstacle
    ((5.0, 1.0), (5.0, 10.0), InputDataError, "start"),
    ((5.0, 1.0, float("nan")), (5.0, 10.0), InputDataError, "start"),
])
def test_bad_start_and_goal_raise(start, goal, exc, words):
    sc = paper_scenario("u-trap")
    with pytest.raises(exc, match=words):
        simulate(sc.world, start, goal)


def test_bad_navigator_and_sim_parameters_raise():
    sc = paper_scenario("simple")
    with pytest.raises(ParameterError, match="navigator"):
        simulate(sc.world, sc.start, sc.goal, "bug2")
    with pytest.raises(ParameterError, match="goal_tolerance"):
        SimParams(goal_tolerance=0.0)
    with pytest.raises(ParameterError, match="max_steps"):
        SimParams(max_steps=0)


# ------------------------------------------------------------------ scenarios

def _polygon_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between two disjoint polygons: min over vertex-edge pairs (brute force)."""
    def point_seg(p, q, r):
        d = r - q
        t = np.clip(np.dot(p - q, d) / np.dot(d, d), 0.0, 1.0)
        return float(np.hypot(*(p - q - t * d)))

    best = math.inf
    for p, q in ((a, b), (b, a)):
        for v in p:
            for i in range(len(q)):
                best = min(best, point_seg(v, q[i], q[(i + 1) % len(q)]))
    return best


def test_random_scenarios_keep_the_promised_gaps():
    params = RandomSuiteParams()
    for seed in (0, 1, 2):
        sc = random_scenario(seed, params)
        w = sc.world
        assert len(w.obstacles) >= 1
        for a, b in combinations(w.obstacles, 2):
            assert _polygon_distance(a, b) >= params.gap - 1e-9
        for poly in w.obstacles:
            x0, y0, x1, y1 = w.bounds
            assert poly[:, 0].min() - x0 >= params.gap and x1 - poly[:, 0].max() >= params.gap
            assert poly[:, 1].min() - y0 >= params.gap and y1 - poly[:, 1].max() >= params.gap
        assert w.distance_to_obstacles(sc.start[:2]) > 0.5
        assert w.distance_to_obstacles(sc.goal) > 0.5
    assert random_scenario(7).world == random_scenario(7).world
    assert random_suite(3, 1)[2].world == random_suite(5, 1)[2].world


def test_resolve_world_names_and_files(tmp_path):
    world, sc = resolve_world("u-trap")
    assert sc is not None and world.name == "u-trap"
    path = tmp_path / "w.json"
    world.to_json(path)
    again, none = resolve_world(str(path))
    assert none is None and again.obstacles[0].shape == world.obstacles[0].shape
    with pytest.raises(InputDataError, match="unknown world"):
        resolve_world("nowhere")
    with pytest.raises(ParameterError, match="max_radius"):
        RandomSuiteParams(min_radius=1.0, max_radius=0.5)


# ------------------------------------------------------------------ figures

def test_figures_and_gif(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from subtask_opt.plotting.reactive import animate_run, plot_memberships, plot_run

    sc = paper_scenario("u-trap")
    run = simulate(sc.world, sc.start, sc.goal, "fuzzy", params=SimParams(max_steps=12))
    fig = plot_run(sc.world, run)
    fig.savefig(tmp_path / "run.png")
    fig2 = plot_memberships(run)
    fig2.savefig(tmp_path / "mu.png")
    out = animate_run(sc.world, run, tmp_path / "run.gif", every=4)
    from PIL import Image

    with Image.open(out) as im:
        assert im.format == "GIF" and im.n_frames == 4
    assert (tmp_path / "run.png").stat().st_size > 0
    assert isinstance(PolygonWorld, type)


# ------------------------------------------------------------------ invariants and baselines

@settings(max_examples=8, deadline=None)
@given(x=st.floats(0.5, 9.5), y=st.floats(0.5, 9.5), th=st.floats(-math.pi, math.pi),
       gx=st.floats(0.5, 9.5), gy=st.floats(0.5, 9.5))
def test_fuzzy_never_collides(x, y, th, gx, gy):
    world = paper_scenario("simple").world
    if (not world.is_free((x, y)) or world.distance_to_obstacles((x, y)) < 0.3
            or not world.is_free((gx, gy))):
        return
    run = simulate(world, (x, y, th), (gx, gy), "fuzzy", params=SimParams(max_steps=120))
    assert run.outcome != "collision", run.summary()
    assert run.min_clearance > 0


def test_vfh_blocks_the_directions_an_enlarged_echo_subtends():
    robot, sonar = Unicycle(), SonarRing()
    nav = VFHNavigator(robot, sonar, VFHParams(threshold_distance=1.0, safety_margin=0.08))
    assert nav.free_directions(np.full(18, 2.5)).all()
    ranges = np.full(18, 2.5)
    ranges[9] = 0.5                                   # one echo at +5 degrees
    free = nav.free_directions(ranges)
    half = math.asin(0.28 / 0.5) + 0.5 * sonar.spacing
    expected = np.abs(sonar.angles - sonar.angles[9]) > half
    np.testing.assert_array_equal(free, expected)
    # the goal straight ahead is blocked: steer to the nearest free direction
    d = nav.decide(np.zeros(3), ranges, np.array([5.0, 0.0]))
    assert d.omega != 0.0
    # goal behind: turn in place toward it
    d = nav.decide(np.zeros(3), np.full(18, 2.5), np.array([-5.0, 0.1]))
    assert d.v == 0.0 and d.omega == robot.max_turn_rate


def test_vff_follows_the_resultant_force():
    robot, sonar = Unicycle(), SonarRing()
    nav = VFFNavigator(robot, sonar, VFFParams())
    d = nav.decide(np.zeros(3), np.full(18, 2.5), np.array([5.0, 0.0]))
    assert d.v == robot.max_speed and d.omega == 0.0
    ranges = np.full(18, 2.5)
    ranges[6:9] = 0.4                                   # echoes ahead on the right
    d = nav.decide(np.zeros(3), ranges, np.array([5.0, 0.0]))
    assert d.omega > 0                                  # pushed to the left
    with pytest.raises(ParameterError, match="attraction"):
        VFFParams(attraction=0.0)
    with pytest.raises(ParameterError, match="threshold_distance"):
        VFHParams(threshold_distance=-1.0)

"""Closed-loop runs: the paper's scenarios, the U-trap acceptance, a small random suite,
run records, reproducibility, end conditions, bad inputs and the figures."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.base import get_planner, planners
from subtask_opt.planners.polygon.world import PolygonWorld
from subtask_opt.planners.reactive.baselines import (
    SonarVFFParams,
    SonarVFHParams,
    VFFNavigator,
    VFHNavigator,
)
from subtask_opt.planners.reactive.fuzzy import NavDecision
from subtask_opt.planners.reactive.scenarios import (
    PAPER_SCENARIOS,
    RandomSuiteParams,
    paper_scenario,
    random_navigation_scenario,
    random_navigation_suite,
    resolve_world,
)
from subtask_opt.planners.reactive.simulation import (
    MEMORY_LIMIT,
    NAVIGATORS,
    ReactiveParams,
    SimParams,
    benchmark_navigators,
    navigation_suite_summary,
    plan,
    run_navigation_suite,
    simulate,
)
from subtask_opt.planners.reactive.sonar import MAX_BEAMS, SonarRing
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc


def _run(name: str, navigator: str, **kw):
    sc = paper_scenario(name)
    return sc, simulate(sc.world, sc.start, sc.goal, navigator, **kw)


@pytest.mark.parametrize("name", PAPER_SCENARIOS)
def test_fuzzy_reaches_the_goal_in_the_paper_scenarios(name):
    sc, run = _run(name, "fuzzy")
    assert run.outcome == Outcome.SUCCESS, run.summary()
    assert np.hypot(*(run.poses[-1, :2] - sc.goal)) <= run.goal_tolerance
    assert run.min_clearance > 0


def test_u_trap_needs_the_escape():
    _, trapped = _run("u-trap", "fuzzy-no-escape")
    # with the default 1500 steps and a 200-step stall window, a trapped robot stalls
    assert trapped.outcome == Outcome.STALL, trapped.summary()
    # it never got past the bottom of the U (y = 7.1 inside, the goal is at y = 10)
    assert trapped.poses[:, 1].max() < 7.1
    _, escaped = _run("u-trap", "fuzzy")
    assert escaped.outcome == Outcome.SUCCESS, escaped.summary()
    assert np.any(escaped.escaping)


def test_run_record_is_consistent():
    sc, run = _run("simple", "fuzzy")
    robot = Unicycle()
    assert run.outcome == Outcome.SUCCESS
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
    assert d["mu"][0][3] == run.mu[0, 3]


def test_same_seed_same_run_with_noisy_sonar():
    noisy = ReactiveParams(sonar=SonarRing(noise_std=0.03))
    _, a = _run("corridor", "fuzzy", params=noisy, seed=5)
    _, b = _run("corridor", "fuzzy", params=noisy, seed=5)
    _, c = _run("corridor", "fuzzy", params=noisy, seed=6)
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.scans, b.scans)
    # the first scan already differs: the noise depends on the seed
    assert not np.array_equal(a.scans[0], c.scans[0])


def test_small_random_suite_fuzzy_succeeds_without_collisions():
    scenarios = random_navigation_suite(12, seed=11)
    runs = run_navigation_suite(scenarios, ["fuzzy", "vfh"], seed=11)
    table = navigation_suite_summary(runs)
    assert table["fuzzy"]["collisions"] == 0 and table["vfh"]["collisions"] == 0
    assert table["fuzzy"]["success"] >= 11
    for name, rs in runs.items():
        row = table[name]
        assert row["runs"] == 12 == len(rs)
        assert row["success"] + row["collisions"] + row["stalls"] + row["timeouts"] == 12
        assert row["stalls"] == sum(r.outcome == Outcome.STALL for r in rs)


def test_benchmark_path_ratio_is_against_the_exact_shortest_path():
    from subtask_opt.planners.polygon.visibility import shortest_path_length

    table = benchmark_navigators(2, 3, navigators=["fuzzy", "vff"])
    assert set(table) == {"fuzzy", "vff"}
    scenarios = random_navigation_suite(2, 3)
    runs = run_navigation_suite(scenarios, ["fuzzy"], seed=3)["fuzzy"]
    ok = [i for i, r in enumerate(runs) if r.success]
    assert ok, "fuzzy failed both random worlds"
    ratios = [runs[i].path_length / shortest_path_length(scenarios[i].world,
                                                         scenarios[i].start[:2],
                                                         scenarios[i].goal) for i in ok]
    assert table["fuzzy"]["mean_path_ratio"] == pytest.approx(np.mean(ratios), rel=1e-12)
    assert min(ratios) >= 1.0 - 1e-9   # nothing beats the shortest path


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


def _sim(**kw) -> ReactiveParams:
    return ReactiveParams(sim=SimParams(**kw))


def test_collision_stall_and_timeout_end_the_run():
    sc = paper_scenario("u-trap")
    hit = simulate(sc.world, sc.start, sc.goal, _Straight())
    assert hit.outcome == Outcome.COLLISION
    assert hit.min_clearance < 0
    # the straight line from (5, 1) heading +y first touches the U's inner wall y = 7.1
    # when the centre is one radius below it: the run stops at that contact
    np.testing.assert_allclose(hit.poses[-1, :2], [5.0, 7.1 - 0.2], atol=1e-7)
    for i in range(hit.steps):          # the record stays consistent up to the contact
        np.testing.assert_allclose(hit.poses[i + 1],
                                   integrate_arc(hit.poses[i], *hit.commands[i], 0.5),
                                   atol=1e-12)
    stuck = simulate(sc.world, sc.start, sc.goal, _Still(), params=_sim(stall_steps=5))
    assert stuck.outcome == Outcome.STALL and stuck.steps == 5
    short = simulate(sc.world, sc.start, sc.goal, "fuzzy", params=_sim(max_steps=7))
    assert short.outcome == Outcome.TIMEOUT and short.steps == 7
    for run in (hit, stuck, short):
        res = run.to_plan_result()
        assert not res.success and res.outcome == run.outcome


class _Sideways:
    """Drives along an arc that grazes a corner between two samples of the old check."""

    name = "arc"

    def reset(self) -> None: ...

    def decide(self, pose, ranges, goal) -> NavDecision:
        return NavDecision(v=0.3, omega=0.0)


def test_the_swept_check_catches_a_corner_between_samples():
    # the robot drives along y = 1 (body y in [0.8, 1.2]) in steps of 0.15 from x = 0.5; a
    # triangle's apex at (1.0625, 1.199) pokes 0.001 into that band, where the body covers
    # it only for centres x in 1.0625 -+ 0.02: between the evenly spaced samples 1.025
    # and 1.1 of the step from 0.95 (both 0.2025 from the apex)
    world = PolygonWorld((0.0, 0.0, 4.0, 3.0),
                         (np.array([[0.95, 2.5], [1.0625, 1.199], [1.175, 2.5]]),))
    run = simulate(world, (0.5, 1.0, 0.0), (3.5, 1.0), _Sideways())
    assert run.outcome == Outcome.COLLISION
    # the body first touches the apex where (x - 1.0625)^2 + 0.199^2 = 0.2^2
    np.testing.assert_allclose(run.poses[-1, :2], [1.0625 - math.sqrt(0.2**2 - 0.199**2), 1.0],
                               atol=1e-7)


def test_registered_planners_follow_the_protocol():
    found = planners("reactive")
    assert list(found) == list(NAVIGATORS)
    sc = paper_scenario("u-trap")
    expected = {"fuzzy": Outcome.SUCCESS, "fuzzy-no-escape": Outcome.STALL,
                "vff": Outcome.STALL, "vfh": Outcome.STALL}     # no escape: trapped in the U
    for name, info in found.items():
        assert info.description and info.stochastic and not info.iterative
        res = info.plan(sc.world, sc.start, sc.goal, params=None, seed=0, stop=None)
        assert isinstance(res, PlanResult) and res.planner == name
        assert res.outcome == expected[name], res.message
        assert res.success == (expected[name] == Outcome.SUCCESS)
        assert res.info["outcome"] == expected[name].value
        np.testing.assert_array_equal(res.path[0], sc.start[:2])
        res.to_dict()        # JSON-safe
    assert get_planner("reactive", "vfh").plan is found["vfh"].plan


@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, "3", True])
def test_plan_rejects_bad_seeds(seed):
    sc = paper_scenario("simple")
    with pytest.raises(ParameterError, match="seed"):
        plan(sc.world, sc.start, sc.goal, seed=seed)


def test_plan_rejects_a_stopping_criterion_and_foreign_params():
    sc = paper_scenario("simple")
    with pytest.raises(ParameterError, match="stop"):
        plan(sc.world, sc.start, sc.goal, stop=object())
    with pytest.raises(ParameterError, match="params"):
        plan(sc.world, sc.start, sc.goal, params=SimParams())
    with pytest.raises(InputDataError, match="PolygonWorld"):
        plan("simple", sc.start, sc.goal)


def test_reactive_params_refuse_runs_beyond_the_memory_limit():
    need = ReactiveParams(sim=SimParams(max_steps=1000)).memory_estimate()
    assert 0 < need < MEMORY_LIMIT
    with pytest.raises(ParameterError, match=r"max_steps = 100000000 .* MiB, more than the limit"):
        ReactiveParams(sim=SimParams(max_steps=10**8))
    with pytest.raises(ParameterError, match="more than the limit"):
        ReactiveParams(sonar=SonarRing(n_beams=MAX_BEAMS), sim=SimParams(max_steps=200_000))


def test_reactive_params_refuse_steps_longer_than_the_sonar_range():
    with pytest.raises(ParameterError, match="must not exceed the sonar range"):
        ReactiveParams(robot=Unicycle(max_speed=6.0, dt=0.5))
    ReactiveParams(robot=Unicycle(max_speed=5.0, dt=0.5))   # 2.5: exactly the range


def test_shared_params_and_worlds_give_the_same_runs_from_many_threads():
    from concurrent.futures import ThreadPoolExecutor

    params = ReactiveParams(sonar=SonarRing(noise_std=0.02))
    cases = [(name, nav) for name in PAPER_SCENARIOS for nav in ("fuzzy", "vfh")]
    worlds = {name: paper_scenario(name) for name in PAPER_SCENARIOS}

    def one(case):
        sc = worlds[case[0]]
        return plan(sc.world, sc.start, sc.goal, params=params, seed=4, navigator=case[1])

    serial = [one(c) for c in cases]
    with ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(one, cases * 2))
    for i, res in enumerate(threaded):
        ref = serial[i % len(cases)]
        np.testing.assert_array_equal(res.path, ref.path)
        assert res.outcome == ref.outcome


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
    with pytest.raises(ParameterError, match="max_steps"):
        SimParams(max_steps=2**70)
    with pytest.raises(ParameterError, match="ReactiveParams.robot"):
        ReactiveParams(robot=SonarRing())


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
        sc = random_navigation_scenario(seed, params)
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
    assert random_navigation_scenario(7).world == random_navigation_scenario(7).world
    assert random_navigation_suite(3, 1)[2].world == random_navigation_suite(5, 1)[2].world
    with pytest.raises(ParameterError, match="seed"):
        random_navigation_scenario(-1)
    with pytest.raises(ParameterError, match="n"):
        random_navigation_suite(0, 1)


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
    run = simulate(sc.world, sc.start, sc.goal, "fuzzy", params=_sim(max_steps=12))
    fig = plot_run(sc.world, run)
    assert fig.axes[0].get_xlabel() == "x (m)" and "fuzzy on u-trap" in fig.axes[0].get_title()
    fig.savefig(tmp_path / "run.png")
    fig2 = plot_memberships(run)
    fig2.savefig(tmp_path / "mu.png")
    out = animate_run(sc.world, run, tmp_path / "run.gif", every=4)
    from PIL import Image

    with Image.open(out) as im:       # frames at steps 0, 4, 8, 12
        assert im.format == "GIF" and im.n_frames == 4


@pytest.mark.parametrize("navigator, panels", [("fuzzy", 3), ("vfh", 2), ("vff", 2)])
def test_run_figure_has_no_empty_panel(navigator, panels):
    import matplotlib.pyplot as plt

    from subtask_opt.plotting.reactive import plot_memberships, run_figure

    sc = paper_scenario("simple")
    run = simulate(sc.world, sc.start, sc.goal, navigator, params=_sim(max_steps=30))
    fig = run_figure(sc.world, run)
    twins = [ax for ax in fig.axes if ax.get_ylabel() == "turn rate (rad/s)"]
    assert len(fig.axes) - len(twins) == panels and len(twins) == 1
    for ax in fig.axes:                   # every panel draws data and names its units
        assert ax.lines or ax.collections
        assert "(" in ax.get_ylabel()
    for ax in set(fig.axes) - set(twins):
        assert "(" in ax.get_xlabel() and navigator in ax.get_title()
    plt.close(fig)
    if navigator != "fuzzy":
        with pytest.raises(ParameterError, match="no fuzzy memberships"):
            plot_memberships(run)


# ------------------------------------------------------------------ invariants and baselines

@settings(max_examples=8, deadline=None)
@given(x=st.floats(0.5, 9.5), y=st.floats(0.5, 9.5), th=st.floats(-math.pi, math.pi),
       gx=st.floats(0.5, 9.5), gy=st.floats(0.5, 9.5))
def test_fuzzy_never_collides(x, y, th, gx, gy):
    world = paper_scenario("simple").world
    assume(world.is_free((x, y)) and world.distance_to_obstacles((x, y)) >= 0.3
           and world.is_free((gx, gy)))
    run = simulate(world, (x, y, th), (gx, gy), "fuzzy", params=_sim(max_steps=120))
    assert run.outcome != Outcome.COLLISION, run.summary()
    assert run.min_clearance > 0


def test_vfh_blocks_the_directions_an_enlarged_echo_subtends():
    robot, sonar = Unicycle(), SonarRing()
    nav = VFHNavigator(robot, sonar, SonarVFHParams(threshold_distance=1.0, safety_margin=0.08))
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
    nav = VFFNavigator(robot, sonar, SonarVFFParams())
    d = nav.decide(np.zeros(3), np.full(18, 2.5), np.array([5.0, 0.0]))
    assert d.v == robot.max_speed and d.omega == 0.0
    ranges = np.full(18, 2.5)
    ranges[6:9] = 0.4                                   # echoes ahead on the right
    d = nav.decide(np.zeros(3), ranges, np.array([5.0, 0.0]))
    assert d.omega > 0                                  # pushed to the left
    with pytest.raises(ParameterError, match="SonarVFFParams.attraction"):
        SonarVFFParams(attraction=0.0)
    with pytest.raises(ParameterError, match="SonarVFHParams.threshold_distance"):
        SonarVFHParams(threshold_distance=-1.0)


def test_baselines_never_drive_into_a_wall_they_see():
    # a wall 0.35 ahead (clearance 0.15 < radius + margin): neither baseline moves forward
    robot, sonar = Unicycle(), SonarRing()
    world = PolygonWorld((0.0, 0.0, 4.0, 4.0), (np.array([[1.35, 0.5], [1.6, 0.5], [1.6, 3.5],
                                                          [1.35, 3.5]]),))
    from subtask_opt.planners.reactive.sonar import scene_edges

    pose = np.array([1.0, 2.0, 0.0])
    ranges = sonar.scan(scene_edges(world), pose)
    for nav in (VFFNavigator(robot, sonar), VFHNavigator(robot, sonar)):
        d = nav.decide(pose, ranges, np.array([3.0, 2.0]))
        assert d.v == 0.0, nav.name

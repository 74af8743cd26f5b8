"""Invariants checked with independent oracles: the baselines' driven bodies never overlap an
obstacle (shapely), and the scenario/world readers turn any input into a valid object or the
project's error (hypothesis fuzzing)."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import SubtaskOptError
from subtask_opt.base.results import Outcome
from subtask_opt.planners.reactive.scenarios import (
    RandomSuiteParams,
    Scenario,
    paper_scenario,
    random_navigation_scenario,
    resolve_world,
)
from subtask_opt.planners.reactive.simulation import ReactiveParams, SimParams, simulate
from subtask_opt.planners.reactive.unicycle import integrate_arc

shapely = pytest.importorskip("shapely")
from shapely.geometry import LineString, Polygon, box  # noqa: E402

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))


# ------------------------------------------------------------------ bodies never overlap

def _driven_polyline(run, per_step: int = 64) -> np.ndarray:
    """The centre's path, each step's arc densified (chord error < 1e-5 for these robots)."""
    f = np.linspace(0.0, 1.0, per_step + 1)[1:]
    pts = [run.poses[:1, :2]]
    for i in range(run.steps):
        v, om = run.commands[i]
        pts.append(integrate_arc(run.poses[i], v * f, om * f, run.dt)[:, :2])
    return np.vstack(pts)


def _assert_body_clear(world, run) -> None:
    """Shapely: the centre's path stays at least one radius from every obstacle and wall."""
    path = _driven_polyline(run)
    line = LineString(path) if len(path) > 1 else LineString([path[0], path[0]])
    x0, y0, x1, y1 = world.bounds
    assert box(x0, y0, x1, y1).contains(line)
    assert line.distance(box(x0, y0, x1, y1).exterior) >= run.radius - 1e-5
    for k, poly in enumerate(world.obstacles):
        d = Polygon(poly).distance(line)
        assert d >= run.radius - 1e-5, (f"{run.navigator}: body overlaps obstacle {k} by "
                                        f"{run.radius - d:.3g} m ({run.outcome})")


@pytest.mark.parametrize("navigator", ["vff", "vfh"])
@settings(max_examples=6, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**63 - 1))
def test_baselines_never_drive_through_an_obstacle(navigator, seed):
    sc = random_navigation_scenario(seed)
    params = ReactiveParams(sim=SimParams(max_steps=250))
    run = simulate(sc.world, sc.start, sc.goal, navigator, params=params, seed=seed)
    assert run.outcome != Outcome.COLLISION, run.summary()
    _assert_body_clear(sc.world, run)


@pytest.mark.fuzz
@pytest.mark.parametrize("navigator", ["vff", "vfh", "fuzzy"])
@settings(max_examples=FUZZ_EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**63 - 1), noise=st.sampled_from([0.0, 0.02]))
def test_fuzz_navigators_never_drive_through_an_obstacle(navigator, seed, noise):
    from subtask_opt.planners.reactive.sonar import SonarRing

    sc = random_navigation_scenario(seed, RandomSuiteParams(min_obstacles=14, max_obstacles=20))
    params = ReactiveParams(sonar=SonarRing(noise_std=noise), sim=SimParams(max_steps=400))
    run = simulate(sc.world, sc.start, sc.goal, navigator, params=params, seed=seed)
    assert run.outcome != Outcome.COLLISION, run.summary()
    _assert_body_clear(sc.world, run)


# random-146409670 (14-20 obstacles): with 0.02 m sonar noise VFF stood 3 cm from a wall
# turning back and forth, until one echo read 5 cm too long let its guard drive on
_NOISY_WORLD = 146409670


def _noisy_world_run(noise_sigmas: float):
    from subtask_opt.planners.reactive.baselines import SonarVFFParams
    from subtask_opt.planners.reactive.sonar import SonarRing

    sc = random_navigation_scenario(_NOISY_WORLD,
                                    RandomSuiteParams(min_obstacles=14, max_obstacles=20))
    assert sc.start[:2] == pytest.approx((1.0, 5.6117), abs=1e-4)
    params = ReactiveParams(sonar=SonarRing(noise_std=0.02), sim=SimParams(max_steps=400),
                            vff=SonarVFFParams(noise_sigmas=noise_sigmas))
    return sc, simulate(sc.world, sc.start, sc.goal, "vff", params=params, seed=_NOISY_WORLD)


def test_vff_with_sonar_noise_keeps_clear_in_the_world_the_fuzzer_found():
    sc, run = _noisy_world_run(3.0)  # the default
    assert run.outcome != Outcome.COLLISION, run.summary()
    _assert_body_clear(sc.world, run)


def test_without_the_noise_margin_vff_hits_that_wall():
    # the regression above can fail: the guard trusting the noisy echoes collides
    sc, run = _noisy_world_run(0.0)
    assert run.outcome == Outcome.COLLISION
    with pytest.raises(AssertionError, match="overlaps"):
        _assert_body_clear(sc.world, _extend(run))


def _extend(run):
    """The collided run with its last step driven to the full command (past the contact)."""
    from dataclasses import replace

    v, om = run.commands[-1]
    cmds = run.commands.copy()
    cmds[-1] = (v * 2.0, om * 2.0)
    return replace(run, commands=cmds)


def test_pessimistic_ranges_moves_only_the_echoes():
    from subtask_opt.planners.reactive.baselines import pessimistic_ranges
    from subtask_opt.planners.reactive.sonar import SonarRing

    ring = SonarRing(n_beams=4, max_range=2.5, noise_std=0.02)
    got = pessimistic_ranges(ring, np.array([2.5, 1.0, 0.03, 0.0]), 3.0)
    np.testing.assert_allclose(got, [2.5, 1.0 - 0.06, 0.0, 0.0])
    quiet = SonarRing(n_beams=4, max_range=2.5)
    np.testing.assert_array_equal(pessimistic_ranges(quiet, np.array([2.5, 1.0, 0.3, 0.0]), 3.0),
                                  [2.5, 1.0, 0.3, 0.0])


def test_noise_sigmas_is_validated():
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.planners.reactive.baselines import SonarVFFParams, SonarVFHParams

    for cls in (SonarVFFParams, SonarVFHParams):
        for bad in (-0.1, 10.5, math.nan, "3"):
            with pytest.raises(ParameterError, match=f"{cls.__name__}.noise_sigmas"):
                cls(noise_sigmas=bad)


def test_the_oracle_sees_a_collision():
    # the oracle itself must be able to fail: a straight drive into the U
    from subtask_opt.planners.reactive.fuzzy import NavDecision

    class Straight:
        name = "straight"

        def reset(self) -> None: ...

        def decide(self, pose, ranges, goal) -> NavDecision:
            return NavDecision(v=1.0, omega=0.0)

    sc = paper_scenario("u-trap")
    run = simulate(sc.world, sc.start, sc.goal, Straight())
    # the run stops at contact: clear up to 1e-5, and one more step would overlap
    _assert_body_clear(sc.world, run)
    longer = integrate_arc(run.poses[-1], 0.05, 0.0, 1.0)
    assert Polygon(sc.world.obstacles[0]).distance(
        LineString([run.poses[-1, :2], longer[:2]])) < run.radius - 0.04


# ------------------------------------------------------------------ readers: fuzzing

_JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-10**20, 10**20)
    | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner,
                                                                max_size=5),
    max_leaves=25)

_NUM = st.one_of(st.floats(-20, 20), st.integers(-20, 20), st.just(float("nan")),
                 st.just(1e308), st.text(max_size=3), st.none())


@st.composite
def _near_scenarios(draw):
    """Scenario dicts close to valid ones, with mutated fields."""
    base = paper_scenario(draw(st.sampled_from(["simple", "u-trap", "corridor"]))).to_dict()
    key = draw(st.sampled_from(["world", "start", "goal", "name", "bounds", "obstacle",
                                "vertex", "drop"]))
    if key == "start":
        base["start"] = draw(st.lists(_NUM, max_size=4) | _JSON)
    elif key == "goal":
        base["goal"] = draw(st.lists(_NUM, max_size=3) | _JSON)
    elif key == "name":
        base["name"] = draw(_JSON)
    elif key == "world":
        base["world"] = draw(_JSON)
    elif key == "bounds":
        base["world"]["bounds"] = draw(st.lists(_NUM, max_size=5) | _JSON)
    elif key == "obstacle":
        obs = base["world"]["obstacles"]
        obs[draw(st.integers(0, len(obs) - 1))] = draw(st.lists(st.lists(_NUM, max_size=3),
                                                                max_size=6) | _JSON)
    elif key == "vertex":
        obs = base["world"]["obstacles"]
        poly = obs[draw(st.integers(0, len(obs) - 1))]
        poly[draw(st.integers(0, len(poly) - 1))] = [draw(_NUM), draw(_NUM)]
    else:
        base.pop(draw(st.sampled_from(["world", "start", "goal"])))
    return base


def _reads_or_refuses(d) -> None:
    """A valid Scenario whose start and goal are free, or a SubtaskOptError: nothing else."""
    try:
        sc = Scenario.from_dict(d)
    except SubtaskOptError as exc:
        assert str(exc)
        return
    assert sc.world.is_free(sc.start[:2]) and sc.world.is_free(sc.goal)
    assert all(math.isfinite(v) for v in (*sc.start, *sc.goal))
    assert Scenario.from_dict(sc.to_dict()).world == sc.world


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(d=_JSON | _near_scenarios())
def test_scenario_reader_gives_a_scenario_or_the_projects_error(d):
    _reads_or_refuses(d)


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=st.binary(max_size=300) | _near_scenarios().map(
    lambda d: json.dumps(d).encode()))
def test_scenario_files_give_a_world_or_the_projects_error(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.json"
        path.write_bytes(data)
        try:
            world, sc = resolve_world(str(path))
        except SubtaskOptError as exc:
            assert str(path) in str(exc)
            return
        assert sc is None or sc.world is world


@pytest.mark.fuzz
@settings(max_examples=FUZZ_EXAMPLES * 10, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(d=_JSON | _near_scenarios())
def test_fuzz_scenario_reader(d):
    _reads_or_refuses(d)


@pytest.mark.fuzz
@settings(max_examples=FUZZ_EXAMPLES * 5, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=st.binary(max_size=2000) | _JSON.map(lambda d: json.dumps(d).encode())
       | _near_scenarios().map(lambda d: json.dumps(d).encode()))
def test_fuzz_scenario_files(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.json"
        path.write_bytes(data)
        try:
            resolve_world(str(path))
        except SubtaskOptError:
            pass


def test_scenario_round_trip_through_a_file(tmp_path):
    sc = paper_scenario("corridor")
    sc.to_json(tmp_path / "c.json")
    again = Scenario.from_json(tmp_path / "c.json")
    assert again.world == sc.world and again.start == sc.start and again.goal == sc.goal
    world, found = resolve_world(str(tmp_path / "c.json"))
    assert found is not None and found.goal == sc.goal and world == sc.world

"""Every polygon planner through the registry: protocol, bad input, awkward geometry,
and a property test of collision-freedom checked independently with shapely."""

from __future__ import annotations

import dataclasses
import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point, Polygon, box
from shapely.ops import unary_union

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.base.results import Outcome
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.base import get_planner, planners
from subtask_opt.planners.polygon import maklink, visibility
from subtask_opt.planners.polygon.world import (
    MAX_FILE_BYTES,
    MAX_JSON_DEPTH,
    MAX_VERTICES,
    MEMORY_LIMIT_BYTES,
    PolygonWorld,
    convex_hull,
    planner_memory_bytes,
)

NAMES = ("dijkstra", "improved", "pso", "visibility")


def run(name: str, world: PolygonWorld, start, goal):
    """A planner from the registry, with a seed and a short stop only where it takes them."""
    info = get_planner("polygon", name)
    kwargs = {}
    if info.stochastic:
        kwargs["seed"] = 3
    if info.iterative:
        kwargs["stop"] = MaxGenerations(40)
    return info.plan(world, start, goal, **kwargs)


# -- the registry ------------------------------------------------------------------


def test_registry_lists_the_four_planners():
    found = planners("polygon")
    assert sorted(found) == sorted(NAMES)
    assert [n for n, i in found.items() if i.stochastic] == ["pso"]
    assert [n for n, i in found.items() if i.iterative] == ["pso"]
    assert all(i.description for i in found.values())


@pytest.mark.parametrize("name", NAMES)
def test_registered_planner_names_its_result(seed003, name):
    res = run(name, seed003, (20, 20), (320, 320))
    assert res.planner == name and res.outcome == Outcome.SUCCESS
    json.dumps(res.to_dict())  # JSON-safe, info included


@pytest.mark.parametrize("name", ["dijkstra", "improved", "visibility"])
def test_deterministic_planners_refuse_seed_and_stop(seed003, name):
    plan = get_planner("polygon", name).plan
    with pytest.raises(ParameterError, match=f"{name} is deterministic"):
        plan(seed003, (20, 20), (320, 320), seed=0)
    with pytest.raises(ParameterError, match=f"{name} is not iterative"):
        plan(seed003, (20, 20), (320, 320), stop=MaxGenerations(3))


@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, True, "1"])
def test_pso_refuses_bad_seeds(seed003, seed):
    with pytest.raises(ParameterError, match=r"seed must be an integer in \[0, 2\*\*63\)"):
        get_planner("polygon", "pso").plan(seed003, (20, 20), (320, 320), seed=seed)


def test_pso_params_type_checked(seed003):
    with pytest.raises(ParameterError, match="pso params must be None or a PSOParams"):
        get_planner("polygon", "pso").plan(seed003, (20, 20), (320, 320), params={"swarm": 3})


# -- start equals goal -------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_start_equals_goal_is_a_zero_length_success(seed003, name):
    graph = maklink.graph_for(seed003)
    # an ordinary point, and the midpoint of a free link (a point on two cells)
    for p in ((20.0, 20.0), tuple(graph.midpoints[0])):
        res = run(name, seed003, p, p)
        assert res.success and res.length == 0.0
        np.testing.assert_array_equal(res.path[0], p)
        np.testing.assert_array_equal(res.path[-1], p)


# -- points on boundaries, degenerate polygons ---------------------------------------


@pytest.mark.parametrize("p, where", [
    ((40, 200), "on the boundary of obstacle 0"),  # on an edge
    ((40, 151), "on the boundary of obstacle 0"),  # a vertex
    ((50, 200), "inside obstacle 0"),
])
@pytest.mark.parametrize("name", NAMES)
def test_points_on_obstacle_boundaries_are_not_free(seed003, name, p, where):
    with pytest.raises(UnreachableError, match=f"start .* is {where}"):
        run(name, seed003, p, (320, 320))


def test_start_on_the_outer_boundary_is_free(seed003):
    for name in ("improved", "pso", "visibility"):  # the straight line along the wall
        assert run(name, seed003, (0, 0), (350, 0)).length == pytest.approx(350.0)
    dij = run("dijkstra", seed003, (0, 0), (350, 0))  # through link midpoints: longer
    assert dij.success and dij.length > 350.0


def test_collinear_vertex_changes_nothing():
    plain = PolygonWorld((0, 0, 10, 10), ([[4, 2], [6, 2], [6, 8], [4, 8]],))
    extra = PolygonWorld((0, 0, 10, 10), ([[4, 2], [5, 2], [6, 2], [6, 8], [4, 8]],))
    for name in NAMES:
        a, b = run(name, plain, (5, 1), (8, 1)), run(name, extra, (5, 1), (8, 1))
        assert a.success and b.success
        assert b.length == pytest.approx(a.length, rel=1e-9)
    assert run("visibility", extra, (5, 1), (8, 1)).length == pytest.approx(
        math.dist((5, 1), (8, 1)))
    assert run("visibility", extra, (5, 1.9), (5, 8.5)).length == pytest.approx(
        math.dist((5, 1.9), (6, 2)) + 6 + math.dist((6, 8), (5, 8.5)))


@pytest.mark.parametrize("obstacles, match", [
    (([[1, 1], [3, 3], [5, 5]],), "obstacle 0 is degenerate"),  # collinear: zero area
    (([[1, 1], [2, 1], [2, 1], [1, 2]],), "obstacle 0 is not a simple"),  # repeated vertex
    (([[1, 1], [4, 1], [4, 4], [1, 4]], [[2, 2], [6, 2], [6, 6]]), "obstacles 0 and 1 overlap"),
    (([[1, 1], [4, 1], [4, 4], [1, 4]], [[4, 4], [6, 4], [6, 6]]), "obstacles 0 and 1 overlap"),
])
def test_degenerate_or_overlapping_obstacles_are_refused(obstacles, match):
    with pytest.raises(InputDataError, match=match):
        PolygonWorld((0, 0, 10, 10), obstacles)


# -- zero-width gaps at the outer boundary ----------------------------------------------

POCKET = {"bounds": [0, 0, 10, 10], "obstacles": [[[6, 6], [10, 6], [6, 10]]]}


@pytest.mark.parametrize("name", NAMES)
def test_obstacle_touching_the_walls_closes_the_corner(name):
    world = PolygonWorld.from_dict(POCKET)
    res = run(name, world, (1, 1), (9.5, 9.5))
    assert not res.success and res.outcome == Outcome.NO_PATH and res.path.shape == (0, 2)
    inside = run(name, world, (9.5, 9.5), (7.5, 9.9))  # both in the corner pocket
    assert inside.success and inside.length == pytest.approx(math.dist((9.5, 9.5), (7.5, 9.9)))


def test_visibility_leaves_out_vertices_on_the_walls():
    world = PolygonWorld.from_dict(POCKET)
    assert world.on_bounds.tolist() == [False, True, True]
    assert visibility.graph_for(world).vertex_index.tolist() == [0]


# -- immutability and the graph caches -----------------------------------------------------


def test_world_is_immutable_and_keeps_no_planner_state(seed003):
    before = dict(vars(seed003))
    for name in NAMES:
        run(name, seed003, (20, 20), (320, 320))
    assert vars(seed003).keys() == before.keys()
    assert all(vars(seed003)[k] is before[k] for k in before)
    with pytest.raises(dataclasses.FrozenInstanceError):
        seed003.name = "x"  # type: ignore[misc]
    for arr in (seed003.vertices, seed003.edges, seed003.obstacles[0], seed003.offsets):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 0


def test_graph_caches_are_keyed_by_equal_worlds(seed003):
    twin = PolygonWorld.from_dict(seed003.to_dict())
    assert twin == seed003 and hash(twin) == hash(seed003) and twin is not seed003
    assert maklink.graph_for(twin) is maklink.graph_for(seed003)
    other = PolygonWorld.from_dict({**seed003.to_dict(), "name": "copy"})
    assert maklink.graph_for(other) is not maklink.graph_for(seed003)


# -- the JSON reader -------------------------------------------------------------------------


@pytest.mark.parametrize("text, match", [
    ('{"bounds": [0, 0, 10, "10"], "obstacles": []}', "four finite numbers"),
    ('{"bounds": [0, 0, 10, 10], "obstacles": [[[1, 1], [2, 1], ["2", 2]]]}', "vertex 2"),
    ('{"bounds": [0, 0, 10, NaN], "obstacles": []}', "NaN is not a finite number"),
    ('{"bounds": [0, 0, 10, Infinity], "obstacles": []}', "Infinity is not a finite"),
    ('{"bounds": [0, 0, 10, 1e999], "obstacles": []}', "1e999 is out of range"),
    ('{"bounds": [0, 0, 10, 10], "obstacles": [], "name": 5}', "'name' must be a string"),
    ('{"bounds": {"a": 1}, "obstacles": []}', "'bounds' must be a list"),
    ('{"bounds": [0, 0, 10, 10], "obstacles": [[[[[[[[1]]]]]]]]}', "nested 9 deep"),
    ('{"bounds": [0, 0, 10, 10], "obstacles": [[[1, 1], [2, 1], [1, ' + "9" * 5000 + "]]]}",
     "digits"),
    ("[" * 100000, "nested 100000 deep"),
    ("", "not valid JSON"),
])
def test_reader_refuses(text, match):
    with pytest.raises(InputDataError, match=match):
        PolygonWorld.from_text(text)


def test_reader_depth_ignores_brackets_in_strings():
    world = PolygonWorld.from_text('{"bounds": [0, 0, 1, 1], "obstacles": [], '
                                   '"name": "[[[[[[[[[[[[ ]"}')
    assert world.name == "[[[[[[[[[[[[ ]" and MAX_JSON_DEPTH == 8


def test_reader_refuses_oversize_files(tmp_path):
    big = tmp_path / "big.json"
    big.write_text('{"bounds": [0, 0, 1, 1], "obstacles": []}' + " " * MAX_FILE_BYTES)
    with pytest.raises(InputDataError, match=f"the limit is {MAX_FILE_BYTES}"):
        PolygonWorld.from_json(big)
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + json.dumps(POCKET).encode())
    assert PolygonWorld.from_json(bom) == PolygonWorld.from_dict(POCKET, name="bom")
    bad = tmp_path / "bad.json"
    bad.write_bytes(b'{"name": "\xff"}')
    with pytest.raises(InputDataError, match="not UTF-8"):
        PolygonWorld.from_json(bad)


def test_vertex_limit_follows_from_memory():
    # the limit is the largest vertex count whose estimate fits in the memory budget
    assert max(planner_memory_bytes(MAX_VERTICES).values()) <= MEMORY_LIMIT_BYTES
    assert max(planner_memory_bytes(MAX_VERTICES + 1).values()) > MEMORY_LIMIT_BYTES
    assert planner_memory_bytes(98)["visibility"] == 8 * 100**2 * 8  # 8 dense float matrices
    n = MAX_VERTICES + 1
    ring = np.column_stack([5 + 4 * np.cos(np.linspace(0, 2 * np.pi, n, endpoint=False)),
                            5 + 4 * np.sin(np.linspace(0, 2 * np.pi, n, endpoint=False))])
    with pytest.raises(InputDataError, match=rf"{n} obstacle vertices.*MiB.*at most "
                                             rf"{MAX_VERTICES} vertices"):
        PolygonWorld((0, 0, 10, 10), (ring,))


_SCALARS = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                     st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4))
_JSONISH = st.recursive(_SCALARS, lambda kids: st.one_of(
    st.lists(kids, max_size=5), st.dictionaries(st.sampled_from(
        ["bounds", "obstacles", "name", "x"]), kids, max_size=4)), max_leaves=40)


def _mutate(text: str, cuts: list[tuple[int, str]]) -> str:
    for pos, ins in cuts:
        pos %= len(text) + 1
        text = text[:pos] + ins + text[pos + 1:]
    return text


_VALID = json.dumps({"bounds": [0, 0, 10, 10],
                     "obstacles": [[[1, 1], [4, 1], [4, 4]], [[6, 6], [9, 6], [9, 9], [6, 9]]]})
_TEXTS = st.one_of(
    st.text(max_size=200),
    _JSONISH.map(lambda v: json.dumps(v)),
    st.builds(lambda b, o: json.dumps({"bounds": b, "obstacles": o}), _JSONISH, _JSONISH),
    st.lists(st.tuples(st.integers(0, 10**4), st.sampled_from(
        ["", "[", "]", "{", "}", ",", '"', "-", "1e999", "NaN", "0", "9" * 30, "true"])),
        max_size=6).map(lambda cuts: _mutate(_VALID, cuts)),
)


def _reader_gives_a_world_or_input_data_error(text: str) -> None:
    try:
        world = PolygonWorld.from_text(text)
    except InputDataError:
        return
    assert isinstance(world.bounds, tuple) and all(math.isfinite(v) for v in world.bounds)
    assert all(p.shape[1] == 2 and len(p) >= 3 for p in world.obstacles)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=_TEXTS)
def test_reader_gives_a_world_or_input_data_error(text):
    _reader_gives_a_world_or_input_data_error(text)


@pytest.mark.fuzz
@settings(max_examples=int(os.environ.get("FUZZ_EXAMPLES", "60")), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(text=_TEXTS)
def test_fuzz_reader_gives_a_world_or_input_data_error(text):
    _reader_gives_a_world_or_input_data_error(text)


# -- property: paths stay in the start's component of the free space (shapely) ---------------


def _u_shape(cx: int, cy: int, turn: int, depth: float) -> np.ndarray:
    """A U-shaped (non-convex) obstacle filling most of cell (cx, cy), opening in one of
    four directions, its pocket ``depth`` (0..1) of the cell deep."""
    u = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.7, 0.9], [0.7, 0.9 - 0.6 * depth],
                  [0.3, 0.9 - 0.6 * depth], [0.3, 0.9], [0.1, 0.9]])
    for _ in range(turn):  # rotate by 90 deg about the cell centre
        u = np.column_stack([1.0 - u[:, 1], u[:, 0]])
    return (np.array([cx, cy]) + u) * (100 / 3)


@st.composite
def walled_worlds(draw):
    """Obstacles in a 3 x 3 grid of cells over 100 x 100: convex hulls of random points
    or U shapes (non-convex, with a pocket). A convex obstacle in a border cell may
    get a vertex on the adjacent wall(s), which closes the gap between it and the
    wall (a corner obstacle touching both walls seals a pocket)."""
    obstacles = []
    for cx in range(3):
        for cy in range(3):
            if not draw(st.booleans()):
                continue
            if draw(st.integers(0, 3)) == 0:
                obstacles.append(_u_shape(cx, cy, draw(st.integers(0, 3)),
                                          draw(st.floats(0.2, 0.9))))
                continue
            pts = np.array(draw(st.lists(st.tuples(st.floats(0.1, 0.9), st.floats(0.1, 0.9)),
                                         min_size=3, max_size=6)))
            pts = (np.array([cx, cy]) + pts) * (100 / 3)
            extra = []
            if cx == 0 and draw(st.booleans()):
                extra.append((0.0, pts[np.argmin(pts[:, 0]), 1]))
            if cx == 2 and draw(st.booleans()):
                extra.append((100.0, pts[np.argmax(pts[:, 0]), 1]))
            if cy == 0 and draw(st.booleans()):
                extra.append((pts[np.argmin(pts[:, 1]), 0], 0.0))
            if cy == 2 and draw(st.booleans()):
                extra.append((pts[np.argmax(pts[:, 1]), 0], 100.0))
            hull = convex_hull(np.vstack([pts, *extra]) if extra else pts)
            if len(hull) < 3 or Polygon(hull).area < 5.0:
                continue
            try:  # the hull of nearly collinear points can fold back in floating point
                PolygonWorld((0.0, 0.0, 100.0, 100.0), (hull,), name="one")
            except InputDataError:
                continue
            obstacles.append(hull)
    return PolygonWorld((0.0, 0.0, 100.0, 100.0), tuple(obstacles), name="walled")


def _free_components(world: PolygonWorld) -> list:
    free = box(*world.bounds).difference(unary_union([Polygon(p) for p in world.obstacles]))
    return list(getattr(free, "geoms", [free]))


def _component_of(components, p) -> int:
    d = [c.distance(Point(p)) for c in components]
    return int(np.argmin(d))


@settings(max_examples=int(os.environ.get("POLYGON_PROPERTY_EXAMPLES", "25")), deadline=None,
          suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow])
@given(data=st.data())
def test_paths_never_cross_obstacles_or_closed_gaps(data):
    world = data.draw(walled_worlds())
    pts = [np.array([data.draw(st.floats(0, 100)), data.draw(st.floats(0, 100))])
           for _ in range(2)]
    assume(all(world.is_free(p) and world.distance_to_obstacles(p) > 1e-3 for p in pts))
    start, goal = pts
    comps = _free_components(world)
    same = _component_of(comps, start) == _component_of(comps, goal)
    region = comps[_component_of(comps, start)].buffer(1e-6)
    shrunk = [Polygon(p).buffer(-1e-6) for p in world.obstacles]
    for name in NAMES:
        res = run(name, world, start, goal)
        assert res.success == same, (name, res.message)
        if res.success:
            line = LineString(res.path)
            assert region.covers(line), name  # never leaves the start's free component
            assert not any(line.intersects(s) for s in shrunk if not s.is_empty), name

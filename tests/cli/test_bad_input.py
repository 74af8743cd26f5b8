"""Issue 16's list of bad inputs, walked in its order: one test id per example.

Each example either exits 2 with exactly one line on stderr (a user mistake),
succeeds (the input is legitimate, e.g. start = goal), or exits 1 (the job ran
and genuinely failed, e.g. a goal behind a corner gap). API examples raise the
project's :class:`SubtaskOptError` subclass instead of Python's own errors.
Sections follow the issue: numbers, allocations, degenerate geometry, malformed
structure, output paths, silently accepted input, planner correctness, valid
input refused. The random-world properties of the planners live in
``tests/planners/*/test_properties.py``.
"""

from __future__ import annotations

import json
import threading
from importlib.resources import files

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError, SubtaskOptError
from subtask_opt.cli import main
from subtask_opt.tour.problem import MatrixProblem

SUBTASKS = "x,y\n0.30,0.10\n0.35,0.22\n0.25,0.30\n0.40,0.05\n"
FAST = ["--max-generations", "3", "--no-progress", "--quiet"]
DEEP = 3000
"""Nesting depth of the 'thousands deep' JSON examples."""


def _one_line(capsys, code: int, *needles: str) -> str:
    """The command's stderr: exactly one line (or none on success), no traceback, holding
    every needle (case-insensitive)."""
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    if code == 0:
        assert err == "" or len(err.splitlines()) == 1
    else:
        assert len(err.splitlines()) == 1, err
    for n in needles:
        assert n.lower() in err.lower(), (n, err)
    return err


def _exits(argv: list[str], code: int, capsys, *needles: str) -> str:
    assert main(argv) == code
    return _one_line(capsys, code, *needles)


@pytest.fixture
def part(tmp_path):
    """A valid four-subtask CSV file."""
    path = tmp_path / "part.csv"
    path.write_text(SUBTASKS)
    return path


@pytest.fixture
def urdf_robot(tmp_path):
    """A copy of planar_2r as a URDF file with its limits JSON beside it: (urdf, params)."""
    robots = files("subtask_opt.robots")
    urdf = tmp_path / "arm.urdf"
    urdf.write_text((robots / "planar_2r.urdf").read_text())
    return urdf, json.loads((robots / "planar_2r.json").read_text())


def _agv_scenario(tmp_path, **changes):
    d = {"name": "corridor", "map": ["..........", "....@@....", ".........."],
         "start": [0, 1], "goal": [9, 1]}
    d.update(changes)
    path = tmp_path / "agv.json"
    path.write_text(json.dumps(d))
    return path


# ---------------------------------------------------------------- numbers out of any range

def test_max_generations_2_to_the_63(capsys):
    _exits(["solve", "--case", "square20", "--max-generations", str(2**63), *FAST[2:]], 2,
           capsys, "max-generations", str(2**63))


def test_no_improvement_of_a_billion(capsys):
    _exits(["solve", "--case", "square20", "--no-improvement", "1000000000", *FAST[2:]], 2,
           capsys, "no-improvement", "1000000000")


def test_no_improvement_2_to_the_64(capsys):
    _exits(["solve", "--case", "square20", "--no-improvement", str(2**64), *FAST[2:]], 2,
           capsys, "no-improvement")


def test_stall_2_to_the_64(capsys):
    _exits(["plan", "grid", "--map", "open", "--planner", "ga", "--stall", str(2**64)], 2,
           capsys, "stall")


def test_json_subtasks_with_a_thousands_digit_integer(tmp_path, capsys):
    path = tmp_path / "big.json"
    path.write_text('{"points": [[' + "9" * 5000 + ", 0.1], [0.3, 0.2], [0.2, 0.3]]}")
    _exits(["solve", "--case", str(path), *FAST], 2, capsys, str(path))


@pytest.mark.parametrize("argv", [
    ["plan", "grid", "--map", "open", "--planner", "ga"],
    ["plan", "reactive", "--world", "simple"],
    ["bench", "grid"],
    ["bench", "reactive"],
], ids=["plan-grid-ga", "plan-reactive", "bench-grid", "bench-reactive"])
def test_negative_seed(argv, capsys):
    _exits([*argv, "--seed", "-1"], 2, capsys, "seed", "-1")


def test_api_numbers_given_as_strings(part):
    from subtask_opt import MaxRuntime, SolverParams, TargetCost

    with pytest.raises(ParameterError, match="MaxRuntime"):
        MaxRuntime("1")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="TargetCost"):
        TargetCost("5")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="convergence_tol"):
        SolverParams(convergence_tol="0.1")  # type: ignore[arg-type]


def test_api_solve_with_params_as_a_name(part):
    from subtask_opt import solve
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.tasks import load_subtasks
    from subtask_opt.kinematics.planar import load_planar_arm

    problem = PlanarProblem(load_subtasks(part), load_planar_arm("planar_2r"))
    with pytest.raises(SubtaskOptError, match="params"):
        solve(problem, params="default")  # type: ignore[arg-type]


def test_api_problem_with_the_arm_as_a_name(part):
    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.tasks import load_subtasks
    from subtask_opt.kinematics.planar import load_planar_arm

    subtasks = load_subtasks(part)
    try:
        by_name = PlanarProblem(subtasks, "planar_2r")  # type: ignore[arg-type]
    except SubtaskOptError as exc:  # refused: it must say what to do instead
        assert "load_planar_arm" in str(exc)
        return
    by_object = PlanarProblem(subtasks, load_planar_arm("planar_2r"))
    np.testing.assert_array_equal(by_name.matrix, by_object.matrix)


# ---------------------------------------------------------------- allocations

def test_trajectory_dt_1e_minus_9(tmp_path, capsys):
    _exits(["solve", "--case", "square20", *FAST, "--trajectory", str(tmp_path / "t.csv"),
            "--dt", "1e-9"], 2, capsys, "--dt", "1e-9")
    assert not (tmp_path / "t.csv").exists()


def test_agv_scenario_with_a_tiny_dt(tmp_path, capsys):
    path = _agv_scenario(tmp_path, params={"dt": 1e-9})
    _exits(["plan", "agv", "--scenario", str(path)], 2, capsys, "dt")


def test_agv_scenario_with_a_huge_max_time(tmp_path, capsys):
    path = _agv_scenario(tmp_path, params={"max_time_s": 1e15})
    _exits(["plan", "agv", "--scenario", str(path)], 2, capsys, "max_time_s")


def test_polygon_world_with_5000_vertices(tmp_path, capsys):
    # 1250 small squares in a 100 x 100 world: 5,000 vertices
    obstacles = [[[x, y], [x + 0.5, y], [x + 0.5, y + 0.5], [x, y + 0.5]]
                 for x in range(1, 51) for y in range(1, 26)]
    path = tmp_path / "w.json"
    path.write_text(json.dumps({"bounds": [0, 0, 100, 100], "obstacles": obstacles}))
    code = main(["plan", "polygon", "--world", str(path), "--start", "0.2,0.2",
                 "--goal", "99,99", "--planner", "visibility", "--no-progress"])
    if code == 2:  # refused for its size: the line says which limit
        _one_line(capsys, 2, "vert")
    else:  # or planned (within the test's time): then it found the obvious path
        assert code == 0
        capsys.readouterr()


def test_one_line_csv_of_50_mb(tmp_path, capsys):
    path = tmp_path / "big.csv"
    path.write_bytes(b"x,y," + b"1," * (25 * 1024 * 1024))
    _exits(["solve", "--case", str(path), *FAST], 2, capsys, str(path))


# ---------------------------------------------------------------- degenerate geometry

@pytest.mark.parametrize("planner", ["pso", "dijkstra", "improved", "visibility"])
def test_plan_polygon_start_equals_goal(planner, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["plan", "polygon", "--start", "20,20", "--goal", "20,20", "--planner", planner,
                 "--seed", "1", "--json", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    r = json.loads(out.read_text())
    assert r["success"] is True and r["length"] == 0.0


# ---------------------------------------------------------------- malformed structure

def test_deep_json_subtasks(tmp_path, capsys):
    path = tmp_path / "deep.json"
    path.write_text('{"points": ' + "[" * DEEP + "]" * DEEP + "}")
    _exits(["solve", "--case", str(path), *FAST], 2, capsys, "nest")


def test_deep_json_robot_limits(tmp_path, urdf_robot, capsys):
    urdf, params = urdf_robot
    text = json.dumps(params).replace('"kv": 1.0', '"kv": ' + "[" * DEEP + "]" * DEEP)
    urdf.with_suffix(".json").write_text(text)
    _exits(["solve", "--case", "square20", "--robot", str(urdf), *FAST], 2, capsys, "nest")


def test_deep_json_polygon_world(tmp_path, capsys):
    path = tmp_path / "w.json"
    path.write_text('{"bounds": [0, 0, 10, 10], "obstacles": ' + "[" * DEEP + "]" * DEEP + "}")
    _exits(["plan", "polygon", "--world", str(path), "--start", "1,1", "--goal", "9,9"], 2,
           capsys, "nest")


def test_deep_json_agv_scenario(tmp_path, capsys):
    path = tmp_path / "agv.json"
    path.write_text('{"map": ["...."], "start": [0, 0], "goal": [3, 0], "obstacles": '
                    + "[" * DEEP + "]" * DEEP + "}")
    _exits(["plan", "agv", "--scenario", str(path)], 2, capsys, "nest")


def test_agv_scenario_with_a_string_for_a_number(tmp_path, capsys):
    path = _agv_scenario(tmp_path, obstacles=[{"path": [[5, 2], [5, 0]], "speed": "fast"}])
    _exits(["plan", "agv", "--scenario", str(path)], 2, capsys, "speed")


# ---------------------------------------------------------------- output paths

def test_plot_with_an_unknown_suffix(tmp_path, capsys):
    _exits(["solve", "--case", "square20", *FAST, "--plot", str(tmp_path / "out.xyz")], 2,
           capsys, ".xyz")


def test_animate_as_mp4(tmp_path, capsys):
    _exits(["solve", "--case", "square20", *FAST, "--animate", str(tmp_path / "out.mp4")], 2,
           capsys, ".gif")


def test_json_to_an_empty_path(capsys):
    _exits(["solve", "--case", "square20", *FAST, "--json", ""], 2, capsys, "json")


# ---------------------------------------------------------------- silently accepted or wrong

@pytest.mark.parametrize("base", [0.3, 0.3 + 0.5e-9, 0.123456789123])
def test_subtasks_1e_minus_12_apart_are_duplicates_wherever_they_sit(base, tmp_path, capsys):
    path = tmp_path / "dup.csv"
    path.write_text(f"x,y\n{base!r},0.1\n{base + 1e-12!r},0.1\n0.25,0.3\n")
    _exits(["solve", "--case", str(path), *FAST], 2, capsys, "duplicate")


def test_subtask_reachable_only_past_a_joint_limit(tmp_path, capsys):
    path = tmp_path / "limit.csv"
    path.write_text("x,y\n0.4,0.0\n0.12,0.0\n0.3,0.1\n")
    _exits(["solve", "--case", str(path), *FAST], 2, capsys, "subtask 1", "joint limit")


def test_cartesian_limit_of_1e_minus_308(tmp_path, urdf_robot, capsys):
    urdf, params = urdf_robot
    params["cartesian_limits"]["kv"] = 1e-308
    urdf.with_suffix(".json").write_text(json.dumps(params))
    _exits(["solve", "--case", "square20", "--robot", str(urdf), "--time-model", "line",
            *FAST], 2, capsys, "kv")


def test_json_output_onto_the_input(part, capsys):
    before = part.read_bytes()
    _exits(["solve", "--case", str(part), *FAST, "--json", str(part)], 2, capsys, str(part))
    assert part.read_bytes() == before


def test_complex_subtasks():
    from subtask_opt import Targets

    with pytest.raises(InputDataError):
        Targets(np.array([[0.3 + 1j, 0.1], [0.35, 0.22], [0.25, 0.3]]))


def test_matrix_problem_of_1e308():
    from subtask_opt import MaxGenerations, solve

    try:
        problem = MatrixProblem(np.full((4, 4), 1e308))
    except SubtaskOptError as exc:
        assert "matrix" in str(exc)
        return
    result = solve(problem, seed=0, stop=MaxGenerations(5))
    assert np.isfinite(result.cost)


# ---------------------------------------------------------------- planner correctness

@pytest.mark.parametrize("planner", ["vff", "vfh", "dt", "mdt"])
def test_grid_diagonal_corner_gap_2x2(planner, tmp_path, capsys):
    path = tmp_path / "gap.map"
    path.write_text("type octile\nheight 2\nwidth 2\nmap\n.@\n@.\n")
    _exits(["plan", "grid", "--map", str(path), "--start", "0,0", "--goal", "1,1",
            "--planner", planner], 1, capsys)


@pytest.mark.parametrize("planner", ["vff", "vfh", "dt", "mdt"])
def test_grid_diagonal_corner_gap_2x7(planner, tmp_path, capsys):
    path = tmp_path / "gap.map"
    path.write_text("type octile\nheight 2\nwidth 7\nmap\n...@...\n..@....\n")
    _exits(["plan", "grid", "--map", str(path), "--start", "0,0", "--goal", "6,1",
            "--planner", planner], 1, capsys)


@pytest.mark.parametrize("planner", ["visibility", "dijkstra", "improved", "pso"])
def test_obstacle_vertex_touching_the_boundary_closes_the_gap(planner, tmp_path, capsys):
    path = tmp_path / "touch.json"
    path.write_text('{"bounds":[0,0,10,10],"obstacles":[[[6,6],[10,6],[6,10]]]}')
    _exits(["plan", "polygon", "--world", str(path), "--start", "1,1", "--goal", "9.5,9.5",
            "--planner", planner, "--seed", "0", "--no-progress"], 1, capsys)


def test_arm_fk_from_eight_threads():
    from subtask_opt.kinematics.planar import load_planar_arm

    arm = load_planar_arm("planar_2r")
    qs = np.random.default_rng(5).uniform(-2.5, 2.5, size=(2000, 2))
    expected = np.array([arm.fk(q) for q in qs])
    results: list[np.ndarray | None] = [None] * 8
    barrier = threading.Barrier(8)

    def work(k: int) -> None:
        barrier.wait()
        out = np.empty_like(expected)
        for i in np.roll(np.arange(len(qs)), 251 * k):
            out[i] = arm.fk(qs[i])
        results[k] = out

    threads = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for out in results:
        np.testing.assert_array_equal(out, expected)


# ---------------------------------------------------------------- valid input refused or blamed

def test_negative_start_without_the_equals_sign(capsys):
    # parsed as a value (not taken for an option), then refused as outside the world
    err = _exits(["plan", "polygon", "--start", "-50,-50", "--goal", "320,320"], 2, capsys,
                 "-50")
    assert "expected one argument" not in err


def test_csv_with_a_utf8_bom(tmp_path, capsys):
    path = tmp_path / "bom.csv"
    path.write_text(SUBTASKS, encoding="utf-8-sig")
    assert main(["solve", "--case", str(path), *FAST]) == 0
    capsys.readouterr()


def test_agv_obstacle_parking_on_the_goal_is_not_blamed_on_the_input(tmp_path, capsys):
    path = tmp_path / "parked.json"
    path.write_text(json.dumps({
        "name": "parked", "map": ["." * 12] * 9, "start": [1, 4], "goal": [9, 4],
        "obstacles": [{"path": [[9, 0], [9, 4]], "start_time": 2.0}],
        "params": {"max_time_s": 40.0}}))
    err = _exits(["plan", "agv", "--scenario", str(path)], 1, capsys)
    assert "goal is on an obstacle" not in err


def test_bad_urdf_prints_only_our_line(tmp_path, capfd):
    urdf = tmp_path / "bad.urdf"
    urdf.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'>"
                    "<parent link='a'/><child link='missing'/></joint></robot>")
    assert main(["solve", "--case", "square20", "--robot", str(urdf), *FAST]) == 2
    err = capfd.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert str(urdf) in err and "Traceback" not in err


@pytest.mark.parametrize("argv", [["bench", "maklink", "--runs", "1", "--seed=--"],
                                  ["plan", "reactive", "--world", "simple", "--start=--"]])
def test_a_lone_double_dash_is_a_missing_value(argv, capsys):
    # argparse hands the handler an empty list for "--"; found by make fuzz
    _exits(argv, 2, capsys, "expected a value")

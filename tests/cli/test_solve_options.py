"""Every option of ``subtask-opt solve`` × every kind of robot: honoured, or refused.

An option that applies to one kind of robot only (``cli.solve.ONLY``) exits 2 with one
line naming it on the other kind; every other option applies to both, and the tests below
check that it does something there (``tests/arm/test_problem.py`` checks the API behind it).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.cli import build_parser, main
from subtask_opt.cli.solve import ONLY, PLANAR, SERIAL

DATA = Path(__file__).resolve().parents[2] / "examples" / "data"
ROWS = "x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n" \
       "0.42,-0.10,0.35,1,0,-0.3\n0.42,0.10,0.35,1,0,-0.3\n"
SAMPLE = {  # a valid value of every option that takes one
    "case_seed": "3", "k": "0.2", "elbow": "1", "configurations": "fixed",
    "line_fallback": "exclude", "animate": "{dir}/a.gif", "scene": str(DATA /
                                                                     "ur5_panel_scene.json"),
    "standoff": "0.01", "axis_step": "90", "tool_frame": "tool0", "limits": "{dir}/lim.json",
    "view": "{dir}/v.html",
}
BOTH = {"case", "robot", "time_model", "first", "tour", "end", "home", "home_joints",
        "precedence", "preset",
        "seed", "runs", "certify", "certify_time_limit", "vmax", "amax", "jmax",
        "speed_scale", "accel_scale", "max_generations", "max_runtime", "no_improvement",
        "target", "json", "plot", "trajectory", "dt", "quiet", "no_progress"}
"""The options that apply to every robot (``time_model``: every robot has ``joint``)."""


def _solve_actions() -> list[argparse.Action]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [a for a in sub.choices["solve"]._actions if a.dest not in ("help", "handler")]


def test_every_option_is_classified() -> None:
    dests = {a.dest for a in _solve_actions()}
    assert dests == BOTH | set(ONLY), (dests - BOTH - set(ONLY), BOTH | set(ONLY) - dests)
    assert not BOTH & set(ONLY)


@pytest.fixture()
def files(tmp_path: Path) -> dict[str, str]:
    (tmp_path / "holes.csv").write_text(ROWS)
    (tmp_path / "lim.json").write_text(json.dumps({"acceleration": [3.0] * 6}))
    return {"dir": str(tmp_path), "holes": str(tmp_path / "holes.csv")}


def _base(kind: str, files: dict[str, str]) -> list[str]:
    if kind == PLANAR:
        return ["solve", "--case", "square20", "--max-generations", "3"]
    return ["solve", "--robot", "ur5", "--case", files["holes"], "--home",
            "0,-90,90,-90,-90,0", "--max-generations", "3"]


@pytest.mark.parametrize("dest", sorted(ONLY))
def test_an_option_of_the_other_kind_of_robot_is_refused_in_one_line(dest, files,
                                                                      capsys) -> None:
    other = SERIAL if ONLY[dest] == PLANAR else PLANAR
    action = next(a for a in _solve_actions() if a.dest == dest)
    flag = action.option_strings[0]
    value = [] if action.nargs == 0 else [SAMPLE[dest].format(dir=files["dir"])]
    code = main([*_base(other, files), flag, *value])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and flag in err[0] and f"{ONLY[dest]} arms only" in err[0], err


def _json(argv: list[str], tmp: str) -> dict:
    out = Path(tmp) / "out.json"
    assert main([*argv, "--json", str(out), "--quiet"]) == 0
    return json.loads(out.read_text())


@pytest.mark.parametrize("kind", [PLANAR, SERIAL])
def test_shape_options_are_honoured_on_both_kinds(kind, files, tmp_path) -> None:
    base = [a for a in _base(kind, files) if a not in ("--max-generations", "3")]
    (tmp_path / "prec.txt").write_text("2,1\n")
    doc = _json([*base, "--tour", "open", "--first", "3", "--precedence",
                 str(tmp_path / "prec.txt"), "--seed", "1"], files["dir"])
    order = doc["order"]
    assert doc["tour"] == "open" and order[0] == 3
    assert order.index(2) < order.index(1)
    n = len(order)
    # an open path: a planar arm drives N - 1 legs between subtasks, a serial arm N from home
    assert len(doc["leg_times"]) == (n - 1 if kind == PLANAR else n)
    assert doc["lower_bound"] <= doc["total_time"]
    closed = _json([*base, "--end", "2", "--seed", "1"] + (
        ["--home", "0.3,0.3"] if kind == PLANAR else []), files["dir"])
    assert closed["order"][-1] == 2


@pytest.mark.parametrize("kind", [PLANAR, SERIAL])
def test_a_home_configuration_is_honoured_on_both_kinds(kind, files, tmp_path) -> None:
    """--home-joints: the trajectory starts in that configuration on every robot."""
    csv = tmp_path / "t.csv"
    joints = "30,-60" if kind == PLANAR else "0,-90,90,-90,-90,0"
    base = [a for a in _base(kind, files) if a not in ("--home", "0,-90,90,-90,-90,0")]
    _json([*base, "--home-joints", joints, "--trajectory", str(csv)], files["dir"])
    first = np.loadtxt(csv, delimiter=",", skiprows=1)[0]
    q = np.radians([float(v) for v in joints.split(",")])
    np.testing.assert_allclose(first[1:1 + q.size], q, atol=1e-9)


@pytest.mark.parametrize("kind", [PLANAR, SERIAL])
def test_speed_limits_are_honoured_on_both_kinds(kind, files, tmp_path) -> None:
    base = _base(kind, files)
    csv = tmp_path / "t.csv"
    full = _json([*base, "--seed", "0"], files["dir"])
    slow = _json([*base, "--seed", "0", "--vmax", "0.5", "--speed-scale", "0.5",
                  "--trajectory", str(csv)], files["dir"])
    assert slow["total_time"] > full["total_time"]
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    nq = 2 if kind == PLANAR else 6
    speeds = np.abs(rows[:, 1 + nq:1 + 2 * nq])
    assert speeds.max() <= 0.25 * (1 + 1e-6)


@pytest.mark.parametrize("kind", [PLANAR, SERIAL])
def test_certify_and_runs_are_honoured_on_both_kinds(kind, files) -> None:
    doc = _json([*_base(kind, files), "--certify", "--runs", "2", "--seed", "0"],
                files["dir"])
    assert doc["certified"] is not None and doc["runs"] == 2

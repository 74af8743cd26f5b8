"""One CLI convention for every command: exit 0 ok, 1 ran and failed, 2 bad input.

Every stochastic command refuses a negative seed, every command with an input
refuses a missing one, and every planning command that cannot reach its goal
exits 1 - each with exactly one line on stderr and no traceback.
"""

from __future__ import annotations

import json

import pytest

from subtask_opt.cli import main
from subtask_opt.kinematics.planar import load_planar_arm

SEEDED = [
    ["solve", "--case", "square20"],
    ["tsp", "FILE"],
    ["batch", "FILE", "--json", "OUT"],
    ["plan", "grid", "--map", "open", "--planner", "ga"],
    ["plan", "polygon", "--start", "20,20", "--goal", "320,320", "--planner", "pso"],
    ["plan", "reactive", "--world", "simple"],
    ["plan", "agv"],
    ["bench", "grid"],
    ["bench", "maklink"],
    ["bench", "reactive"],
    ["bench", "agv"],
]

MISSING = [
    ["solve", "--case", "MISSING.csv"],
    ["tsp", "MISSING.tsp"],
    ["batch", "MISSING.csv", "--json", "OUT"],
    ["plan", "grid", "--map", "MISSING.map"],
    ["plan", "polygon", "--world", "MISSING.json", "--start", "1,1", "--goal", "2,2"],
    ["plan", "reactive", "--world", "MISSING.json"],
    ["plan", "agv", "--scenario", "MISSING.json"],
    ["bench", "movingai", "--map", "MISSING.map", "--scen", "MISSING.scen"],
    ["bench", "maklink", "--world", "MISSING.json"],
]


def _fill(argv: list[str], tmp_path) -> list[str]:
    tsp = tmp_path / "tiny.tsp"
    tsp.write_text("NAME: tiny\nTYPE: TSP\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EUC_2D\n"
                   "NODE_COORD_SECTION\n1 0 0\n2 10 0\n3 10 10\n4 0 10\nEOF\n")
    csv = tmp_path / "part.csv"
    csv.write_text("x,y\n0.30,0.10\n0.35,0.22\n0.25,0.30\n")
    out = []
    for a in argv:
        if a == "FILE":
            a = str(tsp) if argv[0] == "tsp" else str(csv)
        elif a == "OUT":
            a = str(tmp_path / "out.json")
        elif a.startswith("MISSING"):
            a = str(tmp_path / a)
        out.append(a)
    return out


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize("argv", SEEDED, ids=lambda a: " ".join(a[:2]))
def test_a_negative_seed_is_refused_in_one_line(argv, tmp_path, capsys):
    assert main([*_fill(argv, tmp_path), "--seed", "-1"]) == 2
    assert "seed" in _one_line(capsys)


@pytest.mark.parametrize("argv", SEEDED, ids=lambda a: " ".join(a[:2]))
def test_a_seed_of_two_to_the_63_is_refused(argv, tmp_path, capsys):
    assert main([*_fill(argv, tmp_path), "--seed", str(2**63)]) == 2
    assert "seed" in _one_line(capsys)


@pytest.mark.parametrize("argv", MISSING, ids=lambda a: " ".join(a[:2]))
def test_a_missing_input_is_refused_in_one_line(argv, tmp_path, capsys):
    assert main(_fill(argv, tmp_path)) == 2
    assert "MISSING" in _one_line(capsys)


def test_solve_that_finds_no_tour_exits_1(tmp_path, capsys):
    arm = load_planar_arm("asr_twodof")
    bx, by = arm.base_xy
    r = 0.5 * (arm.r_min + arm.r_max)
    csv = tmp_path / "disc.csv"  # every tour needs a straight line through the inner disc
    csv.write_text(f"x,y\n{bx - r},{by}\n{bx + r},{by}\n{bx},{by + r}\n")
    assert main(["solve", "--case", str(csv), "--robot", "asr_twodof", "--time-model",
                 "line", "--line-fallback", "exclude"]) == 1
    _one_line(capsys)


def test_plan_grid_without_a_path_exits_1(tmp_path, capsys):
    walled = tmp_path / "walled.txt"
    walled.write_text(".....\n..@@@\n..@..\n..@@@\n.....\n")
    assert main(["plan", "grid", "--map", str(walled), "--start", "0,0", "--goal", "3,2",
                 "--planner", "dt"]) == 1
    _one_line(capsys)


def test_plan_polygon_without_a_path_exits_1(tmp_path, capsys):
    world = tmp_path / "pocket.json"
    world.write_text(json.dumps({"bounds": [0, 0, 10, 10],
                                 "obstacles": [[[6, 6], [10, 6], [6, 10]]]}))
    assert main(["plan", "polygon", "--world", str(world), "--start", "1,1", "--goal",
                 "9.5,9.5", "--planner", "visibility"]) == 1
    _one_line(capsys)


def test_plan_reactive_that_stalls_exits_1(capsys):
    assert main(["plan", "reactive", "--world", "u-trap", "--navigator", "fuzzy-no-escape"]) == 1
    _one_line(capsys)


def test_plan_agv_that_collides_exits_1(capsys):
    assert main(["plan", "agv", "--scenario", "2-3", "--no-collision-check"]) == 1
    _one_line(capsys)


def test_batch_with_a_failed_job_exits_1(tmp_path, capsys):
    bad = tmp_path / "far.csv"
    bad.write_text("x,y\n0.30,0.10\n0.35,0.22\n9.0,9.0\n")
    assert main(["batch", str(bad), "--json", str(tmp_path / "b.json"), "--workers", "0"]) == 1


def test_batch_plot_marks_the_failed_job(tmp_path, capsys):
    good = tmp_path / "good.csv"
    good.write_text("x,y\n0.30,0.10\n0.35,0.22\n0.25,0.30\n")
    bad = tmp_path / "far.csv"
    bad.write_text("x,y\n0.30,0.10\n0.35,0.22\n9.0,9.0\n")
    png = tmp_path / "b.png"
    assert main(["batch", str(good), str(bad), "--json", str(tmp_path / "b.json"),
                 "--plot", str(png), "--workers", "0"]) == 1
    assert png.stat().st_size > 5_000
    data = json.loads((tmp_path / "b.json").read_text())
    assert [j["success"] for j in data["jobs"]] == [True, False]


def test_python_dash_m_runs_the_same_cli(tmp_path) -> None:
    """``python -m subtask_opt.cli`` is the console script: a run writes its JSON (exit 0),
    bad input is one line on stderr and exit 2."""
    import subprocess
    import sys

    out = tmp_path / "square20.json"
    ok = subprocess.run([sys.executable, "-m", "subtask_opt.cli", "solve", "--case", "square20",
                         "--time-model", "trapezoid", "--json", str(out)],
                        capture_output=True, text=True, timeout=600)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(out.read_text())["total_time"] > 0
    bad = subprocess.run([sys.executable, "-m", "subtask_opt.cli", "solve", "--case", "nope"],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2
    assert len(bad.stderr.strip().splitlines()) == 1


def test_a_closed_standard_output_is_a_failed_run_in_one_line() -> None:
    """``subtask-opt ... | head`` whose reader leaves before the output ends: exit 1 with one
    line, not 2 (bad input) and no second error from the interpreter's last flush."""
    import os
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)  # nobody will read: the first print fails
    proc = subprocess.run([sys.executable, "-m", "subtask_opt.cli", "plan", "grid", "--map",
                           "fig2.4", "--start", "2,7", "--goal", "12,1", "--planner", "dt"],
                          stdout=write_end, stderr=subprocess.PIPE, text=True, timeout=600)
    os.close(write_end)
    err = proc.stderr.splitlines()
    assert proc.returncode == 1, proc.stderr
    assert err[-1] == "subtask-opt: failed: standard output was closed before the run finished"
    assert not any("Exception ignored" in line or "Traceback" in line for line in err)


def _every_option(parser, path=()):
    """(command path, action) of every option of every subcommand."""
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _every_option(sub, (*path, name))
        elif action.option_strings:
            yield path, action


def test_no_option_reads_a_number_with_the_builtin_parsers() -> None:
    # Python's float() and int() read Arabic-Indic, full-width and mathematical digits
    # ("٣", "１", "𝟙"), which an option never means: every numeric option goes through
    # the ASCII-checking parsers of cli._common, on every command
    from subtask_opt.cli.app import build_parser

    builtin = [(" ".join(path), action.option_strings[0])
               for path, action in _every_option(build_parser())
               if action.type in (float, int, complex)]
    assert builtin == []


@pytest.mark.parametrize("digit", ["\u0663", "\uff11", "\U0001d7d9"])
def test_reactive_numbers_in_other_scripts_are_refused(digit, capsys) -> None:
    for option in ("--noise", "--range", "--max-speed", "--max-turn-rate", "--dt"):
        assert main(["plan", "reactive", "--world", "simple", option, digit]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and option in err[0]


def test_a_huge_subtask_file_among_good_ones_fails_only_its_job(tmp_path, capsys):
    from subtask_opt.base.files import MAX_FILE_BYTES

    good = tmp_path / "good.csv"
    good.write_text("x,y\n0.30,0.10\n0.35,0.22\n0.25,0.30\n")
    huge = tmp_path / "huge.csv"
    with huge.open("wb") as f:  # sparse: the size without the disk
        f.truncate(MAX_FILE_BYTES + 1)
    out = tmp_path / "b.json"
    assert main(["batch", str(good), str(huge), "--json", str(out), "--workers", "0",
                 "--max-generations", "3", "--no-progress"]) == 1
    jobs = {j["id"]: j for j in json.loads(out.read_text())["jobs"]}
    assert jobs[str(good)]["success"] and not jobs[str(huge)]["success"]
    assert "bytes" in jobs[str(huge)]["error"] and str(MAX_FILE_BYTES) in jobs[str(huge)]["error"]

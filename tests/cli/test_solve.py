"""`subtask-opt solve`: output, JSON, figures and one-line errors with exit code 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from subtask_opt.cli.app import main
from tests.conftest import size


def test_solve_prints_order_and_leg_table_and_writes_json_and_plot(tmp_path, capsys):
    out_json = tmp_path / "r.json"
    out_png = tmp_path / "r.png"
    code = main(["solve", "--case", "square20", "--seed", "3", "--json", str(out_json),
                 "--plot", str(out_png), *size([], ["--max-generations", "20"])])
    assert code == 0
    printed = capsys.readouterr().out
    assert "order:" in printed and "leg" in printed and "time [s]" in printed
    data = json.loads(out_json.read_text())
    for key in ("order", "total_time", "leg_times", "matrix", "generations", "restarts",
                "runtime_s", "seed", "report"):
        assert key in data
    for key in ("time_model", "robot", "infeasible_legs", "configurations", "diagnostics"):
        assert key in data["report"]
    assert data["report"]["time_model"] == "joint"  # the executable default
    assert sorted(data["order"]) == list(range(20))
    m = np.array(data["matrix"])
    order = np.array(data["order"])
    assert data["total_time"] == pytest.approx(m[order, np.roll(order, -1)].sum())
    assert data["seed"] == 3 and data["report"]["robot"] == "planar_2r"
    assert out_png.stat().st_size > 10_000


def test_solve_reads_a_csv_case_and_honours_stopping_options(tmp_path, capsys):
    csv = tmp_path / "points.csv"
    csv.write_text("x,y\n0.3,0.1\n0.35,0.2\n0.25,0.3\n0.4,-0.1\n0.2,-0.2\n")
    assert main(["solve", "--case", str(csv), "--seed", "1", "--max-generations", "7",
                 "--preset", "paper", "--quiet"]) == 0
    assert "7 generations" in capsys.readouterr().out


def test_solve_makes_the_runs_asked_for(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["solve", "--case", "square20", "--runs", "3", "--max-generations", "4",
                 "--quiet", "--json", str(out)]) == 0
    assert "12 generations, " in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["runs"] == 3 and data["generations"] == 12


@pytest.mark.parametrize(("argv", "needle"), [
    (["solve", "--case", "nowhere.csv"], "nowhere.csv"),
    (["solve", "--case", "square20", "--robot", "r2d2"], "r2d2"),
    (["solve", "--case", "square20", "--time-model", "magic"], "magic"),
    (["solve", "--case", "square20", "--seed", "-3"], "-3"),
    (["solve", "--case", "square20", "--max-generations", "0"], "0"),
    (["solve", "--case", "square20", "--first", "99"], "99"),
    (["solve", "--case", "square20", "--runs", "0"], "--runs"),
    (["solve", "--case", "square20", "--runs", "1001"], "1001"),
    (["solve"], "--case"),
])
def test_user_mistakes_print_one_line_and_exit_2(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert needle in err


@pytest.mark.parametrize(("content", "needle"), [
    ("x,y\n0.3,0.1\n0.35,nan\n0.25,0.3\n", "nan"),
    ("x,y\n0.3,0.1\n0.3,0.1\n0.25,0.3\n", "duplicate"),
    ("x,y\n0.3,0.1\n0.25,0.3\n", "3"),
    ("x,y\n0.3,0.1\n5.0,5.0\n0.25,0.3\n", "subtask 1"),
    ("a,b\n1,2\n", "x,y"),
])
def test_bad_subtask_files_exit_2(tmp_path, content, needle, capsys):
    csv = tmp_path / "bad.csv"
    csv.write_text(content)
    assert main(["solve", "--case", str(csv)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert needle.lower() in err.lower()


@pytest.mark.parametrize(("section", "key", "value"), [
    ("cartesian_limits", "kv", -1.0), ("cartesian_limits", "ka", 0.0),
    ("joint_limits", "acceleration", [10.0, -1.0]),
])
def test_non_positive_limits_of_a_urdf_robot_exit_2(tmp_path, capsys, section, key, value):
    from importlib.resources import files

    robots = files("subtask_opt.robots")
    (tmp_path / "arm.urdf").write_text((robots / "planar_2r.urdf").read_text())
    params = json.loads((robots / "planar_2r.json").read_text())
    params[section][key] = value
    (tmp_path / "arm.json").write_text(json.dumps(params))
    assert main(["solve", "--case", "square20", "--robot", str(tmp_path / "arm.urdf")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert key in err


def test_infinite_coordinates_exit_2(tmp_path, capsys):
    csv = tmp_path / "inf.csv"
    csv.write_text("x,y\n0.3,0.1\ninf,0.2\n0.25,0.3\n")
    assert main(["solve", "--case", str(csv)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "inf" in err.lower()


def test_trapezoid_json_checks_the_tour_legs_and_all_pairs_on_request(tmp_path):
    out = tmp_path / "r.json"
    argv = ["solve", "--case", "random30", "--robot", "asr_twodof", "--time-model",
            "trapezoid", "--max-generations", "3", "--quiet", "--json", str(out)]
    assert main(argv) == 0
    report = json.loads(out.read_text())["report"]
    counts = report["tour_leg_check"]
    assert counts["n_legs"] == 30
    assert counts["n_impossible"] + counts["n_overspeed"] == len(report["infeasible_legs"]) > 0
    assert "all_pairs_leg_check" not in report["diagnostics"]
    assert main([*argv, "--check-all-legs"]) == 0
    all_pairs = json.loads(out.read_text())["report"]["diagnostics"]["all_pairs_leg_check"]
    assert all_pairs["n_legs"] == 30 * 29 // 2
    assert all_pairs["n_infeasible"] >= counts["n_impossible"]

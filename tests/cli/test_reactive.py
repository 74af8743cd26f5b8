"""``subtask-opt plan reactive`` and ``subtask-opt bench reactive``."""

from __future__ import annotations

import json

import pytest

from subtask_opt.cli.app import main
from subtask_opt.planners.reactive.scenarios import paper_scenario


def test_plan_reactive_writes_json_plot_and_gif(tmp_path, capsys):
    out = tmp_path / "run.json"
    png = tmp_path / "run.png"
    gif = tmp_path / "run.gif"
    assert main(["plan", "reactive", "--world", "u-trap", "--json", str(out), "--plot", str(png),
                 "--animate", str(gif)]) == 0
    assert "fuzzy on u-trap: success" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["outcome"] == "success" and data["navigator"] == "fuzzy"
    assert len(data["poses"]) == data["steps"] + 1 and len(data["mu"]) == data["steps"]
    assert png.stat().st_size > 0 and gif.read_bytes()[:3] == b"GIF"


def test_plan_reactive_on_a_json_world_with_start_and_goal(tmp_path, capsys):
    path = tmp_path / "world.json"
    paper_scenario("simple").world.to_json(path)
    assert main(["plan", "reactive", "--world", str(path), "--start", "1,1,30",
                 "--goal", "9,9", "--navigator", "vfh", "--seed", "3"]) == 0
    assert "vfh on simple" in capsys.readouterr().out


def test_plan_reactive_no_escape_fails_in_the_u_trap(capsys):
    assert main(["plan", "reactive", "--world", "u-trap", "--navigator", "fuzzy-no-escape"]) == 0
    assert "stall" in capsys.readouterr().out


def test_bench_reactive_json(tmp_path, capsys):
    out = tmp_path / "bench.json"
    assert main(["bench", "reactive", "--n", "2", "--seed", "1", "--navigators", "fuzzy", "vfh",
                 "--json", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "fuzzy" in text and "vfh" in text and "path ratio" in text
    table = json.loads(out.read_text())["navigators"]
    assert set(table) == {"fuzzy", "vfh"}
    for row in table.values():
        assert {"runs", "success", "collisions", "timeouts", "mean_path_ratio",
                "mean_min_clearance"} <= set(row)


@pytest.mark.parametrize("argv, words", [
    (["--world", "u-trap", "--start", "3.2,6,0"], "start"),               # inside an obstacle
    (["--world", "u-trap", "--goal", "5,20"], "goal"),                    # outside the world
    (["--world", "u-trap", "--range", "0"], "max_range"),
    (["--world", "u-trap", "--range", "-2"], "max_range"),
    (["--world", "u-trap", "--max-speed", "0"], "max_speed"),
    (["--world", "u-trap", "--max-turn-rate", "-1"], "max_turn_rate"),
    (["--world", "u-trap", "--noise", "-0.1"], "noise_std"),
    (["--world", "atlantis"], "unknown world"),
    (["--world", "seed003"], "--start"),                                  # no default start
    (["--world", "u-trap", "--start", "1,2"], "3 comma-separated"),
    (["--world", "u-trap", "--navigator", "bug"], "invalid choice"),
])
def test_bad_plan_inputs_exit_2_with_one_line(argv, words, capsys):
    assert main(["plan", "reactive", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err


def test_missing_world_file_exits_2(tmp_path, capsys):
    assert main(["plan", "reactive", "--world", str(tmp_path / "none.json"), "--start", "1,1,0",
                 "--goal", "2,2"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_bad_bench_inputs_exit_2(capsys):
    assert main(["bench", "reactive", "--n", "0"]) == 2
    assert capsys.readouterr().err.count("\n") == 1

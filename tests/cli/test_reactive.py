"""``subtask-opt plan reactive``, ``bench reactive`` and ``bench fuzzy-table``."""

from __future__ import annotations

import json

import pytest

from subtask_opt.cli import main
from subtask_opt.planners.reactive.scenarios import paper_scenario


def test_plan_reactive_writes_json_plot_and_gif(tmp_path, capsys):
    out = tmp_path / "run.json"
    png = tmp_path / "run.png"
    gif = tmp_path / "run.gif"
    assert main(["plan", "reactive", "--world", "u-trap", "--json", str(out), "--plot", str(png),
                 "--animate", str(gif), "--no-progress"]) == 0
    assert "fuzzy on u-trap: success" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["outcome"] == "success" and data["navigator"] == "fuzzy"
    assert len(data["poses"]) == data["steps"] + 1 and len(data["mu"]) == data["steps"]
    assert png.read_bytes()[:4] == b"\x89PNG" and gif.read_bytes()[:3] == b"GIF"


def test_plan_reactive_on_a_json_world_with_start_and_goal(tmp_path, capsys):
    path = tmp_path / "world.json"
    paper_scenario("simple").world.to_json(path)
    assert main(["plan", "reactive", "--world", str(path), "--start", "1,1,30",
                 "--goal", "9,9", "--navigator", "vfh", "--seed", "3"]) == 0
    assert "vfh on simple: success" in capsys.readouterr().out


def test_plan_reactive_on_a_scenario_file(tmp_path, capsys):
    path = tmp_path / "sc.json"
    paper_scenario("corridor").to_json(path)
    assert main(["plan", "reactive", "--world", str(path)]) == 0
    assert "fuzzy on corridor: success" in capsys.readouterr().out


@pytest.mark.parametrize("navigator", ["fuzzy-no-escape", "vff", "vfh"])
def test_a_trapped_run_exits_1_and_says_why(navigator, tmp_path, capsys):
    out = tmp_path / "run.json"
    png = tmp_path / "run.png"
    assert main(["plan", "reactive", "--world", "u-trap", "--navigator", navigator,
                 "--json", str(out), "--plot", str(png)]) == 1
    assert f"{navigator} on u-trap: stall" in capsys.readouterr().out
    assert json.loads(out.read_text())["outcome"] == "stall"
    assert png.stat().st_size > 0          # a failed run still gets its figure


def test_a_timeout_exits_1(capsys):
    assert main(["plan", "reactive", "--world", "simple", "--max-steps", "3"]) == 1
    assert "timeout" in capsys.readouterr().out


def test_navigator_choices_come_from_the_registry():
    from subtask_opt.cli import build_parser
    from subtask_opt.planners.base import planners

    def sub(parser, name):
        action = next(a for a in parser._actions if a.choices and name in a.choices)
        return action.choices[name]

    root = build_parser()
    names = list(planners("reactive"))
    for parser, option in ((sub(sub(root, "plan"), "reactive"), "--navigator"),
                           (sub(sub(root, "bench"), "reactive"), "--navigators")):
        action = next(a for a in parser._actions if option in a.option_strings)
        assert list(action.choices) == names


def test_bench_reactive_json_and_plot(tmp_path, capsys):
    out = tmp_path / "bench.json"
    png = tmp_path / "bench.png"
    assert main(["bench", "reactive", "--n", "2", "--seed", "1", "--workers", "0",
                 "--navigators", "fuzzy", "vfh",
                 "--json", str(out), "--plot", str(png), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "fuzzy" in text and "vfh" in text and "path ratio" in text
    table = json.loads(out.read_text())["navigators"]
    assert set(table) == {"fuzzy", "vfh"}
    for row in table.values():
        assert row["runs"] == 2
        assert row["success"] + row["collisions"] + row["stalls"] + row["timeouts"] == 2
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_fuzzy_table_prints_the_paper_beside_ours(tmp_path, capsys):
    out = tmp_path / "t.json"
    png = tmp_path / "t.png"
    assert main(["bench", "fuzzy-table", "--json", str(out), "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    assert "muD paper       0.1    0.2   0.05    0.4    0.1   0.25    0.2" in text
    assert "muD ours        0.1    0.2   0.05    0.4    0.1   0.25    0.2" in text
    data = json.loads(out.read_text())
    assert data["choice"] == data["paper_choice"] == 4 and data["matches"] is True
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_fuzzy_table_with_saaty_weights(tmp_path, capsys):
    out = tmp_path / "t.json"
    # G1 three times as important as G2 and G3, which are equal: a consistent matrix,
    # eigenvector (3, 1, 1), weights 3 * (3, 1, 1) / 5
    assert main(["bench", "fuzzy-table", "--pairwise", "3,3,1", "--json", str(out)]) == 0
    assert "Saaty weights 1.8000, 0.6000, 0.6000" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["weights"] == pytest.approx([1.8, 0.6, 0.6])
    assert data["weighted"] is True


@pytest.mark.parametrize("argv, words", [
    (["--weights", "1,1"], "weights must be 3 numbers"),
    (["--weights", "1,0,1"], "weights[1] must be a number in (0, 100]"),
    (["--weights", "1,nan,1"], "finite"),
    (["--pairwise", "1,2"], "m (m - 1) / 2"),
    (["--pairwise", "1,-2,3"], "> 0"),
    (["--weights", "1,1,1", "--pairwise", "1,1,1"], "not allowed with"),
])
def test_bad_fuzzy_table_inputs_exit_2(argv, words, capsys):
    assert main(["bench", "fuzzy-table", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err


@pytest.mark.parametrize("argv, words", [
    (["--world", "u-trap", "--start", "3.2,6,0"], "start"),               # inside an obstacle
    (["--world", "u-trap", "--goal", "5,20"], "goal"),                    # outside the world
    (["--world", "u-trap", "--range", "0"], "max_range"),
    (["--world", "u-trap", "--range", "-2"], "max_range"),
    (["--world", "u-trap", "--range", "nan"], "max_range"),
    (["--world", "u-trap", "--range", "inf"], "max_range"),
    (["--world", "u-trap", "--max-speed", "0"], "max_speed"),
    (["--world", "u-trap", "--max-speed", "6"], "must not exceed the sonar range"),
    (["--world", "u-trap", "--max-turn-rate", "-1"], "max_turn_rate"),
    (["--world", "u-trap", "--max-turn-rate", "7"], "max_turn_rate must be <= pi / dt"),
    (["--world", "u-trap", "--dt", "0"], "dt"),
    (["--world", "u-trap", "--dt", "20", "--max-turn-rate", "0.1"],
     "must not exceed the sonar range"),
    (["--world", "u-trap", "--noise", "-0.1"], "noise_std"),
    (["--world", "u-trap", "--noise", "3"], "noise_std must be in [0.0, 2.5]"),
    (["--world", "u-trap", "--max-steps", "0"], ">= 1"),
    (["--world", "u-trap", "--max-steps", "1000000000"], "MiB, more than the limit of 1,024 MiB"),
    (["--world", "u-trap", "--seed", "-1"], "seed"),
    (["--world", "u-trap", "--seed", str(2**63)], "seed"),
    (["--world", "u-trap", "--seed", "x"], "seed"),
    (["--world", "atlantis"], "unknown world"),
    (["--world", "seed003"], "--start"),                                  # no default start
    (["--world", "u-trap", "--start", "1,2"], "3 comma-separated"),
    (["--world", "u-trap", "--navigator", "bug"], "invalid choice"),
    (["--world", "u-trap", "--plot", "out.txt"], ".png"),
    (["--world", "u-trap", "--animate", "out.png"], ".gif"),
])
def test_bad_plan_inputs_exit_2_with_one_line(argv, words, capsys):
    assert main(["plan", "reactive", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err
    assert "Traceback" not in err


def test_missing_and_malformed_world_files_exit_2(tmp_path, capsys):
    assert main(["plan", "reactive", "--world", str(tmp_path / "none.json"), "--start", "1,1,0",
                 "--goal", "2,2"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    bad = tmp_path / "bad.json"
    bad.write_bytes(b'{"world": {"bounds": [0, 0, 1], "obstacles": []}, "start": [0, 0, 0], '
                    b'"goal": [1, 1]}\xff')
    assert main(["plan", "reactive", "--world", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(bad) in err


@pytest.mark.parametrize("argv, words", [
    (["--n", "0"], ">= 1"), (["--seed", "-3"], "seed"),
    (["--navigators", "bug2"], "invalid choice"), (["--noise", "9"], "noise_std"),
    (["--n", "2000000"], "n must be an integer in [1, 1000000]"),
])
def test_bad_bench_inputs_exit_2(argv, words, capsys):
    assert main(["bench", "reactive", *argv, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err

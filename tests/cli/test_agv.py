"""CLI: ``subtask-opt plan agv`` and ``subtask-opt bench agv``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from subtask_opt.cli.app import main


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    return err


def test_plan_paper_scenario_writes_json_and_plot(tmp_path, capsys):
    out, fig = tmp_path / "run.json", tmp_path / "run.png"
    assert main(["plan", "agv", "--scenario", "2-2", "--json", str(out), "--plot", str(fig)]) == 0
    text = capsys.readouterr().out
    assert "2-2: success" in text and "replan" in text
    data = json.loads(out.read_text())
    assert data["outcome"] == "success" and data["delay_s"] > 0
    kinds = [e["kind"] for e in data["events"]]
    assert {"crossing", "wait", "static", "replan", "recovery"} <= set(kinds)
    assert len(data["trajectory"]) == len(data["times"])
    with Image.open(fig) as im:
        assert im.format == "PNG" and im.size[0] > 800


def test_plan_exits_1_on_a_collision(tmp_path, capsys):
    out = tmp_path / "run.json"
    assert main(["plan", "agv", "--scenario", "2-3", "--no-collision-check",
                 "--json", str(out)]) == 1
    assert json.loads(out.read_text())["outcome"] == "collision"
    assert "collision" in capsys.readouterr().out


def test_plan_exits_1_on_a_timeout(tmp_path):
    scen = {"map": ["@@@@@@@@@@", "..........", "@@@@@@@@@@"], "start": [0, 1],
            "goal": [9, 1], "obstacles": [{"path": [[6, 1]]}], "params": {"max_time_s": 20}}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(scen))
    assert main(["plan", "agv", "--scenario", str(path)]) == 1


def test_plan_json_scenario_with_animation_and_drift(tmp_path, capsys):
    scen = {"map": ["........", "........", "........"], "start": [0, 1], "goal": [7, 1],
            "obstacles": [{"path": [[4, 2], [4, 0]], "start_time": 2.5, "speed": 0.5}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(scen))
    gif, out = tmp_path / "run.gif", tmp_path / "run.json"
    assert main(["plan", "agv", "--scenario", str(path), "--animate", str(gif),
                 "--frames", "12", "--drift", "--seed", "4", "--json", str(out)]) == 0
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == 12
    data = json.loads(out.read_text())
    assert data["params"]["drift"] and data["seed"] == 4
    assert "success" in capsys.readouterr().out


def test_bench_writes_the_totals_and_a_plot(tmp_path, capsys):
    out, fig = tmp_path / "bench.json", tmp_path / "bench.png"
    code = main(["bench", "agv", "--n", "3", "--seed", "3", "--workers", "0", "--json", str(out),
                 "--plot", str(fig), "--no-progress"])
    data = json.loads(out.read_text())
    for key in ("runs", "success", "collisions", "timeouts", "mean_delay_s", "min_separation",
                "mean_drift_error", "mean_drift_error_no_check"):
        assert key in data
    assert data["runs"] == 3 and data["drift"]
    assert code == (0 if data["collisions"] + data["timeouts"] == 0 else 1)
    assert "3 runs" in capsys.readouterr().out
    with Image.open(fig) as im:
        assert im.format == "PNG"


def test_bench_is_reproducible(tmp_path):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    for out in (a, b):
        main(["bench", "agv", "--n", "3", "--seed", "11", "--workers", "0", "--json", str(out),
              "--no-progress"])
    da, db = json.loads(a.read_text()), json.loads(b.read_text())
    da.pop("seconds"), db.pop("seconds")
    assert da == db


@pytest.mark.parametrize("argv", [
    ["plan", "agv", "--seed", "-1"],
    ["plan", "agv", "--seed", str(2**63)],
    ["bench", "agv", "--seed", "x"],
    ["bench", "agv", "--n", "0"],
    ["bench", "agv", "--quiet"],
    ["plan", "agv", "--plot", "out.txt"],
])
def test_bad_options_exit_2_with_one_line(argv, capsys):
    assert main(argv) == 2
    _one_line_error(capsys)


def test_bad_inputs_exit_2_with_one_line(tmp_path, capsys):
    assert main(["plan", "agv", "--scenario", "nope"]) == 2
    assert "unknown scenario" in _one_line_error(capsys)

    bad_img = tmp_path / "bad.png"
    bad_img.write_text("not a png")
    scen = tmp_path / "s.json"
    scen.write_text(json.dumps({"image": "bad.png", "start": [0, 0], "goal": [1, 1]}))
    assert main(["plan", "agv", "--scenario", str(scen)]) == 2
    assert "cannot read image" in _one_line_error(capsys)

    img = np.full((40, 40), 255, dtype=np.uint8)
    img[:10, :10] = 0
    Image.fromarray(img).save(tmp_path / "ok.png")
    scen.write_text(json.dumps({"image": "ok.png", "start": [0, 0], "goal": [3, 3]}))
    assert main(["plan", "agv", "--scenario", str(scen)]) == 2
    assert "start (0, 0) is on an obstacle" in _one_line_error(capsys)

    scen.write_text(json.dumps({"image": "ok.png", "start": [1, 1], "goal": [3, 3],
                                "params": {"dt": 1e-9}}))
    assert main(["plan", "agv", "--scenario", str(scen)]) == 2
    assert "steps" in _one_line_error(capsys)

    scen.write_text("[" * 5000 + "]" * 5000)
    assert main(["plan", "agv", "--scenario", str(scen)]) == 2
    assert "deeper" in _one_line_error(capsys)

    assert main(["plan", "agv", "--scenario", str(scen), "--json", str(scen)]) == 2
    assert "also an input" in _one_line_error(capsys)

"""``subtask-opt solve`` for serial arms: the documented command and one-line bad-input errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.cli import main

ROWS = "x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n" \
       "0.42,-0.10,0.35,1,0,-0.3\n0.42,0.10,0.35,1,0,-0.3\n"
SCENE = {"boxes": [{"name": "panel", "center": [0.55, 0.0, 0.28],
                    "half_extents": [0.02, 0.3, 0.2]}]}


@pytest.fixture()
def files(tmp_path: Path) -> dict[str, Path]:
    case = tmp_path / "holes.csv"
    case.write_text(ROWS)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    limits = tmp_path / "limits.json"
    limits.write_text(json.dumps({"acceleration": [3.0] * 6}))
    return {"case": case, "scene": scene, "limits": limits, "dir": tmp_path}


def _base(files: dict[str, Path]) -> list[str]:
    return ["solve", "--robot", "ur5", "--case", str(files["case"]), "--scene",
            str(files["scene"]), "--home", "0,-90,90,-90,-90,0", "--standoff", "0.01",
            "--time-model", "joint", "--seed", "0", "--limits", str(files["limits"])]


def test_documented_command_writes_json_and_trajectory(files, capsys) -> None:
    out_json = files["dir"] / "out.json"
    out_csv = files["dir"] / "out.csv"
    code = main(_base(files) + ["--json", str(out_json), "--trajectory", str(out_csv)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    doc = json.loads(out_json.read_text())
    assert sorted(doc["order"]) == [0, 1, 2, 3]
    assert len(doc["configurations"]) == 4 and len(doc["configurations"][0]) == 6
    np.testing.assert_allclose(doc["report"]["home"], np.radians([0, -90, 90, -90, -90, 0]))
    assert doc["total_time"] == pytest.approx(sum(doc["leg_times"]))
    assert doc["trajectory"]["valid"] is True
    assert doc["report"]["collision_checked"] is True
    assert set(doc["report"]["cpu_s"]) == {"ik", "collision", "matrix", "search", "compile",
                                              "planner"}
    assert doc["robot"] == "ur5" and doc["time_model"] == "joint"
    header = out_csv.read_text().splitlines()[0]
    assert header == "t,q1,q2,q3,q4,q5,q6,dq1,dq2,dq3,dq4,dq5,dq6,x,y,z"
    last_t = float(out_csv.read_text().splitlines()[-1].split(",")[0])
    assert last_t == pytest.approx(doc["total_time"], rel=0.005)


def _bad(files, capsys, argv: list[str], pattern: str) -> None:
    code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    assert pattern in err[0], err[0]


def test_bad_inputs_exit_2_with_one_line(files, capsys) -> None:
    base = _base(files)
    # home outside the limits
    argv = list(base)
    argv[argv.index("--home") + 1] = "0,-400,90,-90,-90,0"
    _bad(files, capsys, argv, "home joint 2")
    # home in collision
    block = files["dir"] / "block.json"
    block.write_text(json.dumps({"boxes": [{"name": "block", "center": [0, 0, 0.4],
                                            "half_extents": [0.3, 0.3, 0.3]}]}))
    argv = list(base)
    argv[argv.index("--scene") + 1] = str(block)
    _bad(files, capsys, argv, "in collision")
    # malformed scene
    broken = files["dir"] / "broken.json"
    broken.write_text('{"boxes": [{"center": [0, 0, 0]}]}')
    argv[argv.index("--scene") + 1] = str(broken)
    _bad(files, capsys, argv, "half_extents")
    # a target with no collision-free configuration
    around = files["dir"] / "around.json"
    around.write_text(json.dumps({"boxes": [{"name": "b", "center": [0.45, -0.15, 0.2],
                                             "half_extents": [0.08, 0.06, 0.08]}]}))
    argv[argv.index("--scene") + 1] = str(around)
    _bad(files, capsys, argv, "no collision-free configuration")
    # CSV with the wrong columns
    wrong = files["dir"] / "wrong.csv"
    wrong.write_text("x,y,z,a\n0.4,0,0.2,1\n")
    argv = list(base)
    argv[argv.index("--case") + 1] = str(wrong)
    _bad(files, capsys, argv, "wrong.csv")
    # unknown tool frame
    _bad(files, capsys, base + ["--tool-frame", "no_such_frame"], "no_such_frame")
    # a model other than joint
    argv = list(base)
    argv[argv.index("--time-model") + 1] = "paper"
    _bad(files, capsys, argv, "joint model only")


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "data"


def test_shipped_panel_example_with_figure_and_view(tmp_path: Path, capsys) -> None:
    """The README's serial-arm command on the shipped files, with --plot and --view."""
    out = {k: tmp_path / f"out.{k}" for k in ("json", "csv", "png", "html")}
    code = main(["solve", "--robot", "ur5", "--case", str(EXAMPLES / "ur5_panel.csv"),
                 "--scene", str(EXAMPLES / "ur5_panel_scene.json"), "--home",
                 "0,-90,90,-90,-90,0", "--standoff", "0.01", "--time-model", "joint",
                 "--seed", "0", "--json", str(out["json"]), "--trajectory", str(out["csv"]),
                 "--plot", str(out["png"]), "--view", str(out["html"])])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    doc = json.loads(out["json"].read_text())
    holes = (EXAMPLES / "ur5_panel.csv").read_text().strip().count("\n")  # rows after the header
    assert sorted(doc["order"]) == list(range(holes))
    assert doc["trajectory"]["valid"] is True
    assert out["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = out["html"].read_text()
    assert "<script" in page and 'src="http' not in page  # self-contained: works offline


@pytest.mark.parametrize("flag,value", [("--view", "out.htm"), ("--animate", "out.gif")])
def test_serial_output_flags_refused_in_one_line(files, capsys, flag, value) -> None:
    _bad(files, capsys, _base(files) + [flag, str(files["dir"] / value)], flag.lstrip("-"))


def test_legs_that_do_not_fit_in_memory_are_refused_before_any_ik(files, capsys,
                                                                 monkeypatch) -> None:
    """The one size limit is memory, checked before the IK starts: one line, exit 2."""
    from subtask_opt.arm import sparse_legs
    from subtask_opt.kinematics import ik

    monkeypatch.setattr(sparse_legs, "available_memory", lambda: 1000)

    def no_ik(*args, **kwargs):
        raise AssertionError("the IK ran before the memory check")

    monkeypatch.setattr(ik.IKSolver, "solve_targets", no_ik)
    code = main(_base(files) + ["--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "GiB" in err[0] and "memory available" in err[0]


@pytest.mark.parametrize("robot", ["ur5", "planar_2r"])
def test_a_time_limit_that_runs_out_while_building_fails_in_one_line(files, robot,
                                                                      capsys) -> None:
    # the limit bounds the problem's construction too: it runs out before any search
    args = (_base(files) if robot == "ur5" else
            ["solve", "--case", "random30", "--seed", "0"]) + ["--time-limit", "1e-9",
                                                              "--no-progress"]
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and "the time limit of 1e-09 s ran out" in err[0], err

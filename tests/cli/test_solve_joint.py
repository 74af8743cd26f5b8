"""`subtask-opt solve` with the joint-aware models: configurations, trajectories, animation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from subtask_opt.arm.tasks import builtin_case
from subtask_opt.cli.app import main
from subtask_opt.kinematics.planar import load_planar_arm
from tests.conftest import REDUCED


def _case(tmp_path, case: str, robot: str, keep) -> tuple[str, int]:
    """``case`` as is, or under the coverage run (``REDUCED``) a CSV of the subtasks
    ``keep(points, arm)`` selects: the same command on a few subtasks. Returns the
    ``--case`` argument and the number of subtasks."""
    if not REDUCED:
        return case, len(builtin_case(case, load_planar_arm(robot)).points)
    arm = load_planar_arm(robot)
    pts = builtin_case(case, arm).points
    pts = pts[keep(pts, arm)]
    csv = tmp_path / f"{case}_reduced.csv"
    csv.write_text("x,y\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in pts))
    return str(csv), len(pts)


def test_joint_model_chooses_configurations_and_writes_trajectory(tmp_path, capsys,
                                                                  monkeypatch):
    if REDUCED:  # drawing 150 GIF frames is most of the time; 4 frames take the same lines
        import functools

        from subtask_opt.plotting import trajectory as plot_trajectory

        monkeypatch.setattr(plot_trajectory, "animate_tour",
                            functools.partial(plot_trajectory.animate_tour, max_frames=4))
    out_json = tmp_path / "r.json"
    out_csv = tmp_path / "t.csv"
    out_gif = tmp_path / "t.gif"
    case, n = _case(tmp_path, "square20", "asr_twodof", lambda pts, arm: slice(0, 5))
    code = main(["solve", "--case", case, "--robot", "asr_twodof", "--time-model",
                 "joint", "--seed", "1", "--json", str(out_json), "--trajectory", str(out_csv),
                 "--dt", "0.02", "--animate", str(out_gif)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "elbow:" in printed and "move" in printed and "trajectory valid" in printed
    data = json.loads(out_json.read_text())
    report = data["report"]
    assert report["configurations_mode"] == "optimize"
    assert len(report["configurations"]) == n and set(report["configurations"]) <= {0, 1}
    assert report["leg_moves"] == ["joint"] * n
    order = np.array(data["order"])
    m = np.array(data["matrix"])
    assert data["total_time"] == pytest.approx(m[order, np.roll(order, -1)].sum())
    table = np.loadtxt(out_csv, delimiter=",", skiprows=1)
    assert out_csv.read_text().startswith("t,q1,q2,dq1,dq2,x,y\n")
    assert table[-1, 0] == pytest.approx(data["total_time"], rel=1e-6)
    assert np.allclose(table[0, 5:], data["points"][order[0]], atol=1e-9)
    assert out_gif.read_bytes()[:3] == b"GIF"
    assert data["trajectory"]["valid"] and data["trajectory"]["max_velocity_ratio"] <= 1.001
    assert data["trajectory"]["duration"] == pytest.approx(data["total_time"], rel=1e-6)


def _disc_crossing_csv(tmp_path):
    """Three asr_twodof subtasks; the line between the first two crosses the inner disc."""
    arm = load_planar_arm("asr_twodof")
    bx, by = arm.base_xy
    r = 0.5 * (arm.r_min + arm.r_max)
    csv = tmp_path / "through_the_disc.csv"
    csv.write_text(f"x,y\n{bx - r},{by}\n{bx + r},{by}\n{bx},{by + r}\n")
    return csv


def test_line_model_table_shows_infeasible_lines_and_elbow_changes(tmp_path, capsys):
    out_json = tmp_path / "r.json"
    assert main(["solve", "--case", str(_disc_crossing_csv(tmp_path)), "--robot", "asr_twodof",
                 "--time-model", "line", "--json", str(out_json)]) == 0
    printed = capsys.readouterr().out
    assert "line infeasible (leaves the reachable annulus)" in printed
    data = json.loads(out_json.read_text())
    report = data["report"]
    not_straight = [leg for leg in report["infeasible_legs"] if "line infeasible" in leg["reason"]]
    assert not_straight and report["diagnostics"]["all_pairs_lines"]["fallback"] == "joint"
    assert "joint" in report["leg_moves"] and "line" in report["leg_moves"]
    # planar_2r's random30 has subtasks only elbow-up reaches: the fixed branch must change
    # (reduced: the first subtask only elbow-up reaches, the first only elbow-down
    # reaches and the first both reach)
    def one_of_each(pts, arm):
        q = arm.ik(pts)
        down, up = np.isfinite(q[:, 0]).all(axis=1), np.isfinite(q[:, 1]).all(axis=1)
        return [np.flatnonzero(m)[0] for m in (up & ~down, down & ~up, up & down)]

    case, _ = _case(tmp_path, "random30", "planar_2r", one_of_each)
    assert main(["solve", "--case", case, "--time-model", "line", "--configurations",
                 "fixed"]) == 0
    printed = capsys.readouterr().out
    assert "elbow change" in printed and ("u->d" in printed or "d->u" in printed)


def test_cartesian_model_trajectory_reports_the_real_time(tmp_path, capsys):
    out_csv = tmp_path / "t.csv"
    assert main(["solve", "--case", "square20", "--robot", "asr_twodof", "--time-model",
                 "trapezoid", "--trajectory", str(out_csv)]) == 0
    printed = capsys.readouterr().out
    assert "note: the trapezoid model promised" in printed and "trajectory valid" in printed


@pytest.mark.parametrize(("extra", "needle"), [
    (["--time-model", "joint", "--trajectory", "OUT", "--dt", "0"], "dt"),
    (["--time-model", "joint", "--trajectory", "OUT", "--dt", "-1"], "dt"),
    (["--time-model", "trapezoid", "--configurations", "optimize"], "joint or line"),
    (["--time-model", "line", "--line-fallback", "hop"], "hop"),
    (["--time-model", "joint", "--animate", "OUT.mp4"], ".gif"),
])
def test_user_mistakes_print_one_line_and_exit_2(extra, needle, tmp_path, capsys):
    argv = ["solve", "--case", "square20", *[str(tmp_path / "x.csv") if a == "OUT" else
                                              str(tmp_path / "x.mp4") if a == "OUT.mp4" else a
                                              for a in extra]]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert needle in err


def test_excluded_lines_without_a_tour_and_unreachable_subtasks_exit_2(tmp_path, capsys):
    arm = load_planar_arm("asr_twodof")
    bx, by = arm.base_xy
    r = 0.5 * (arm.r_min + arm.r_max)
    assert main(["solve", "--case", str(_disc_crossing_csv(tmp_path)), "--robot", "asr_twodof",
                 "--time-model", "line", "--line-fallback", "exclude"]) == 1  # ran, no tour
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "excluded straight lines" in err
    bad = tmp_path / "unreachable.csv"
    bad.write_text(f"x,y\n{bx + r},{by}\n{bx},{by + r}\n{bx + 0.001},{by}\n")
    assert main(["solve", "--case", str(bad), "--robot", "asr_twodof", "--time-model",
                 "joint"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "subtask 2" in err


def test_robot_without_limits_exits_2(tmp_path, capsys):
    from importlib.resources import files

    urdf = tmp_path / "bare.urdf"  # planar_2r's URDF without its limits file
    urdf.write_text((files("subtask_opt.robots") / "planar_2r.urdf").read_text())
    assert main(["solve", "--case", "square20", "--robot", str(urdf), "--time-model",
                 "joint"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "acceleration" in err

"""CLI: plan grid, bench grid, bench movingai, and their bad inputs."""

from __future__ import annotations

import json

import pytest

from subtask_opt.cli.app import main


def _one_line_error(capsys, needle):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err, err


@pytest.mark.parametrize("planner", ["dt", "dt-octile", "mdt", "ga", "vff", "vfh"])
def test_plan_grid_json(tmp_path, capsys, planner):
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", "open", "--planner", planner, "--seed", "1",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    for key in ("length", "path", "success", "turns", "runtime_s"):
        assert key in data
    assert data["success"] and data["path"][0] == [3.0, 7.0]
    assert planner in capsys.readouterr().out


def test_plan_grid_file_map_and_plot(tmp_path, movingai_dir):
    plot = tmp_path / "p.png"
    assert main(["plan", "grid", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--start", "1,11", "--goal", "4,12", "--planner", "dt-octile",
                 "--plot", str(plot)]) == 0
    assert plot.stat().st_size > 0
    txt = tmp_path / "m.txt"
    txt.write_text("....\n.##.\n....\n")
    assert main(["plan", "grid", "--map", str(txt), "--start", "0,0", "--goal", "3,2"]) == 0


def test_plan_grid_no_path_is_success_false(tmp_path):
    txt = tmp_path / "m.txt"
    txt.write_text(".#.\n##.\n...\n")
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", str(txt), "--start", "0,0", "--goal", "2,2",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["success"] is False and "not reachable" in data["message"]


@pytest.mark.parametrize("argv, needle", [
    (["--map", "open", "--planner", "astar"], "--planner"),
    (["--map", "nowhere.map"], "neither a built-in map"),
    (["--map", "open", "--start", "0,0"], "start (0, 0)"),
    (["--map", "open", "--goal", "99,1"], "outside"),
    (["--map", "open", "--goal", "1.5,1"], "goal must be a cell"),
])
def test_plan_grid_bad_input(capsys, argv, needle):
    assert main(["plan", "grid", *argv]) == 2
    _one_line_error(capsys, needle)


def test_plan_grid_malformed_and_needs_cells(tmp_path, capsys):
    bad = tmp_path / "bad.map"
    bad.write_text("type octile\nheight 1\nwidth 2\nmap\n.x\n")
    assert main(["plan", "grid", "--map", str(bad), "--start", "0,0", "--goal", "1,0"]) == 2
    _one_line_error(capsys, "unknown map character 'x'")
    ok = tmp_path / "ok.txt"
    ok.write_text("..\n")
    assert main(["plan", "grid", "--map", str(ok)]) == 2
    _one_line_error(capsys, "--start and --goal are required")


def test_bench_movingai(tmp_path, capsys, movingai_dir):
    out = tmp_path / "m.json"
    assert main(["bench", "movingai", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--scen", str(movingai_dir / "scenarios" / "arena.map.scen"),
                 "--json", str(out), "--no-progress"]) == 0
    data = json.loads(out.read_text())
    assert data["rows"] == 160 and data["mismatches"] == 0
    assert data["max_abs_error"] < 1e-3 and data["seconds"] >= 0
    assert "0 mismatches" in capsys.readouterr().out


def test_bench_movingai_wrong_pair(capsys, movingai_dir):
    assert main(["bench", "movingai", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--scen", str(movingai_dir / "scenarios" / "den312d.map.scen"),
                 "--no-progress"]) == 2
    _one_line_error(capsys, "65x81")


def test_bench_grid(tmp_path, capsys):
    out = tmp_path / "t.json"
    plot = tmp_path / "t.png"
    assert main(["bench", "grid", "--repeats", "1", "--json", str(out), "--plot", str(plot),
                 "--no-progress"]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert len(rows) == 6 * 6
    mdt = {r["map"]: r["length"] for r in rows if r["planner"] == "mdt"}
    ga = {r["map"]: r["length"] for r in rows if r["planner"] == "ga"}
    assert all(ga[m] <= 1.05 * mdt[m] for m in mdt)
    assert "cluttered" in capsys.readouterr().out and plot.stat().st_size > 0

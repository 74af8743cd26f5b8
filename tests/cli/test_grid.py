"""CLI: plan grid, bench grid, bench movingai: outputs, exit codes 0/1/2, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from subtask_opt.cli.app import main
from subtask_opt.planners.base import planners
from subtask_opt.planners.grid.distance_transform import MDTParams, plan_mdt
from subtask_opt.planners.grid.maps import thesis_case
from tests.conftest import REDUCED
from tests.planners.grid.test_fig24 import PRINTED


def _one_line_error(capsys, needle):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err, err
    assert "Traceback" not in err


@pytest.mark.parametrize("planner", list(planners("grid")))
def test_plan_grid_json_every_planner(tmp_path, capsys, planner):
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", "open", "--planner", planner, "--seed", "1",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["success"] and data["outcome"] == "success"
    assert data["path"][0] == [3.0, 7.0] and data["map"] == "open"
    assert isinstance(data["info"], dict) and data["length"] > 0
    assert data["seed"] == (1 if planners("grid")[planner].stochastic else None)
    assert planner in capsys.readouterr().out


def test_fig24_field_is_the_printed_one(tmp_path):
    out = tmp_path / "f.json"
    assert main(["plan", "grid", "--map", "fig2.4", "--start", "2,7", "--goal", "12,1",
                 "--planner", "dt", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["field"] == PRINTED  # side step 3, diagonal 4, obstacles null


def test_plan_grid_file_maps_and_plot(tmp_path, movingai_dir):
    plot = tmp_path / "p.png"
    assert main(["plan", "grid", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--start", "1,11", "--goal", "4,12", "--planner", "dt-octile",
                 "--plot", str(plot)]) == 0
    assert plot.read_bytes().startswith(b"\x89PNG")
    txt = tmp_path / "m.txt"
    txt.write_text("....\n.##.\n....\n")
    assert main(["plan", "grid", "--map", str(txt), "--start", "0,0", "--goal", "3,2"]) == 0
    img = np.full((3, 4), 255, dtype=np.uint8)
    img[1, 1:3] = 0
    Image.fromarray(img).save(tmp_path / "m.dat", format="PNG")  # read by content
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", str(tmp_path / "m.dat"), "--start", "0,1",
                 "--goal", "3,1", "--planner", "dt-octile", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["path"][0] == [0.0, 1.0]


def test_plan_grid_no_path_exits_1(tmp_path, capsys):
    txt = tmp_path / "m.txt"
    txt.write_text(".#.\n##.\n...\n")
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", str(txt), "--start", "0,0", "--goal", "2,2",
                 "--json", str(out)]) == 1
    data = json.loads(out.read_text())
    assert data["success"] is False and data["outcome"] == "no_path"
    assert "not reachable" in data["message"]


@pytest.mark.parametrize("planner", ["vff", "vfh"])
def test_local_planner_in_corner_gap_exits_1(tmp_path, planner):
    gap = tmp_path / "gap.txt"
    gap.write_text("@.\n.@\n")  # free bottom-left and top-right, blocked corner gap
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", str(gap), "--start", "0,1", "--goal", "1,0",
                 "--planner", planner, "--json", str(out)]) == 1
    data = json.loads(out.read_text())
    assert data["outcome"] == "collision"
    assert isinstance(data["info"]["trajectory"], list)


def test_stall_exits_1_and_plots_the_drive(tmp_path):
    plot = tmp_path / "trap.png"
    assert main(["plan", "grid", "--map", "trap", "--planner", "vff", "--plot", str(plot)]) == 1
    assert plot.stat().st_size > 0


def test_start_equals_goal(tmp_path):
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", "open", "--goal", "3,7", "--planner", "mdt",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["success"] and data["length"] == 0.0


def test_ga_stopping_options(tmp_path):
    out = tmp_path / "r.json"
    assert main(["plan", "grid", "--map", "walls", "--planner", "ga", "--seed", "4",
                 "--generations", "6", "--json", str(out)]) == 0
    assert len(json.loads(out.read_text())["history"]["best_cost"]) == 6


@pytest.mark.parametrize("argv, needle", [
    (["--map", "open", "--planner", "astar"], "invalid choice"),
    (["--map", "nowhere.map"], "neither a built-in map"),
    (["--map", "open", "--start", "0,0"], "start (0, 0)"),
    (["--map", "open", "--goal", "99,1"], "outside"),
    (["--map", "open", "--goal", "1.5,1"], "goal must be a cell"),
    (["--map", "open", "--seed", "-1"], "seed"),
    (["--map", "open", "--seed", str(2**63)], "seed"),
    (["--map", "open", "--plot", "x.txt"], "must end in"),
    (["--map", "open", "--generations", "0"], ">= 1"),
])
def test_plan_grid_bad_input(capsys, argv, needle):
    assert main(["plan", "grid", *argv]) == 2
    _one_line_error(capsys, needle)


def test_plan_grid_malformed_files(tmp_path, capsys):
    bad = tmp_path / "bad.map"
    bad.write_text("type octile\nheight 1\nwidth 2\nmap\n.x\n")
    assert main(["plan", "grid", "--map", str(bad), "--start", "0,0", "--goal", "1,0"]) == 2
    _one_line_error(capsys, "unknown map character 'x'")
    binary = tmp_path / "bin.map"
    binary.write_bytes(b"\x00\xff\xfe\x01")
    assert main(["plan", "grid", "--map", str(binary), "--start", "0,0", "--goal", "1,0"]) == 2
    _one_line_error(capsys, "not a text file")
    ok = tmp_path / "ok.txt"
    ok.write_text("..\n")
    assert main(["plan", "grid", "--map", str(ok)]) == 2
    _one_line_error(capsys, "--start and --goal are required")
    assert main(["plan", "grid", "--map", str(ok), "--start", "0,0", "--goal", "1,0",
                 "--json", str(ok)]) == 2
    _one_line_error(capsys, "also an input file")


def test_help_lists_registered_planners(capsys):
    assert main(["plan", "grid", "--help"]) == 0
    out = capsys.readouterr().out
    flat = "".join(out.split())  # argparse wraps lines (and may break at hyphens)
    for name, info in planners("grid").items():
        assert name in out and "".join(info.description.split()) in flat


def test_bench_movingai(tmp_path, capsys, movingai_dir):
    out = tmp_path / "m.json"
    plot = tmp_path / "m.png"
    scen, rows = movingai_dir / "scenarios" / "arena.map.scen", 160
    if REDUCED:  # every 20th row of the file: the same command on 8 rows
        lines = scen.read_text().splitlines()
        scen, rows = tmp_path / "arena.map.scen", 8
        scen.write_text("\n".join([lines[0], *lines[1::20]]) + "\n")
    assert main(["bench", "movingai", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--scen", str(scen), "--json", str(out), "--plot", str(plot),
                 "--no-progress"]) == 0
    data = json.loads(out.read_text())
    assert data["rows"] == rows and data["mismatches"] == 0
    assert data["max_abs_error"] < 1e-3 and data["seconds"] >= 0
    assert "0 mismatches" in capsys.readouterr().out and plot.stat().st_size > 0


def test_bench_movingai_mismatch_exits_1(tmp_path):
    m = tmp_path / "m.map"
    m.write_text("type octile\nheight 1\nwidth 3\nmap\n...\n")
    s = tmp_path / "s.scen"
    s.write_text("version 1\n0\tm.map\t3\t1\t0\t0\t2\t0\t5\n")  # the optimum is 2, not 5
    assert main(["bench", "movingai", "--map", str(m), "--scen", str(s), "--no-progress"]) == 1


def test_bench_movingai_wrong_pair(capsys, movingai_dir):
    assert main(["bench", "movingai", "--map", str(movingai_dir / "maps" / "arena.map"),
                 "--scen", str(movingai_dir / "scenarios" / "den312d.map.scen"),
                 "--no-progress"]) == 2
    _one_line_error(capsys, "65x81")


def test_bench_grid(tmp_path, capsys):
    out = tmp_path / "t.json"
    plot = tmp_path / "t.png"
    assert main(["bench", "grid", "--repeats", "1", "--seed", "0", "--json", str(out),
                 "--plot", str(plot), "--no-progress"]) == 0
    data = json.loads(out.read_text())
    rows = data["rows"]
    assert data["planners"] == list(planners("grid"))
    assert len(rows) == 6 * len(planners("grid"))
    mdt = {r["map"]: r["length"] for r in rows if r["planner"] == "mdt"}
    dt = {r["map"]: r["length"] for r in rows if r["planner"] == "dt"}
    ga = {r["map"]: r["length"] for r in rows if r["planner"] == "ga"}
    # one corner rule per comparison: DT and MDT take the thesis', the GA closed squares
    cut = {r["planner"]: r["corner_cutting"] for r in rows}
    assert cut["dt"] is cut["mdt"] is True and cut["ga"] is False
    assert all(mdt[m] <= dt[m] + 1e-9 for m in mdt)
    closed = {m: plan_mdt(c.world, c.start, c.goal,
                          params=MDTParams(corner_cutting=False)).length
              for m, c in ((m, thesis_case(m)) for m in mdt)}
    assert all(ga[m] <= 1.05 * closed[m] for m in mdt)
    assert "cluttered" in capsys.readouterr().out and plot.stat().st_size > 0

"""`subtask-opt tsp`: tour, bound and gap, JSON and figure, one-line errors with exit 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from subtask_opt.cli.app import main
from subtask_opt.tour.tsplib import parse_tsplib
from tests.conftest import SHARED_DATA
from tests.tour.test_tsplib import BURMA14, BURMA14_OPT, GR17, GR17_OPT


@pytest.fixture()
def gr17(tmp_path):
    path = tmp_path / "gr17.tsp"
    path.write_text(GR17)
    return path


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "Traceback" not in err
    return err


def test_tsp_prints_length_bound_gap_and_writes_json(gr17, tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(["tsp", str(gr17), "--time-limit", "5", "--seed", "2", "--json", str(out),
                 "--no-progress"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "tour length" in printed and "lower bound" in printed and "gap" in printed
    data = json.loads(out.read_text())
    for key in ("order", "length", "lower_bound", "gap_bound", "runtime_s"):
        assert key in data
    matrix = parse_tsplib(GR17).matrix
    order = np.array(data["order"])
    assert sorted(order) == list(range(17))
    assert data["length"] == matrix[order, np.roll(order, -1)].sum()
    assert data["lower_bound"] <= GR17_OPT <= data["length"]
    assert data["gap_bound"] == pytest.approx(
        (data["length"] - data["lower_bound"]) / data["lower_bound"])
    assert str(data["length"]) in printed


def test_tsp_plot_of_a_geo_instance(tmp_path, capsys):
    pytest.importorskip("subtask_opt.plotting.tsp")
    path = tmp_path / "burma14.tsp"
    path.write_text(BURMA14)
    png = tmp_path / "tour.png"
    assert main(["tsp", str(path), "--time-limit", "3", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
    printed = capsys.readouterr().out
    assert f"wrote {png}" in printed
    assert int(printed.split("tour length")[1].split()[0]) >= BURMA14_OPT


def test_tsp_on_shared_berlin52(capsys):
    path = SHARED_DATA / "tsplib" / "berlin52.tsp"
    if not path.is_file():
        pytest.skip(f"shared TSPLIB data not found at {path}")
    assert main(["tsp", str(path), "--time-limit", "2"]) == 0
    printed = capsys.readouterr().out
    length = int(printed.split("tour length")[1].split()[0])
    bound = float(printed.split("lower bound")[1].split()[0])
    assert bound <= 7542 <= length


@pytest.mark.parametrize("limit", ["0", "-1", "nan", "inf", "soon"])
def test_bad_time_limit_exits_2(gr17, limit, capsys):
    assert main(["tsp", str(gr17), "--time-limit", limit]) == 2
    assert limit in _one_line(capsys)


def test_bad_seed_exits_2(gr17, capsys):
    assert main(["tsp", str(gr17), "--seed", "-1"]) == 2
    assert "-1" in _one_line(capsys)


@pytest.mark.parametrize(("content", "needle"), [
    ("NAME: x\nTYPE: TSP\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n1 0 0\n",
     "line 4: NODE_COORD_SECTION before DIMENSION"),
    ("NAME: x\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 0 x\n"
     "3 1 1\n", "line 6: coordinates must be numbers"),
    ("NAME: x\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 0 1\n"
     "3 1 1\nEOF\n", "line 8: the section ends after 3 of 4 nodes"),
    ("", "DIMENSION is missing"),
])
def test_malformed_file_exits_2_naming_the_line(tmp_path, content, needle, capsys):
    path = tmp_path / "bad.tsp"
    path.write_text(content)
    assert main(["tsp", str(path)]) == 2
    err = _one_line(capsys)
    assert needle in err and "bad.tsp" in err


def test_missing_file_and_output_over_input_exit_2(gr17, tmp_path, capsys):
    assert main(["tsp", str(tmp_path / "nowhere.tsp")]) == 2
    assert "nowhere.tsp" in _one_line(capsys)
    assert main(["tsp", str(gr17), "--json", str(gr17)]) == 2
    assert "also an input" in _one_line(capsys)


def test_plot_without_coordinates_exits_2_before_solving(gr17, tmp_path, capsys):
    assert main(["tsp", str(gr17), "--plot", str(tmp_path / "x.png")]) == 2
    assert "needs node coordinates" in _one_line(capsys)
    assert not (tmp_path / "x.png").exists()

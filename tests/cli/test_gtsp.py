"""`subtask-opt gtsp`: cost, bound and gap; JSON in the file's numbering; one-line errors
naming the line, exit 2; the same seed writes the same JSON in any process."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from subtask_opt.cli.app import main
from tests.cli.test_same_bytes import _strip
from tests.conftest import REDUCED

# 8 sets of 1-3 vertices (18 vertices), EUC_2D, vertex ids scattered over the sets
POINTS = [(5, 5), (60, 8), (12, 70), (90, 90), (40, 40), (75, 30), (20, 25), (55, 85),
          (95, 10), (8, 45), (33, 90), (70, 60), (50, 15), (85, 45), (15, 95), (45, 65),
          (65, 95), (28, 5)]
SETS = [[1, 9], [2, 13, 18], [3, 15], [4, 17, 12], [5, 16], [6, 14], [7, 10], [8, 11]]


def _file(tmp_path, name="t.gtsp"):
    nodes = "".join(f"{i + 1} {x} {y}\n" for i, (x, y) in enumerate(POINTS))
    sets = "".join(f"{k + 1} {' '.join(map(str, s))} -1\n" for k, s in enumerate(SETS))
    path = tmp_path / name
    path.write_text(f"NAME : t\nTYPE : GTSP\nDIMENSION : {len(POINTS)}\nGTSP_SETS : "
                    f"{len(SETS)}\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n{nodes}"
                    f"GTSP_SET_SECTION\n{sets}EOF\n")
    return path


def _nint(a, b):
    return int(np.floor(np.hypot(a[0] - b[0], a[1] - b[1]) + 0.5))


def test_gtsp_prints_cost_bound_gap_and_writes_json(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(["gtsp", str(_file(tmp_path)), "--time-limit", "5", "--seed", "3", "--json",
                 str(out), "--no-progress", "--certify"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "cost" in printed and "lower bound" in printed and "gap" in printed
    data = json.loads(out.read_text())
    for key in ("tour", "cost", "lower_bound", "runtime_s", "seed"):
        assert key in data
    tour = data["tour"]  # 1-based vertex ids, one per set
    owner = {v: k for k, s in enumerate(SETS) for v in s}
    assert sorted(owner[v] for v in tour) == list(range(len(SETS)))
    cost = sum(_nint(POINTS[a - 1], POINTS[b - 1])
               for a, b in zip(tour, tour[1:] + tour[:1], strict=True))
    assert data["cost"] == cost
    assert data["lower_bound"] <= cost
    assert data["seed"] == 3
    assert data["certified"] == "optimal (proven)"


def test_gtsp_plot(tmp_path):
    out = tmp_path / "t.png"
    assert main(["gtsp", str(_file(tmp_path)), "--time-limit", "2", "--plot", str(out),
                 "--no-progress"]) == 0
    assert out.stat().st_size > 1000


@pytest.mark.parametrize("change, line", [
    (lambda t: t.replace("8 8 11 -1", "8 8 11"), 33),
    (lambda t: t.replace("3 3 15 -1", "3 3 15 99 -1"), 28),
    (lambda t: t.replace("7 20 25", "7 20"), 13),
    (lambda t: t.replace("GTSP_SETS : 8", "GTSP_SETS : eight"), 4),
])
def test_malformed_file_is_one_line_exit_2(tmp_path, capsys, change, line):
    path = _file(tmp_path)
    path.write_text(change(path.read_text()))
    assert main(["gtsp", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert f"line {line}:" in err and "expected" in err, err


def test_missing_file_exits_2(tmp_path, capsys):
    assert main(["gtsp", str(tmp_path / "none.gtsp")]) == 2
    assert "none.gtsp" in capsys.readouterr().err


@pytest.mark.skipif(REDUCED, reason="coverage run: subprocesses are not measured")
def test_same_seed_same_json_bytes_across_processes(tmp_path):
    path = _file(tmp_path)
    texts = []
    for hash_seed in ("1", "2"):
        out = tmp_path / f"{hash_seed}.json"
        env = {**os.environ, "PYTHONHASHSEED": hash_seed, "MPLBACKEND": "Agg"}
        argv = ["gtsp", str(path), "--seed", "7", "--time-limit", "60", "--json", str(out),
                "--no-progress"]
        code = f"import sys; from subtask_opt.cli import main; sys.exit(main({argv!r}))"
        proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        texts.append(json.dumps(_strip(json.loads(out.read_text())), indent=2))
    assert texts[0] == texts[1]

"""The README's Python blocks run as written, and API and CLI share one set of defaults."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from subtask_opt import solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import load_subtasks
from subtask_opt.cli import main
from subtask_opt.kinematics.planar import load_planar_arm

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_the_readme_has_python_examples():
    assert _python_blocks()


@pytest.mark.parametrize("index", range(len(_python_blocks())))
def test_readme_python_block_runs(index, tmp_path, monkeypatch):
    import shutil

    # the blocks read the repository's example data by relative path, and write nothing
    # into the repository
    shutil.copytree(README.parent / "examples" / "data", tmp_path / "examples" / "data")
    monkeypatch.chdir(tmp_path)
    exec(compile(_python_blocks()[index], f"README block {index}", "exec"), {})


def test_api_and_cli_defaults_give_the_same_total_time(tmp_path, capsys):
    csv = tmp_path / "part.csv"
    csv.write_text("x,y\n0.30,0.10\n0.35,0.22\n0.25,0.30\n0.40,-0.12\n0.21,-0.20\n0.45,0.05\n"
                   "0.32,-0.25\n0.28,0.18\n")
    out = tmp_path / "r.json"
    assert main(["solve", "--case", str(csv), "--json", str(out)]) == 0
    cli = json.loads(out.read_text())
    arm = load_planar_arm()
    api = solve(PlanarProblem(load_subtasks(csv), arm))
    assert cli["total_time"] == api.total_time
    assert cli["order"] == api.order.tolist()
    assert cli["report"]["time_model"] == api.report.time_model
    assert cli["report"]["configurations_mode"] == api.report.configurations_mode

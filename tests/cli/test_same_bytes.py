"""Same seed, same bytes: a command's JSON (timings aside) does not depend on the process.

Each command runs in two fresh processes with different ``PYTHONHASHSEED`` (set
iteration order and hash-based choices would show up as different bytes).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REDUCED

TIMING = re.compile(r"(runtime|seconds|_ms$|^time_s$|compile|elapsed|wall|^cpu)",
                    re.IGNORECASE)
DATA = Path(__file__).resolve().parents[2] / "examples" / "data"

COMMANDS = {
    "solve": ["solve", "--case", "random30", "--seed", "3"],
    "plan grid ga": ["plan", "grid", "--map", "rooms", "--planner", "ga", "--seed", "5"],
    "plan polygon pso": ["plan", "polygon", "--start", "20,20", "--goal", "320,320",
                         "--planner", "pso", "--seed", "2"],
    "tsp": ["tsp", "TSP", "--seed", "1"],
    "solve ur5": ["solve", "--robot", "ur5", "--case", str(DATA / "ur5_panel.csv"), "--scene",
                  str(DATA / "ur5_panel_scene.json"), "--home", "0,-90,90,-90,-90,0",
                  "--tour", "open", "--precedence", "PRECEDENCE", "--seed", "3"],
}


def _strip(value: object) -> object:
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if not TIMING.search(str(k))}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


# Under `make coverage` the subprocesses run the kernels as Python (minutes each) and
# coverage does not measure them: the test adds no covered line there; the same commands
# run in-process in tests/cli/test_solve.py, test_grid.py, test_polygon.py and test_tsp.py.
@pytest.mark.skipif(REDUCED, reason="coverage run: subprocesses are not measured")
@pytest.mark.parametrize("name", list(COMMANDS))
def test_json_is_identical_across_processes(name, tmp_path):
    tsp = tmp_path / "ring.tsp"
    coords = "".join(f"{i + 1} {37 * (i * 7 % 13)} {53 * (i * 5 % 11)}\n" for i in range(20))
    tsp.write_text("NAME: ring\nTYPE: TSP\nDIMENSION: 20\nEDGE_WEIGHT_TYPE: EUC_2D\n"
                   f"NODE_COORD_SECTION\n{coords}EOF\n")
    precedence = tmp_path / "before.txt"
    precedence.write_text("4,1\n7,2\n")
    argv = [str(tsp) if a == "TSP" else str(precedence) if a == "PRECEDENCE" else a
            for a in COMMANDS[name]]
    outputs = []
    for hash_seed in ("1", "2"):
        out = tmp_path / f"{hash_seed}.json"
        env = {**os.environ, "PYTHONHASHSEED": hash_seed, "MPLBACKEND": "Agg"}
        code = ("import sys; from subtask_opt.cli import main; "
                f"sys.exit(main({[*argv, '--json', str(out)]!r}))")
        proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        outputs.append(_strip(json.loads(out.read_text())))
    assert outputs[0] == outputs[1]

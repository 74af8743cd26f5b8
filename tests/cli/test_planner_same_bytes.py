"""Same seed, same bytes for the planners: ``plan grid``, ``plan polygon``,
``plan reactive`` and ``plan agv`` write the same ``--json`` (timings aside) in
fresh processes with different ``PYTHONHASHSEED``.

Every registered planner of a family runs (the stochastic ones with a seed, the
iterative ones with a short stop), on maps and scenarios that exercise their
branches: the GA and PSO searches, sensor noise, the AGV's re-plan, sidestep,
drift and check points. One process per family and hash seed runs the
family's commands in turn (set iteration order or hash-based choices would
show up as different bytes); the JSON of each command is compared after the
timing keys are removed, as serialised text, so key order counts too.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from subtask_opt.planners import polygon as _polygon  # noqa: F401  (registers the family)
from subtask_opt.planners.base import planners
from tests.conftest import REDUCED

HASH_SEEDS = ("1", "2", "4242")
WALL_CLOCK = {"runtime_s"}
"""The only wall-clock keys of the planners' JSON (``time_s`` of the reactive and
AGV runs is simulated time, a result, and stays in the comparison)."""


def _strip(value: object) -> object:
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if k not in WALL_CLOCK}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def _family(family: str, places: dict[bool, tuple[list[str], ...]], seed: str,
            iterations: list[str]) -> list[list[str]]:
    """One command per planner of ``family`` and place (``places[stochastic]``: the
    arguments that say where), seeded when stochastic, shortened when iterative."""
    out = []
    for name, info in planners(family).items():
        for where in places[info.stochastic]:
            argv = ["plan", family, *where, "--planner", name]
            if info.stochastic:
                argv += ["--seed", seed]
            if info.iterative:
                argv += iterations
            out.append(argv)
    return out


def _grid() -> list[list[str]]:
    import subtask_opt.planners.grid  # noqa: F401  (registers the family)

    maps = (["--map", "open"],)
    return _family("grid", {False: maps, True: (*maps, ["--map", "blocks"])}, "5",
                   ["--generations", "40"])


def _polygon_commands() -> list[list[str]]:
    ends = (["--start", "20,20", "--goal", "320,320"],)
    return _family("polygon", {False: ends, True: ends}, "2", ["--iterations", "60"])


def _reactive() -> list[list[str]]:
    import subtask_opt.planners.reactive  # noqa: F401  (registers the family)

    out = [["plan", "reactive", "--world", world, "--navigator", name, "--seed", "3",
            "--noise", "0.05", "--no-progress"]
           for name in planners("reactive") for world in ("simple", "corridor")]
    return out + [["plan", "reactive", "--world", "u-trap", "--seed", "3", "--noise", "0.05",
                   "--no-progress"]]  # the fuzzy escape


def _agv() -> list[list[str]]:
    return [["plan", "agv", "--scenario", "2-2"],  # wait, static, re-plan, recovery
            ["plan", "agv", "--scenario", "2-3", "--drift", "--seed", "4"],  # sidestep
            ["plan", "agv", "--scenario", "random", "--seed", "17", "--drift"],
            ["plan", "agv", "--scenario", "random", "--seed", "23", "--drift",
             "--no-check-points"]]


FAMILIES = {"plan grid": _grid, "plan polygon": _polygon_commands, "plan reactive": _reactive,
            "plan agv": _agv}


def _run_family(commands: list[list[str]], hash_seed: str, folder) -> list[tuple[int, str]]:
    """Run every command in one fresh process; (exit code, stripped JSON text) each."""
    outs = [folder / f"{hash_seed}-{i}.json" for i in range(len(commands))]
    code = ("import json, sys; from subtask_opt.cli import main; "
            f"codes = [main(a + ['--json', o]) for a, o in zip({commands!r}, "
            f"{[str(o) for o in outs]!r})]; "
            "print(json.dumps(codes))")
    env = {**os.environ, "PYTHONHASHSEED": hash_seed, "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    codes = json.loads(proc.stdout.strip().splitlines()[-1])
    return [(c, json.dumps(_strip(json.loads(o.read_text())))) for c, o in zip(codes, outs,
                                                                               strict=True)]


# Under `make coverage` the subprocesses run the kernels as Python and coverage does not
# measure them (see tests/cli/test_same_bytes.py); the in-process CLI tests cover the lines.
@pytest.mark.skipif(REDUCED, reason="coverage run: subprocesses are not measured")
@pytest.mark.parametrize("family", list(FAMILIES))
def test_planner_json_is_identical_across_processes_and_hash_seeds(family, tmp_path):
    commands = FAMILIES[family]()
    assert commands
    runs = [_run_family(commands, h, tmp_path) for h in HASH_SEEDS]
    for i, argv in enumerate(commands):
        code, text = runs[0][i]
        assert code == 0, " ".join(argv)  # the commands are chosen to reach their goals
        data = json.loads(text)
        assert len(data.get("path") or data.get("poses") or data.get("trajectory")) > 1
        for other in runs[1:]:
            assert other[i] == (code, text), " ".join(argv)


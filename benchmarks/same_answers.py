"""Same answers before and after a refactor: run a fixed set of CLI commands, compare their JSON.

    python benchmarks/same_answers.py record DIR      # write every command's JSON into DIR
    python benchmarks/same_answers.py compare A B     # diff two recordings, timings ignored

The command set covers every CLI command the README shows and every built-in case, map,
world and scenario. Keys that hold wall-clock measurements (``runtime*``, ``*seconds``,
``*_ms``, ``compile*``) are dropped before comparing; everything else must be equal.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

GRID_MAPS = ("open", "walls", "blocks", "rooms", "spiral", "cluttered", "trap")
GRID_PLANNERS = ("dt", "dt-octile", "mdt", "ga", "ga-paper", "vff", "vfh")
POLYGON_PLANNERS = ("dijkstra", "improved", "pso", "visibility")
REACTIVE_WORLDS = ("simple", "u-trap", "corridor")
REACTIVE_NAVIGATORS = ("fuzzy", "vff", "vfh")
AGV_SCENARIOS = ("1", "2-1", "2-2", "2-3")

TIMING_KEY = re.compile(r"(runtime|seconds|_ms$|^ms$|^time_s$|compile|elapsed|wall)", re.IGNORECASE)


def commands() -> dict[str, list[str]]:
    """Name -> CLI arguments (without --json, which is appended)."""
    cmds: dict[str, list[str]] = {}
    for case in ("square20", "random30"):
        for model in ("paper", "trapezoid", "joint", "line"):
            cmds[f"solve-{case}-{model}"] = ["solve", "--case", case, "--time-model", model,
                                             "--seed", "1"]
    cmds["solve-asr-joint"] = ["solve", "--case", "random30", "--robot", "asr_twodof",
                               "--time-model", "joint", "--seed", "1"]
    cmds["solve-paper-preset"] = ["solve", "--case", "square20", "--preset", "paper",
                                  "--time-model", "trapezoid", "--seed", "3",
                                  "--max-generations", "300"]
    for name in GRID_MAPS:
        for planner in GRID_PLANNERS:
            cmds[f"grid-{name}-{planner}"] = ["plan", "grid", "--map", name,
                                              "--planner", planner, "--seed", "0"]
    for planner in POLYGON_PLANNERS:
        cmds[f"polygon-{planner}"] = ["plan", "polygon", "--start", "20,20", "--goal",
                                      "320,320", "--planner", planner, "--seed", "0"]
    for world in REACTIVE_WORLDS:
        for nav in REACTIVE_NAVIGATORS:
            cmds[f"reactive-{world}-{nav}"] = ["plan", "reactive", "--world", world,
                                               "--navigator", nav]
    for scen in AGV_SCENARIOS:
        cmds[f"agv-{scen}"] = ["plan", "agv", "--scenario", scen]
    cmds["bench-grid"] = ["bench", "grid", "--repeats", "1"]
    cmds["bench-maklink"] = ["bench", "maklink", "--runs", "3"]
    cmds["bench-reactive"] = ["bench", "reactive", "--n", "10"]
    cmds["bench-agv"] = ["bench", "agv", "--n", "10"]
    return cmds


def _strip(value: object) -> object:
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if not TIMING_KEY.search(str(k))}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def record(out: Path, only: str | None = None) -> int:
    out.mkdir(parents=True, exist_ok=True)
    failures = 0
    exe = Path(sys.executable).with_name("subtask-opt")
    for name, args in commands().items():
        if only and only not in name:
            continue
        target = out / f"{name}.json"
        proc = subprocess.run([str(exe), *args, "--json", str(target)],
                              capture_output=True, text=True, env=None)
        status = "ok" if target.exists() else f"no JSON (exit {proc.returncode})"
        if not target.exists():
            failures += 1
            print(f"{name:34s} {status}: {proc.stderr.strip()[-300:]}")
        else:
            print(f"{name:34s} exit {proc.returncode}")
    return failures


def compare(a: Path, b: Path) -> int:
    differing = 0
    names = sorted({p.name for p in a.glob("*.json")} | {p.name for p in b.glob("*.json")})
    for name in names:
        pa, pb = a / name, b / name
        if not (pa.exists() and pb.exists()):
            print(f"{name}: only in {'A' if pa.exists() else 'B'}")
            differing += 1
            continue
        ja, jb = _strip(json.loads(pa.read_text())), _strip(json.loads(pb.read_text()))
        if ja != jb:
            differing += 1
            print(f"{name}: differs")
    print(f"{len(names) - differing} of {len(names)} identical (timings excluded)")
    return 1 if differing else 0


def main(argv: list[str]) -> int:
    if len(argv) >= 2 and argv[0] == "record":
        return 1 if record(Path(argv[1]), argv[2] if len(argv) > 2 else None) else 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(Path(argv[1]), Path(argv[2]))
    print(__doc__.strip().splitlines()[2], file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

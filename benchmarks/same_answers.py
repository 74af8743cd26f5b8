"""Same answers before and after a refactor: run a fixed set of CLI commands, compare their JSON.

    python benchmarks/same_answers.py record DIR      # write every command's JSON into DIR
    python benchmarks/same_answers.py compare A B     # diff two recordings, timings ignored

The command set covers every CLI command the README shows and every built-in case, map,
world and scenario, planar and serial tour shapes (open paths, fixed ends, a home,
precedence, runs) and serial arms (a UR5 in its box cell, the VS060 on RoboTSP's
drilling subset when ``../shared/data`` is there). Keys that hold wall-clock measurements
(``runtime*``, ``*seconds``, ``*_ms``, ``compile*``, ``cpu*``) are dropped before comparing.

Every command but a serial arm's must give equal values for every key the older recording
has, nested keys included (keys added since are listed, not failed). A serial arm's
answer must be equal *or better*: its executed ``total_time`` no longer than before (the
search and the joint model of serial arms were reworked, so their tours may change).
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

TIMING_KEY = re.compile(r"(runtime|seconds|_ms$|^ms$|^time_s$|compile|elapsed|wall|^cpu)",
                        re.IGNORECASE)
HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PRECEDENCE = HERE / "data" / "precedence.txt"
UR5_CASE = ROOT / "examples" / "data" / "ur5_panel.csv"
UR5_SCENE = ROOT / "examples" / "data" / "ur5_panel_scene.json"
ROBOTSP = ROOT.parent / "shared" / "data" / "robotsp"
SERIAL_PREFIX = "solve-serial-"


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
    for model in ("joint", "trapezoid"):
        base = ["solve", "--case", "random30", "--time-model", model, "--seed", "2"]
        cmds[f"solve-open-{model}"] = [*base, "--tour", "open", "--first", "4"]
        cmds[f"solve-open-end-{model}"] = [*base, "--tour", "open", "--first", "4", "--end", "9"]
        cmds[f"solve-home-{model}"] = [*base, "--home", "0.3,0.3"]
        cmds[f"solve-precedence-{model}"] = [*base, "--precedence", str(PRECEDENCE)]
    ur5 = ["solve", "--robot", "ur5", "--case", str(UR5_CASE), "--scene", str(UR5_SCENE),
           "--home", "0,-90,90,-90,-90,0"]
    for seed in (0, 1, 2):
        cmds[f"{SERIAL_PREFIX}ur5-{seed}"] = [*ur5, "--seed", str(seed)]
    # the tour shapes on a serial arm (the UR5 case has 20 holes; PRECEDENCE's pairs are
    # within them)
    cmds[f"{SERIAL_PREFIX}ur5-open"] = [*ur5, "--seed", "0", "--tour", "open"]
    cmds[f"{SERIAL_PREFIX}ur5-open-end"] = [*ur5, "--seed", "0", "--tour", "open", "--first",
                                           "4", "--end", "9"]
    cmds[f"{SERIAL_PREFIX}ur5-precedence"] = [*ur5, "--seed", "0", "--precedence",
                                             str(PRECEDENCE)]
    cmds[f"{SERIAL_PREFIX}ur5-runs"] = [*ur5, "--seed", "0", "--runs", "3"]
    cmds[f"{SERIAL_PREFIX}ur5-noscene"] = ["solve", "--robot", "ur5", "--case", str(UR5_CASE),
                                          "--home", "0,-90,90,-90,-90,0", "--seed", "0"]
    if ROBOTSP.is_dir():
        cmds[f"{SERIAL_PREFIX}vs060-robotsp"] = [
            "solve", "--robot", "vs060_drill", "--case",
            str(ROBOTSP / "targets.csv"), "--seed", "0", "--quiet"]
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


def _differences(old: object, new: object, where: str = "") -> tuple[list[str], list[str]]:
    """(keys of ``old`` whose values ``new`` changes, keys ``new`` adds), nested keys
    dotted: a dict is compared key by key, anything else by equality."""
    if not (isinstance(old, dict) and isinstance(new, dict)):
        return ([where or "(value)"] if old != new else []), []
    changed: list[str] = []
    added = [f"{where}{k}" for k in new if k not in old]
    for k, v in old.items():
        if k not in new:
            changed.append(f"{where}{k}")
            continue
        c, a = _differences(v, new[k], f"{where}{k}.")
        changed += [x.rstrip(".") for x in c]
        added += a
    return sorted(changed), sorted(added)


def compare(a: Path, b: Path) -> int:
    """Compare recording ``b`` (after) with ``a`` (before); 1 when an answer got worse."""
    differing = 0
    names = sorted({p.name for p in a.glob("*.json")} | {p.name for p in b.glob("*.json")})
    for name in names:
        pa, pb = a / name, b / name
        if not (pa.exists() and pb.exists()):
            print(f"{name}: only in {'A' if pa.exists() else 'B'}")
            differing += 1
            continue
        ja, jb = _strip(json.loads(pa.read_text())), _strip(json.loads(pb.read_text()))
        if name.startswith(SERIAL_PREFIX):
            before, after = float(ja["total_time"]), float(jb["total_time"])
            verdict = "equal" if after == before else ("better" if after < before else "WORSE")
            print(f"{name}: {verdict} ({before:.6f} -> {after:.6f} s)")
            differing += verdict == "WORSE"
            continue
        changed, added = _differences(ja, jb)
        if changed:
            differing += 1
            print(f"{name}: differs in {', '.join(changed)}")
        elif added:
            print(f"{name}: identical; keys added: {', '.join(added)}")
    print(f"{len(names) - differing} of {len(names)} identical or better (timings excluded)")
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

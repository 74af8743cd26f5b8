"""Thousands of targets on a UR10: time per phase, peak memory, tour, bound, growth.

Targets 245 -> 500 -> 1,000 -> 2,000 -> 5,000 holes of a generated, seeded wing-skin
panel (:func:`subtask_opt.arm.panel.wing_panel`) at the defaults (45 degree axis step,
0.01 m standoff, self-collision checked), the home ``HOME_DEG``. Each size runs in a fresh
subprocess (``--one N``), so its peak RSS (``resource.getrusage(RUSAGE_SELF).ru_maxrss``)
is its own; numba compilation is reported apart (``compile``) and left out of the CPU
figures. Every configuration of the problem is checked to reach its target by
Pinocchio's FK (the largest miss is printed). The growth exponent is the slope of
log(CPU outside compilation) against log(targets) from 500 to 5,000 (least squares).

    PYTHONPATH=. .venv/bin/python benchmarks/scale.py [--sizes 245,500,...] [--json OUT]

``--compare`` instead solves the same problems with the dense matrix (micro-GA) and the
candidate legs (iterated local search), the same seed: RoboTSP's subsets
(``../shared/data/robotsp``, its scene and limits, no +-2 pi alternatives) and small
held-out panels (seeds 101-103), and prints the planned times side by side.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time
from typing import Any

import numpy as np

SIZES = (245, 500, 1000, 2000, 5000)
HOME_DEG = (0.0, -60.0, 90.0, -30.0, 90.0, 0.0)
SEED = 0


def one(n: int, seed: int, legs_mode: str) -> dict[str, Any]:
    """Build and solve one size in this process; its figures."""
    from subtask_opt.arm.panel import wing_panel
    from subtask_opt.arm.poses import make_targets
    from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem
    from subtask_opt.kinematics.serial import load_serial_arm

    wall0 = time.monotonic()
    arm = load_serial_arm("ur10")
    targets = make_targets(wing_panel(n, seed=seed), axis_step=45.0, standoff=0.01)
    problem = SerialProblem(targets, arm, np.radians(HOME_DEG), legs_mode=legs_mode)
    result = solve_serial_problem(problem, seed=seed)
    wall = time.monotonic() - wall0
    cpu = dict(result.report.cpu)
    miss = 0.0
    points = np.array([p[0, :3, 3] for p in targets.poses])
    owner = np.repeat(np.arange(n), problem.counts)
    for q, t in zip(problem.flat, owner, strict=True):
        miss = max(miss, float(np.linalg.norm(arm.fk(q)[:3, 3] - points[t])))
    work = sum(v for k, v in cpu.items() if k != "compile")
    bound = result.lower_bound
    planned = result.report.planned_time
    return {
        "targets": n, "legs_mode": "sparse" if problem.sparse is not None else "dense",
        "configurations": int(problem.offsets[-1]),
        "dropped_dominated": problem.dropped_dominated, "dropped_by_cap": problem.dropped_by_cap,
        "dropped_in_collision": problem.dropped_in_collision,
        "cpu_s": cpu, "cpu_outside_compile_s": work, "wall_s": wall,
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "tour_s": result.total_time, "planned_s": planned, "bound_s": bound,
        "gap_pct": None if bound is None else 100 * (planned / bound - 1),
        "fk_miss_m": miss, "kicks_or_generations": result.generations,
        "search_rounds": result.report.counts["search_rounds"],
        "legs_infeasible": result.report.counts["legs_infeasible"],
    }


def compare(seed: int, robotsp_sizes: list[int], panels: list[int]) -> list[dict[str, Any]]:
    """Dense against sparse legs on the same problems, the same seed (module doc)."""
    from pathlib import Path

    from subtask_opt.arm.panel import wing_panel
    from subtask_opt.arm.poses import make_targets
    from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem
    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.ik import IKParams
    from subtask_opt.kinematics.serial import load_serial_arm

    cases: list[tuple[str, Any, Any, Any, Any]] = []
    data = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "robotsp"
    if robotsp_sizes and (data / "targets.csv").is_file():
        rows = np.loadtxt(data / "targets.csv", delimiter=",", skiprows=1)
        subsets = json.loads((data / "subsets.json").read_text())["subsets"]
        arm = load_serial_arm("vs060_drill", limits="robotsp")
        scene = Scene.load(data / "obstacles.json")
        home = np.radians((0.0, -20.0, 130.0, 0.0, 70.0, 0.0))
        for size in robotsp_sizes:
            t = make_targets(rows[subsets[str(size)]], axis_step=45.0, standoff=0.01)
            cases.append((f"robotsp {size}", t, arm, home, scene))
    ur10 = load_serial_arm("ur10")
    for k, n in enumerate(panels):
        t = make_targets(wing_panel(n, seed=101 + k), axis_step=45.0, standoff=0.01)
        cases.append((f"panel {n} (seed {101 + k})", t, ur10, np.radians(HOME_DEG), None))
    out = []
    for name, targets, arm, home, scene in cases:
        row: dict[str, Any] = {"case": name}
        for mode in ("dense", "sparse"):
            c0 = time.process_time()
            problem = SerialProblem(targets, arm, home, scene=scene, legs_mode=mode,
                                    ik=IKParams(wrap_alternatives=False))
            result = solve_serial_problem(problem, seed=seed)
            cpu = result.report.cpu
            row[mode] = {"planned_s": result.report.planned_time,
                         "bound_s": result.lower_bound,
                         "configurations": int(problem.offsets[-1]),
                         "cpu_outside_compile_s": time.process_time() - c0 - cpu["compile"]}
        d, sp = row["dense"], row["sparse"]
        print(f"{name:24s} dense {d['planned_s']:9.4f} s ({d['configurations']} conf, "
              f"{d['cpu_outside_compile_s']:6.1f} s CPU)  sparse {sp['planned_s']:9.4f} s "
              f"({sp['configurations']} conf, {sp['cpu_outside_compile_s']:6.1f} s CPU)  "
              f"sparse/dense {sp['planned_s'] / d['planned_s']:.4f}  bounds "
              f"{d['bound_s'] or math.nan:.4f} / {sp['bound_s'] or math.nan:.4f}", flush=True)
        out.append(row)
    return out


def growth(rows: list[dict[str, Any]], lo: int = 500, hi: int = 5000) -> float | None:
    """Least-squares slope of log CPU (outside compilation) on log targets in [lo, hi]."""
    sel = [r for r in rows if lo <= r["targets"] <= hi]
    if len(sel) < 2:
        return None
    x = np.log([r["targets"] for r in sel])
    y = np.log([r["cpu_outside_compile_s"] for r in sel])
    return float(np.polyfit(x, y, 1)[0])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)))
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--legs-mode", default="auto", choices=("auto", "dense", "sparse"))
    ap.add_argument("--json", default=None)
    ap.add_argument("--one", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--compare", action="store_true",
                    help="dense against sparse legs on RoboTSP's subsets and small panels")
    ap.add_argument("--robotsp-sizes", default="25,50,100,150,200,245")
    ap.add_argument("--panels", default="20,40,80")
    args = ap.parse_args(argv)
    if args.compare:
        rows = compare(args.seed, [int(x) for x in args.robotsp_sizes.split(",") if x],
                       [int(x) for x in args.panels.split(",") if x])
        if args.json:
            with open(args.json, "w", encoding="utf-8") as fh:
                json.dump(rows, fh, indent=1)
        return 0
    if args.one is not None:
        print(json.dumps(one(args.one, args.seed, args.legs_mode)))
        return 0
    rows = []
    for n in (int(s) for s in args.sizes.split(",")):
        proc = subprocess.run([sys.executable, __file__, "--one", str(n), "--seed",
                               str(args.seed), "--legs-mode", args.legs_mode],
                              capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            print(f"{n} targets failed:\n{proc.stderr[-2000:]}", file=sys.stderr)
            return 1
        rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        r = rows[-1]
        c = r["cpu_s"]
        print(f"{n:6d} {r['legs_mode']:6s} conf {r['configurations']:7d}  ik {c['ik']:6.2f} "
              f"coll {c['collision']:6.2f} legs {c['matrix']:6.2f} search {c['search']:6.2f} "
              f"bound {c.get('bound', 0.0):5.2f} | cpu {r['cpu_outside_compile_s']:7.2f} s "
              f"(compile {c['compile']:.1f}) rss {r['peak_rss_mib']:7.0f} MiB | tour "
              f"{r['tour_s']:8.3f} s bound {r['bound_s'] or math.nan:8.3f} gap "
              f"{r['gap_pct'] if r['gap_pct'] is not None else math.nan:5.2f}% | fk "
              f"{r['fk_miss_m']:.1e} m | rounds {r['search_rounds']} legs in collision "
              f"{r['legs_infeasible']}", flush=True)
    slope = growth(rows)
    print(f"growth exponent (CPU outside compilation, 500-5000 targets): "
          f"{'n/a' if slope is None else f'{slope:.3f}'}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump({"rows": rows, "growth_exponent": slope}, fh, indent=1)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""How the elbow-choosing solve scales: random subtask sets of 100 ... 500 on both planar arms.

For each robot and size, one random subtask set per ``--sets`` seed
(:func:`subtask_opt.arm.tasks.random_subtasks`), the joint time model with the
elbows chosen (a generalised TSP), solved with the default parameters and the
default stop, ``--seeds`` times. Printed per set: median CPU time of ``solve``
after JIT warm-up, and every seed's tour time sorted (their spread says how
far apart the seeds' local optima are; there is no certified optimum at these
sizes). ``--stall-factor`` multiplies the default stall, to see what a longer
search buys.

    python benchmarks/elbows.py [--sizes 100,200,500] [--seeds 3] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path
from typing import Any

from subtask_opt import SolverParams, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import random_subtasks
from subtask_opt.base.stop import MaxGenerations, NoImprovement
from subtask_opt.kinematics.planar import load_planar_arm

ROBOTS = ("planar_2r", "asr_twodof")


def run(sizes: list[int], sets: list[int], seeds: int, stall_factor: float) -> list[dict[str, Any]]:
    rows = []
    for robot in ROBOTS:
        arm = load_planar_arm(robot)
        for n in sizes:
            for set_seed in sets:
                problem = PlanarProblem(random_subtasks(arm, n, seed=set_seed), arm,
                                        time_model="joint")
                solve(problem, seed=0, stop=MaxGenerations(2))  # JIT warm-up
                stall = SolverParams().default_stop(n, configured=True)[0]
                assert isinstance(stall, NoImprovement)
                stop = [NoImprovement(max(1, round(stall.generations * stall_factor))),
                        MaxGenerations(50_000)]
                cpu, times = [], []
                for seed in range(seeds):
                    t0 = time.process_time()
                    result = solve(problem, seed=seed, stop=stop)
                    cpu.append(time.process_time() - t0)
                    times.append(result.total_time)
                row = {"robot": robot, "subtasks": n, "set": set_seed,
                       "median_cpu_s": statistics.median(cpu), "cpu_s": cpu,
                       "total_times": sorted(times)}
                rows.append(row)
                print(f"{robot:11s} {n:4d} set {set_seed:3d}  median CPU "
                      f"{row['median_cpu_s']:7.2f} s  tour times "
                      + " ".join(f"{t:.4f}" for t in row["total_times"]), flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="100,200,500", help="comma-separated subtask counts")
    parser.add_argument("--sets", default="8,9", help="comma-separated random-set seeds")
    parser.add_argument("--seeds", type=int, default=3, help="solver seeds per set")
    parser.add_argument("--stall-factor", type=float, default=1.0,
                        help="multiply the default stall by this")
    parser.add_argument("--json", type=Path, help="write the rows here")
    args = parser.parse_args()
    try:
        sizes = [int(s) for s in args.sizes.split(",")]
        sets = [int(s) for s in args.sets.split(",")]
    except ValueError:
        parser.error(f"--sizes and --sets take comma-separated integers, got {args.sizes!r} "
                     f"and {args.sets!r}")
    if args.seeds < 1 or not 0 < args.stall_factor <= 100 or min(sizes) < 3 or min(sets) < 0:
        parser.error(f"need --seeds >= 1 (got {args.seeds}), --stall-factor in (0, 100] (got "
                     f"{args.stall_factor}), sizes >= 3 and set seeds >= 0")
    print(f"load average {os.getloadavg()[0]:.1f}; CPU times after JIT warm-up")
    rows = run(sizes, sets, args.seeds, args.stall_factor)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"stall_factor": args.stall_factor, "rows": rows},
                                        indent=2))


if __name__ == "__main__":
    main()

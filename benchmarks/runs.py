"""Several short runs or one long one? Per-run miss rates when the elbows are chosen.

On held-out instances (``benchmarks/heldout.py``'s, joint model, elbows chosen) whose
optimum is certified first, one GA run (``runs=1``) per seed at a fraction of the stall a
single run had before :data:`~subtask_opt.arm.planar_problem.CONFIGURED_RUNS` (twice the
fixed-configuration stall; today's runs stall a third of that); printed per instance and
fraction: the share of runs that miss the optimum (q) and the median wall time of a run.
Then, for k independent runs at each fraction, the expected misses over the instances x 20
seeds (sum of 20 q^k) and the time relative to one run at the first fraction. This is the
measurement behind :data:`~subtask_opt.arm.planar_problem.CONFIGURED_RUNS`.

    python benchmarks/runs.py [--seeds 60] [--fractions 1,1/2,1/3]
        [--instances planar_2r:random60/5002,asr_twodof:random30/9,...] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from fractions import Fraction

import numpy as np
from heldout import REL_TOL, certify, instances

from subtask_opt import SolverParams, solve
from subtask_opt.base.stop import MaxGenerations, NoImprovement

HARDEST = ("planar_2r:random30/4", "planar_2r:random40/5000", "planar_2r:random60/5002",
           "planar_2r:random60/5003", "planar_2r:random60/5004", "asr_twodof:random30/3",
           "asr_twodof:random30/9")
"""The held-out sets where single runs missed most (see CONFIGURED_RUNS)."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--fractions", default="1,1/2,1/3",
                    help="fractions of twice the fixed-configuration default stall")
    ap.add_argument("--instances", default=",".join(HARDEST))
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    try:
        fractions = [Fraction(f) for f in args.fractions.split(",")]
    except (ValueError, ZeroDivisionError):
        ap.error(f"--fractions: expected numbers like 1,1/2,1/3, got {args.fractions!r}")
    if args.seeds < 1 or not all(0 < f <= 4 for f in fractions):
        ap.error("--seeds must be >= 1 and every fraction in (0, 4]")
    wanted = [tuple(w.split(":")) for w in args.instances.split(",")]
    rows = []
    for robot in sorted({r for r, _ in wanted}):
        for _, name, problem in instances(robot, "joint", 5, 5000):
            if (robot, name) not in wanted:
                continue
            optimum = certify(problem, 120.0, solve(problem, seed=0).order)
            if optimum is None:
                print(f"{robot} {name}: optimum not certified in 120 s, skipped")
                continue
            fixed = SolverParams().default_stop(problem.size)[0]
            assert isinstance(fixed, NoImprovement)
            for fraction in fractions:
                stall = max(1, int(2 * fixed.generations * fraction))
                stop = [NoImprovement(stall), MaxGenerations(50_000)]
                totals, walls = [], []
                for seed in range(args.seeds):
                    t0 = time.perf_counter()
                    totals.append(solve(problem, seed=seed, stop=stop,
                                        params=SolverParams(runs=1)).total_time)
                    walls.append(time.perf_counter() - t0)
                q = float(np.mean(np.array(totals) > optimum * (1 + REL_TOL)))
                rows.append({"robot": robot, "instance": name, "fraction": str(fraction),
                             "stall": stall, "miss_rate": q,
                             "median_wall_s": statistics.median(walls)})
                print(f"{robot:11s} {name:14s} stall {stall:4d}: q {q:.3f}, "
                      f"run {1e3 * rows[-1]['median_wall_s']:7.1f} ms", flush=True)
    print("\nexpected misses over the instances x 20 seeds / time, k runs at each stall")
    print("   k  " + "  ".join(f"{'stall x ' + str(f):>23s}" for f in fractions))
    for k in (1, 2, 3, 4, 6, 8, 10, 12):
        cells = []
        for f in fractions:
            at = [r for r in rows if r["fraction"] == str(f)]
            full = {(r["robot"], r["instance"]): r["median_wall_s"] for r in rows
                    if r["fraction"] == str(fractions[0])}
            misses = sum(20 * r["miss_rate"] ** k for r in at)
            cost = np.mean([k * r["median_wall_s"] / full[(r["robot"], r["instance"])]
                            for r in at])
            cells.append(f"{misses:13.3f} / {cost:6.2f}x")
        print(f"{k:4d}  " + "  ".join(cells))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()

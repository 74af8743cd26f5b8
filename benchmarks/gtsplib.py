"""Our GTSP search on the shared GTSPLIB instances beside the best-known values and GLNS.

Every instance of ``../shared/data/gtsplib`` (``reference.json``: best-known ``bks``, GLNS's
C++ port mean, hits out of 10 and seconds per run on an Apple M4 Pro). Each run is ``solve``
over the reader's ``GtspProblem`` from one seed, stopped at the time limit: ``--time-factor``
(default 2) times GLNS's published seconds, at least ``--min-time`` (1 s); with ``--stall``
also at the solver's stall criterion (as ``subtask-opt gtsp`` does) if that comes first.
Instances without a GLNS figure get the minimum, and their best-known value is our best over
the seeds unless ``--certify`` proves an optimum (branch and cut / the arc MILP). The wall
clock is checked between generations, so a run can pass its limit by up to one generation
(the seconds column shows it). Every tour is checked: one vertex of every set, the cost
recomputed from the file's weights.

The limit counts this process's CPU seconds by default (``--clock cpu``: the 2 cores are
shared, and wall time would measure the other processes too), or wall seconds
(``--clock wall``).

Columns: ours mean / best cost, gap of the mean to the BKS, hits (runs at the BKS), mean CPU
and wall seconds (search only, after JIT warm-up; compilation is reported apart), then the BKS,
GLNS's mean, its gap to the BKS, its seconds; the last column is our mean over GLNS's mean.
``--lns 0,1,5`` compares the large-neighbourhood steps per set (0: the arm problems'
order search with vertex-choosing relocations and kicks).

Part 2 (``--pcgtsp``): the precedence-constrained instances of ``../shared/data/pcgtsp``
through ``solve_gtsp`` (start set, precedence) with a 30 s limit, beside their proven optima;
every tour's start and precedence are checked from the file.

    python benchmarks/gtsplib.py [--seeds 3] [--instances 89pcb442,132d657] [--lns 1]
        [--time-factor 2] [--min-time 1] [--json out/gtsplib.json] [--certify] [--pcgtsp]
        [--population P]

Times are wall times on a machine that may be shared (the load average is printed): compare
within one run.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "gtsplib"


class CpuBudget:
    """Stop once this process has used ``seconds`` of CPU since the criterion was made (the
    machine is shared: wall time measures the others' load too)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.start = time.process_time()

    def __call__(self, progress) -> bool:
        return time.process_time() - self.start >= self.seconds

    def generations_left(self, progress) -> None:
        return None


def _run(instance, seed: int, limit: float, lns: int | None,
         stall: bool = False, clock: str = "cpu",
         population: int | None = None) -> tuple[float, float, int, float]:
    from dataclasses import replace

    from subtask_opt.base.stop import MaxRuntime, NoImprovement
    from subtask_opt.tour.gtsplib import gtsp_params
    from subtask_opt.tour.solve import solve

    problem = instance.problem(lns_steps=None if lns is None else lns * instance.set_count)
    params = gtsp_params(runs=None if stall else 1)  # what subtask-opt gtsp searches with
    if population is not None:
        params = replace(params, population=population)
    budget = CpuBudget(limit) if clock == "cpu" else MaxRuntime(limit)
    stop = [*(params.default_stop(problem.size, configured=True) if stall
              else [NoImprovement(10**6)]), budget]
    cpu = time.process_time()
    result = solve(problem, seed=seed, params=params, stop=stop)
    cpu = time.process_time() - cpu
    tour = np.asarray(result.configurations)[result.order]
    cost = instance.tour_cost(tour)  # checks one vertex of every set
    assert cost == result.total_time, (cost, result.total_time)
    return cost, result.runtime_s, result.generations, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=str(DATA))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--instances", default=None)
    parser.add_argument("--lns", default="1", help="LNS steps per set, comma-separated")
    parser.add_argument("--time-factor", type=float, default=2.0)
    parser.add_argument("--min-time", type=float, default=1.0)
    parser.add_argument("--certify", action="store_true")
    parser.add_argument("--stall", action="store_true",
                        help="stop at the solver's stall criterion too (default: the time "
                             "limit only, one run restarting on convergence)")
    parser.add_argument("--json", default=None)
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                        help="what the time limit counts: this process's CPU seconds "
                             "(default; the machine is shared) or wall seconds")
    parser.add_argument("--pcgtsp", action="store_true", help="only part 2, the PCGTSP set")
    parser.add_argument("--population", type=int, default=None,
                        help="micro-GA population (default: subtask-opt gtsp's, "
                             "GTSP_POPULATION)")
    args = parser.parse_args()
    if args.pcgtsp:
        _pcgtsp(args.seeds)
        return

    from subtask_opt.tour.exact import gtsp_set_optimum
    from subtask_opt.tour.gtsplib import read_gtsplib

    data = Path(args.data)
    reference = json.loads((data / "reference.json").read_text())["instances"]
    names = (args.instances.split(",") if args.instances else
             sorted((p.stem for p in data.glob("*.gtsp")),
                    key=lambda s: read_gtsplib(data / f"{s}.gtsp").dimension))
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    started = time.perf_counter()
    warm = read_gtsplib(data / f"{names[0]}.gtsp")
    for lns in {int(x) for x in args.lns.split(",")}:
        _run(warm, 0, 0.2, lns)
    print(f"JIT warm-up (compile or cache load) {time.perf_counter() - started:.1f} s")
    rows = []
    for lns_text in args.lns.split(","):
        lns = int(lns_text)
        print(f"\nLNS steps per set: {lns}")
        print(f"{'instance':>10} {'mean':>9} {'best':>7} {'gap':>7} {'hits':>5} {'cpu s':>6} "
              f"{'wall s':>6} | "
              f"{'BKS':>7} {'GLNS':>9} {'gap':>7} {'s':>6} | ours/GLNS")
        gaps = []
        for name in names:
            instance = read_gtsplib(data / f"{name}.gtsp")
            ref = reference.get(name, {})
            limit = max(args.min_time, args.time_factor * ref.get("glns_cpp_s_m4pro", 0.0))
            runs = [_run(instance, seed, limit, lns, args.stall, args.clock, args.population)
                    for seed in range(args.seeds)]
            costs = [r[0] for r in runs]
            bks = ref.get("bks")
            certified = ""
            if bks is None and args.certify:
                best_tour = None
                bks, _ = gtsp_set_optimum(instance.problem(), time_limit=600.0,
                                          incumbent=best_tour)
                certified = " (certified)"
            if bks is None:
                bks = min(costs)
                certified = " (our best)"
            mean = statistics.fmean(costs)
            gap = 100 * (mean / bks - 1)
            gaps.append(gap)
            hits = sum(c <= bks for c in costs)
            seconds = statistics.fmean(r[1] for r in runs)
            cpu = statistics.fmean(r[3] for r in runs)
            glns = ref.get("glns_cpp_mean")
            glns_txt = (f"{glns:>9.1f} {100 * (glns / bks - 1):>6.3f}% "
                        f"{ref['glns_cpp_s_m4pro']:>6.2f}" if glns else f"{'-':>9} {'-':>7} "
                                                                         f"{'-':>6}")
            ratio = f"{100 * (mean / glns - 1):+.3f}%" if glns else "-"
            print(f"{name:>10} {mean:>9.1f} {min(costs):>7.0f} {gap:>6.3f}% "
                  f"{hits:>2}/{args.seeds} {cpu:>6.2f} {seconds:>6.2f} | {bks:>7.0f} {glns_txt} | "
                  f"{ratio}"
                  f"{certified}", flush=True)
            rows.append({"instance": name, "lns_per_set": lns, "costs": costs, "bks": bks,
                         "mean_gap_percent": gap, "hits": hits, "seconds": seconds,
                         "cpu_seconds": cpu, "clock": args.clock,
                         "limit_s": limit, "glns_mean": glns,
                         "glns_s": ref.get("glns_cpp_s_m4pro")})
        print(f"mean gap over {len(gaps)} instances: {statistics.fmean(gaps):.4f}%")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")


def _pcgtsp(seeds: int, limit: float = 30.0) -> None:
    from subtask_opt.tour.gtsplib import read_gtsplib, solve_gtsp

    folder = DATA.parent / "pcgtsp"
    optimum = json.loads((folder / "reference.json").read_text())["optimum"]
    warm = read_gtsplib(folder / "ESC12.pcglns")
    started = time.perf_counter()
    solve_gtsp(warm, time_limit=0.2, seed=0)
    print(f"load average {os.getloadavg()[0]:.2f}; JIT warm-up "
          f"{time.perf_counter() - started:.1f} s")
    print(f"{'instance':>9} {'sets':>5} {'pairs':>6} {'costs':>22} {'optimum':>8} {'hits':>5} "
          f"{'max s':>6}")
    for name, best in optimum.items():
        instance = read_gtsplib(folder / f"{name}.pcglns")
        costs, seconds = [], []
        for seed in range(seeds):
            solution = solve_gtsp(instance, time_limit=limit, seed=seed)
            assert not instance.violations(solution.tour)
            costs.append(solution.cost)
            seconds.append(solution.search_runtime_s)
        hits = sum(c <= best for c in costs)
        print(f"{name:>9} {instance.set_count:>5} {len(instance.precedence):>6} "
              f"{' '.join(f'{c:g}' for c in costs):>22} {best:>8} {hits:>2}/{seeds} "
              f"{max(seconds):>6.2f}", flush=True)


if __name__ == "__main__":
    main()

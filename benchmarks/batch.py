"""Batch throughput: a random30 batch on 1 and 2 Dask workers, and the per-job overhead.

Each worker count gets its own local Dask cluster (one thread per worker
process). The workers are warmed first (kernels loaded by the warm-up plugin
and one small batch), so the timed batch holds no compile or start-up time.
The same batch also runs in this process (``workers=0``) as the reference; all
runs must give bit-identical tours.

Per-job overhead = (wall time x workers - sum of the jobs' own times in their
workers) / jobs: what the batch machinery (scheduling, pickling, transfers)
adds to each job. The machine is shared and noisy: compare within one run.

    python benchmarks/batch.py [--jobs 200] [--workers 1,2] [--time-model joint]
        [--json out/bench/batch.json]
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import sys
import time
from pathlib import Path

from subtask_opt.arm.timing.models import TIME_MODELS
from subtask_opt.batch import Job, dask_available, overhead_per_job, solve_many

OVERHEAD_BUDGET_S = 0.020
"""The per-job overhead the cluster backend should stay under, after warm-up."""


def make_jobs(n: int, time_model: str, prefix: str = "random30") -> list[Job]:
    return [Job(f"{prefix}/{i}", "random30", time_model=time_model, case_seed=i, seed=i)
            for i in range(n)]


def run_serial(jobs: list[Job]) -> dict:
    solve_many(jobs[:2], seeds=None, workers=0)  # warm-up
    start = time.perf_counter()
    results = solve_many(jobs, seeds=None, workers=0)
    wall = time.perf_counter() - start
    return _row("this process", 1, results, wall)


def run_cluster(jobs: list[Job], workers: int) -> dict:
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        warm = make_jobs(2 * workers, jobs[0].time_model, prefix="warm")
        solve_many(warm, seeds=None, client=client)  # plugin + first jobs on every worker
        start = time.perf_counter()
        results = solve_many(jobs, seeds=None, client=client)
        wall = time.perf_counter() - start
    return _row(f"dask, {workers} worker{'s' * (workers > 1)}", workers, results, wall)


def _row(name: str, workers: int, results: list, wall: float) -> dict:
    failed = [r for r in results if not r.success]
    if failed:
        raise SystemExit(f"{name}: {len(failed)} jobs failed, first: {failed[0].error}")
    times = [r.worker_time_s for r in results]
    return {
        "backend": name, "workers": workers, "jobs": len(results), "wall_s": wall,
        "jobs_time_s": sum(times), "median_job_s": statistics.median(times),
        "overhead_per_job_s": overhead_per_job(results, wall, workers),
        "answers": [(r.order, r.total_time) for r in results],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=200, help="batch size (default 200)")
    parser.add_argument("--workers", default="1,2",
                        help="comma-separated worker counts (default 1,2)")
    parser.add_argument("--time-model", default="joint", choices=TIME_MODELS)
    parser.add_argument("--json", metavar="OUT.json")
    args = parser.parse_args(argv)
    if not dask_available():
        print("benchmarks/batch.py needs dask.distributed: pip install subtask_opt[cluster]",
              file=sys.stderr)
        return 2
    counts = [int(w) for w in args.workers.split(",")]
    jobs = make_jobs(args.jobs, args.time_model)
    rows = [run_serial(jobs)] + [run_cluster(jobs, w) for w in counts]
    identical = all(r["answers"] == rows[0]["answers"] for r in rows)
    base = next((r["wall_s"] for r in rows if r["workers"] == 1 and r is not rows[0]),
                rows[0]["wall_s"])
    print(f"{args.jobs} random30 jobs, {args.time_model} time model; "
          f"tours identical across backends: {identical}")
    print(f"{'backend':<18} {'wall [s]':>9} {'jobs [s]':>9} {'median job [ms]':>16} "
          f"{'speed-up':>9} {'overhead/job [ms]':>18}")
    for r in rows:
        r["speed_up"] = base / r["wall_s"]
        print(f"{r['backend']:<18} {r['wall_s']:>9.2f} {r['jobs_time_s']:>9.2f} "
              f"{r['median_job_s'] * 1e3:>16.1f} {r['speed_up']:>9.2f} "
              f"{r['overhead_per_job_s'] * 1e3:>18.2f}")
    cluster = [r for r in rows if r["backend"].startswith("dask")]
    worst = max(r["overhead_per_job_s"] for r in cluster)
    print(f"worst cluster overhead per job {worst * 1e3:.2f} ms "
          f"(budget {OVERHEAD_BUDGET_S * 1e3:.0f} ms): "
          f"{'within' if worst <= OVERHEAD_BUDGET_S else 'OVER'}")
    payload = {"jobs": args.jobs, "time_model": args.time_model, "identical": identical,
               "overhead_budget_s": OVERHEAD_BUDGET_S,
               "rows": [{k: v for k, v in r.items() if k != "answers"} for r in rows]}
    print(json.dumps(payload, indent=1))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(payload, indent=1) + "\n")
        print(f"wrote {args.json}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())

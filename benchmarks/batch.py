"""Batch throughput: a random30 batch and the AGV suite on 1 and 2 Dask workers.

``--suite random30`` (default): a batch of random30 sequencing jobs
(:func:`subtask_opt.batch.solve_many`), in this process (``workers=0``, the
reference) and on local Dask clusters of 1 and 2 worker processes (one thread
each). ``--suite agv``: the 200-run AGV suite (``subtask-opt bench agv``,
:func:`~subtask_opt.planners.agv.scenarios.run_agv_suite` with a
:func:`~subtask_opt.batch.suite_mapper`) on the same clusters. ``--suite all``
runs both.

Every cluster is warmed first (kernels loaded by the warm-up plugin and a small
batch), so the timed runs hold no compile or start-up time; each measurement
is repeated ``--repeats`` times on the same cluster and the median is quoted
(the machine is shared). All runs must give identical answers (tours, or the
suite's report without its wall time).

Per-job overhead (random30) = (wall time x workers - sum of the jobs' own times
in their workers) / jobs: what the batch machinery (scheduling, pickling,
transfers) adds to each job.

    python benchmarks/batch.py [--suite random30|agv|all] [--jobs 200] [--runs 200]
        [--workers 1,2] [--repeats 3] [--time-model joint] [--json out/bench/batch.json]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from subtask_opt.arm.timing.models import TIME_MODELS
from subtask_opt.batch import (
    Job,
    dask_available,
    overhead_per_job,
    solve_many,
    suite_mapper,
    warm_agv,
)
from subtask_opt.planners.agv.scenarios import run_agv_suite

OVERHEAD_BUDGET_S = 0.020
"""The per-job overhead the cluster backend should stay under, after warm-up."""


def make_jobs(n: int, time_model: str, prefix: str = "random30") -> list[Job]:
    return [Job(f"{prefix}/{i}", "random30", time_model=time_model, case_seed=i, seed=i)
            for i in range(n)]


@contextmanager
def local_cluster(workers: int) -> Iterator[Any]:
    """A Client on a fresh LocalCluster of ``workers`` single-thread processes."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        yield client


def _timed(fn: Callable[[], Any], repeats: int) -> tuple[list[float], Any]:
    """Wall times of ``repeats`` calls and the last call's value."""
    walls, value = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        value = fn()
        walls.append(time.perf_counter() - start)
    return walls, value


def batch_row(name: str, workers: int, jobs: list[Job], repeats: int,
              client: Any = None) -> dict:
    """Time the random30 batch ``repeats`` times (median), here or on ``client``."""
    where: dict[str, Any] = {"workers": 0} if client is None else {"client": client}
    warm = make_jobs(2 * workers, jobs[0].time_model, prefix="warm")
    solve_many(warm, seeds=None, **where)  # plugin + first jobs on every worker
    rows = []
    answers = None
    for _ in range(repeats):
        start = time.perf_counter()
        results = solve_many(jobs, seeds=None, **where)
        wall = time.perf_counter() - start
        failed = [r for r in results if not r.success]
        if failed:
            raise SystemExit(f"{name}: {len(failed)} jobs failed, first: {failed[0].error}")
        rows.append((wall, sum(r.worker_time_s for r in results),
                     overhead_per_job(results, wall, workers),
                     statistics.median(r.worker_time_s for r in results)))
        run_answers = [(r.order, r.total_time) for r in results]
        if answers is not None and run_answers != answers:
            raise SystemExit(f"{name}: a repeat gave other tours")
        answers = run_answers
    med = [statistics.median(col) for col in zip(*rows, strict=True)]
    return {"backend": name, "workers": workers, "jobs": len(jobs), "wall_s": med[0],
            "walls_s": [r[0] for r in rows], "jobs_time_s": med[1],
            "overhead_per_job_s": med[2], "overheads_s": [r[2] for r in rows],
            "median_job_s": med[3], "answers": answers}


def suite_row(name: str, workers: int, runs: int, repeats: int, client: Any = None) -> dict:
    """Time the AGV suite ``repeats`` times (median), here or on ``client``."""
    mapper = suite_mapper(workers=0 if client is None else None, scheduler=client,
                          warm_up=warm_agv)
    run_agv_suite(2 * workers, 10_000, map_runs=mapper)  # warm every worker
    walls, report = _timed(lambda: run_agv_suite(runs, 0, map_runs=mapper), repeats)
    data = report.to_dict()
    data.pop("seconds")
    return {"backend": name, "workers": workers, "runs": runs,
            "wall_s": statistics.median(walls), "walls_s": walls,
            "per_run_s": statistics.median(walls) / runs, "answers": data}


def _report(title: str, rows: list[dict], baseline: dict, extra: bool) -> bool:
    identical = all(r["answers"] == rows[0]["answers"] for r in rows)
    print(f"\n{title}; answers identical across backends: {identical}")
    head = f"{'backend':<18} {'median wall [s]':>16} {'walls [s]':>22} {'speed-up':>9}"
    if extra:
        head += f" {'median job [ms]':>16} {'overhead/job [ms]':>18}"
    print(head)
    for r in rows:
        r["speed_up"] = baseline["wall_s"] / r["wall_s"]
        line = (f"{r['backend']:<18} {r['wall_s']:>16.2f} "
                f"{' '.join(f'{w:.2f}' for w in r['walls_s']):>22} {r['speed_up']:>9.2f}")
        if extra:
            line += (f" {r['median_job_s'] * 1e3:>16.1f} "
                     f"{r['overhead_per_job_s'] * 1e3:>18.2f}")
        print(line)
    return identical


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", choices=("random30", "agv", "all"), default="random30")
    parser.add_argument("--jobs", type=int, default=200, help="random30 batch size (200)")
    parser.add_argument("--runs", type=int, default=200, help="AGV suite runs (200)")
    parser.add_argument("--workers", default="1,2",
                        help="comma-separated worker counts (default 1,2)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="timed repeats per backend; medians are quoted (default 3)")
    parser.add_argument("--time-model", default="joint", choices=TIME_MODELS)
    parser.add_argument("--json", metavar="OUT.json")
    args = parser.parse_args(argv)
    if not dask_available():
        print("benchmarks/batch.py needs dask.distributed: pip install subtask_opt[cluster]",
              file=sys.stderr)
        return 2
    counts = [int(w) for w in args.workers.split(",")]
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; "
          f"{args.repeats} repeats per backend, medians quoted")
    payload: dict[str, Any] = {"repeats": args.repeats, "cpus": os.cpu_count(),
                               "load_average": os.getloadavg()[0]}
    ok = True
    if args.suite in ("random30", "all"):
        jobs = make_jobs(args.jobs, args.time_model)
        rows = [batch_row("this process", 1, jobs, args.repeats)]
        for w in counts:
            with local_cluster(w) as client:
                rows.append(batch_row(f"dask, {w} worker{'s' * (w > 1)}", w, jobs,
                                      args.repeats, client))
        base = next((r for r in rows[1:] if r["workers"] == 1), rows[0])
        ok &= _report(f"{args.jobs} random30 jobs, {args.time_model} time model", rows, base,
                      extra=True)
        worst = max(r["overhead_per_job_s"] for r in rows[1:])
        print(f"worst cluster overhead per job (median of {args.repeats}) {worst * 1e3:.2f} ms "
              f"(budget {OVERHEAD_BUDGET_S * 1e3:.0f} ms): "
              f"{'within' if worst <= OVERHEAD_BUDGET_S else 'OVER'}")
        payload["random30"] = {"jobs": args.jobs, "time_model": args.time_model,
                               "overhead_budget_s": OVERHEAD_BUDGET_S,
                               "rows": [{k: v for k, v in r.items() if k != "answers"}
                                        for r in rows]}
    if args.suite in ("agv", "all"):
        rows = []
        for w in counts:
            with local_cluster(w) as client:
                rows.append(suite_row(f"dask, {w} worker{'s' * (w > 1)}", w, args.runs,
                                      args.repeats, client))
        base = next((r for r in rows if r["workers"] == 1), rows[0])
        ok &= _report(f"AGV suite, {args.runs} runs (drift on, with and without check points)",
                      rows, base, extra=False)
        payload["agv"] = {"runs": args.runs,
                          "rows": [{k: v for k, v in r.items() if k != "answers"}
                                   for r in rows]}
    print(json.dumps(payload, indent=1))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(payload, indent=1) + "\n")
        print(f"wrote {args.json}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

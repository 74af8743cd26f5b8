"""Our solver and the lower bound on TSPLIB instances with published optima, beside peers.

Part 1, solvers: every instance in ``../shared/data/tsplib`` listed in its
``optima.json``. Rows: our micro-GA (``subtask_opt.solve`` over
``MatrixProblem``) at its default stop and with a time limit
(``--limit``, default 1 s) on ``--seeds`` seeds; fast_tsp
(``fast_tsp.find_tour(matrix, limit)``), elkai/LKH (``solve_tsp()``, one run,
no time limit) and OR-Tools guided local search (same limit; in a child process,
because it and highspy bundle clashing HiGHS builds). Cells: median gap to
the published optimum and median wall time. The wall time of ours includes
``MatrixProblem`` (matrix checks), whose time is also shown apart, and the
candidate lists that ``solve`` builds before its clock (and so ``--limit``)
starts: alpha-nearness from 100 cities, about 0.07 s of CPU at pr1002.

Part 2, the Held-Karp bound (:func:`subtask_opt.tour.bound.lower_bound`):
its time at N = 30, 100, 300, 1000 (uniform random points), its gap
``(opt - bound) / opt`` on random 30-point Euclidean instances with optima
certified by MILP (median, max), and on the TSPLIB instances.

Times are wall times after JIT warm-up; the machine may be shared and busy
(the load average is printed), so compare within one run.

    python benchmarks/tsplib.py [--seeds 5] [--limit 1.0] [--json out/tsplib.json]
        [--skip-peers] [--instances eil51,berlin52] [--workers N | --scheduler ADDRESS]

Our solves run here by default (``--workers 0``: times without contention);
``--workers N`` / ``--scheduler`` spread them as ``subtask-opt batch`` does.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

from subtask_opt import MaxRuntime, SolverParams, milp_optimum, solve
from subtask_opt.base.stop import StoppingCriterion
from subtask_opt.batch import map_jobs
from subtask_opt.cli._common import add_workers, where_text, workers_options
from subtask_opt.tour.bound import lower_bound
from subtask_opt.tour.problem import MatrixProblem
from subtask_opt.tour.tsplib import read_tsplib

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tsplib"


def _gap(length: float, optimum: float) -> float:
    return (length - optimum) / optimum


def _tour_length(matrix: np.ndarray, tour) -> int:
    t = np.asarray(tour, dtype=np.int64)
    if sorted(t.tolist()) != list(range(len(matrix))):
        raise RuntimeError(f"a peer returned an invalid tour of {len(t)} cities")
    return int(matrix[t, np.roll(t, -1)].sum())


def _solve_one(job: tuple[np.ndarray, int, int, float | None]) -> tuple[float, float, float, int]:
    """One of our solves (in a worker): gap, wall time, build time, generations."""
    matrix, optimum, seed, limit = job
    params = SolverParams()
    t0 = time.perf_counter()
    problem = MatrixProblem(matrix)
    t1 = time.perf_counter()
    stop: list[StoppingCriterion] = (params.default_stop() if limit is None
                                     else [MaxRuntime(limit)])
    result = solve(problem, seed=seed, params=params, stop=stop)
    t2 = time.perf_counter()
    return _gap(_tour_length(matrix, result.order), optimum), t2 - t0, t1 - t0, result.generations


def _warm() -> None:
    """The GA's kernels loaded once per worker, before its first timed solve."""
    warm = np.random.default_rng(0).random((12, 12)) + 1
    solve(MatrixProblem(warm + warm.T), seed=0)


def run_ours(instances: list[tuple[np.ndarray, int]], seeds: int, limit: float | None,
             where: dict) -> list[dict]:
    """Every ``(matrix, optimum)`` from ``seeds`` seeds, on the workers ``where`` names."""
    jobs = [(m, opt, seed, limit) for m, opt in instances for seed in range(seeds)]
    outs = map_jobs(_solve_one, jobs, **where, warm_up=_warm)
    rows = []
    for k in range(len(instances)):
        part = outs[k * seeds:(k + 1) * seeds]
        rows.append({"gaps": [o[0] for o in part], "wall_s": [o[1] for o in part],
                     "build_s": [o[2] for o in part], "generations": [o[3] for o in part]})
    return rows


def run_fast_tsp(matrix: np.ndarray, optimum: int, limit: float, repeats: int) -> dict | None:
    try:
        import fast_tsp
    except ImportError:
        return None
    gaps, walls = [], []
    for _ in range(repeats):
        t = time.perf_counter()
        tour = fast_tsp.find_tour(matrix.tolist(), limit)
        walls.append(time.perf_counter() - t)
        gaps.append(_gap(_tour_length(matrix, tour), optimum))
    return {"gaps": gaps, "wall_s": walls}


def run_elkai(matrix: np.ndarray, optimum: int) -> dict | None:
    try:
        import elkai
    except ImportError:
        return None
    t = time.perf_counter()
    tour = elkai.DistanceMatrix(matrix.tolist()).solve_tsp()
    wall = time.perf_counter() - t
    return {"gaps": [_gap(_tour_length(matrix, tour[:-1]), optimum)], "wall_s": [wall]}


def _ortools_tour(matrix: np.ndarray, limit: float) -> tuple[list[int], float]:
    """One guided-local-search solve (runs in the child process)."""
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    t = time.perf_counter()
    n = len(matrix)
    manager = pywrapcp.RoutingIndexManager(n, 1, 0)
    routing = pywrapcp.RoutingModel(manager)
    transit = routing.RegisterTransitMatrix(matrix.tolist())  # no Python callback per arc
    routing.SetArcCostEvaluatorOfAllVehicles(transit)
    search = pywrapcp.DefaultRoutingSearchParameters()
    search.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    search.local_search_metaheuristic = (
        routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH)
    search.time_limit.FromMilliseconds(int(limit * 1000))
    solution = routing.SolveWithParameters(search)
    index, tour = routing.Start(0), []
    while not routing.IsEnd(index):
        tour.append(manager.IndexToNode(index))
        index = solution.Value(routing.NextVar(index))
    return tour, time.perf_counter() - t


def run_ortools(matrix: np.ndarray, optimum: int, limit: float, pool) -> dict | None:
    if pool is None:
        return None
    tour, wall = pool.submit(_ortools_tour, matrix, limit).result()
    return {"gaps": [_gap(_tour_length(matrix, tour), optimum)], "wall_s": [wall]}


def _ortools_pool():
    import importlib.util
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    if importlib.util.find_spec("ortools") is None:
        return None
    return ProcessPoolExecutor(max_workers=1, mp_context=get_context("spawn"))


def bound_timing(sizes: tuple[int, ...], seed: int = 0) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = []
    for n in sizes:
        pts = rng.random((n, 2)) * 1000
        m = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
        t = time.perf_counter()
        lower_bound(m)
        rows.append({"n": n, "seconds": time.perf_counter() - t})
    return rows


def bound_gaps_random30(instances: int, seed: int = 1) -> list[float]:
    rng = np.random.default_rng(seed)
    gaps = []
    for _ in range(instances):
        pts = rng.random((30, 2))
        m = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
        opt, _ = milp_optimum(m)
        gaps.append((opt - lower_bound(m)) / opt)
    return gaps


def _cell(run: dict | None) -> str:
    if run is None:
        return f"{'-':>8} {'-':>7}"
    return f"{100 * statistics.median(run['gaps']):7.2f}% {statistics.median(run['wall_s']):7.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds of our solver (default 5)")
    ap.add_argument("--limit", type=float, default=1.0,
                    help="time limit of the limited runs, fast_tsp and OR-Tools (default 1 s)")
    ap.add_argument("--instances", default="", help="comma-separated subset (default all)")
    ap.add_argument("--skip-peers", action="store_true", help="only our solver and the bound")
    ap.add_argument("--random30", type=int, default=20,
                    help="random 30-point instances for the bound's gap (default 20)")
    ap.add_argument("--json", metavar="OUT.json", help="write every number as JSON")
    add_workers(ap, what="our solves", serial_default=True)
    args = ap.parse_args()
    where = workers_options(args)

    optima = json.loads((DATA / "optima.json").read_text())["optimum"]
    wanted = [s for s in args.instances.split(",") if s] or sorted(optima, key=lambda k: (
        int("".join(ch for ch in k if ch.isdigit()) or 0), k))
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")

    # warm-up: JIT compile of the GA and the bound kernels (reported, kept out of the table)
    t = time.perf_counter()
    warm = np.random.default_rng(0).random((12, 12)) + 1
    warm = warm + warm.T
    solve(MatrixProblem(warm), seed=0)
    lower_bound(warm)
    print(f"JIT warm-up (compile or cache load): {time.perf_counter() - t:.1f} s")

    tsps = {name: read_tsplib(DATA / f"{name}.tsp") for name in wanted}
    pairs = [(tsps[name].matrix, int(optima[name])) for name in wanted]
    ours_default = run_ours(pairs, args.seeds, None, where)
    ours_limit = run_ours(pairs, args.seeds, args.limit, where)
    print(f"our solves ran on {where_text(where)}")
    pool = None if args.skip_peers else _ortools_pool()
    rows = []
    for k, name in enumerate(wanted):
        inst = tsps[name]
        m = inst.matrix
        opt = int(optima[name])
        row: dict = {"name": name, "n": inst.dimension, "optimum": opt}
        row["ours_default"] = ours_default[k]
        row["ours_limit"] = ours_limit[k]
        if not args.skip_peers:
            row["fast_tsp"] = run_fast_tsp(m, opt, args.limit, 1)
            row["elkai"] = run_elkai(m, opt)
            row["ortools"] = run_ortools(m, opt, args.limit, pool)
        t = time.perf_counter()
        row["bound"] = lower_bound(m)
        row["bound_s"] = time.perf_counter() - t
        row["bound_gap"] = (opt - row["bound"]) / opt
        rows.append(row)
        print(f"  {name} done", flush=True)
    if pool is not None:
        pool.shutdown()

    print(f"\nmedian gap to the published optimum and median wall time [s]; ours: "
          f"{args.seeds} seeds; peers: one run; limit {args.limit:g} s (elkai: none)")
    head = (f"{'instance':>9} {'N':>5} | {'ours default':>16} {'gens':>5} | "
            f"{'ours ' + format(args.limit, 'g') + ' s':>16} | {'fast_tsp':>16} | "
            f"{'elkai (LKH)':>16} | {'OR-Tools GLS':>16} | {'build s':>7}")
    print(head)
    print("-" * len(head))
    for r in rows:
        d = r["ours_default"]
        print(f"{r['name']:>9} {r['n']:>5} | {_cell(d)} {statistics.median(d['generations']):5.0f}"
              f" | {_cell(r['ours_limit'])} | {_cell(r.get('fast_tsp'))} | "
              f"{_cell(r.get('elkai'))} | {_cell(r.get('ortools'))} | "
              f"{statistics.median(d['build_s']):7.3f}")

    print("\nHeld-Karp lower bound (default 1000 iterations, no upper given)")
    print(f"{'instance':>9} {'N':>5} {'bound':>9} {'optimum':>9} {'gap':>7} {'time s':>7}")
    for r in rows:
        print(f"{r['name']:>9} {r['n']:>5} {r['bound']:9.0f} {r['optimum']:9d} "
              f"{100 * r['bound_gap']:6.2f}% {r['bound_s']:7.2f}")
    timing = bound_timing((30, 100, 300, 1000))
    print("time on uniform random points: " + ", ".join(
        f"N={t['n']}: {t['seconds']:.3f} s" for t in timing))
    gaps = bound_gaps_random30(args.random30) if args.random30 > 0 else []
    if gaps:
        print(f"gap (opt - bound) / opt on {len(gaps)} random 30-point Euclidean instances "
              f"(MILP optima): median {100 * statistics.median(gaps):.2f}%, "
              f"max {100 * max(gaps):.2f}%")
    if args.json:
        out = Path(args.json)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"limit_s": args.limit, "seeds": args.seeds, "rows": rows,
                                   "bound_timing": timing, "bound_gaps_random30": gaps},
                                  indent=1) + "\n")
        print(f"wrote {out}")


if __name__ == "__main__":
    main()

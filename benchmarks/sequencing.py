"""How often and how fast the micro-GA finds the certified optimum, beside peers.

Instances: square20 and random30 from 10 generator seeds (robot and time
model selectable). Each instance's optimum is certified by an exact MILP with
subtour cuts (HiGHS, :func:`subtask_opt.tour.exact.milp_optimum`), not taken from
our own runs. Both presets solve every instance from ``--seeds`` seeds; the
peers OR-Tools (guided local search) and elkai (LKH-3) solve the same
matrices in the same run when installed (``pip install -e '.[bench]'``).

Times are wall times of the search after JIT warm-up (the compile time of the
first call is reported apart); the machine is shared and noisy, so compare
medians and ratios within one run.

    python benchmarks/sequencing.py [--seeds 100] [--robot planar_2r]
        [--time-model trapezoid] [--json out/sequencing.json]
        [--workers N | --scheduler tcp://host:8786]

Our solves run here by default (``--workers 0``: per-solve times without
contention); ``--workers N`` / ``--scheduler`` spread them as ``subtask-opt
batch`` does (same answers; the times then share the cores).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from subtask_opt import SolverParams, builtin_case, milp_optimum, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.base.progress import progress_bar
from subtask_opt.batch import map_jobs
from subtask_opt.cli._common import add_workers, where_text, workers_options
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.exact import tour_length
from subtask_opt.tour.problem import MatrixProblem

# generation at which the paper reports the optimum (its Figs. 10 and 13)
PAPER_GENERATIONS = {"square20": 500, "random30": 800}
REL_TOL = 1e-9


def instances(robot: str, time_model: str) -> list[tuple[str, str, np.ndarray]]:
    arm = load_planar_arm(robot)
    out = [("square20", "square20", PlanarProblem(builtin_case("square20", arm), arm,
                                                      time_model=time_model).matrix)]
    for g in range(10):
        sub = builtin_case("random30", arm, seed=g)
        out.append(("random30", f"random30/{g}",
                    PlanarProblem(sub, arm, time_model=time_model).matrix))
    return out


def _solve_one(job: tuple[np.ndarray, str, int]) -> tuple[float, int, float]:
    """One solve (in a worker): total time, generation of the best tour, search time."""
    matrix, preset, seed = job
    r = solve(MatrixProblem(matrix), seed=seed,
              params=SolverParams(preset=preset))
    return float(r.total_time), int(r.history.generation_of_best()), float(r.runtime_s)


def _warm() -> None:
    """Both presets' kernels loaded once per worker, before its first timed solve."""
    m = np.random.default_rng(0).random((8, 8)) + 1
    for preset in ("default", "paper"):
        _solve_one((m + m.T, preset, 0))


def run_ours(matrices: list[np.ndarray], optima: list[float], preset: str, seeds: int,
             where: dict) -> list[dict]:
    """Every matrix from ``seeds`` seeds, all solves on the workers ``where`` names."""
    jobs = [(m, preset, seed) for m in matrices for seed in range(seeds)]
    outs = map_jobs(_solve_one, jobs, **where, warm_up=_warm, progress=True, desc=preset)
    rows = []
    for k, optimum in enumerate(optima):
        hits, gens, times = 0, [], []
        for total, best_gen, runtime in outs[k * seeds:(k + 1) * seeds]:
            times.append(runtime)
            if total <= optimum * (1 + REL_TOL):
                hits += 1
                gens.append(best_gen)
        rows.append({"success": hits, "runs": seeds, "generations_to_optimum": gens,
                     "times_s": times})
    return rows


def run_elkai(matrix: np.ndarray, optimum: float, repeats: int) -> dict | None:
    try:
        import elkai
    except ImportError:
        return None
    scaled = np.rint(matrix / matrix[matrix > 0].min() * 1000).astype(int).tolist()
    hits, times = 0, []
    for _ in range(repeats):
        t = time.perf_counter()
        tour = elkai.DistanceMatrix(scaled).solve_tsp()
        times.append(time.perf_counter() - t)
        hits += tour_length(matrix, np.array(tour[:-1])) <= optimum * (1 + 1e-6)
    return {"success": hits, "runs": repeats, "times_s": times}


def _ortools_tour(scaled: np.ndarray, limit_s: float) -> tuple[list[int], float]:
    """One OR-Tools guided-local-search solve; runs in a child process (see run_ortools)."""
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    n = len(scaled)
    manager = pywrapcp.RoutingIndexManager(n, 1, 0)
    routing = pywrapcp.RoutingModel(manager)

    def cost(i: int, j: int) -> int:
        return int(scaled[manager.IndexToNode(i), manager.IndexToNode(j)])

    routing.SetArcCostEvaluatorOfAllVehicles(routing.RegisterTransitCallback(cost))
    search = pywrapcp.DefaultRoutingSearchParameters()
    search.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    search.local_search_metaheuristic = (
        routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH)
    search.time_limit.FromMilliseconds(int(limit_s * 1000))
    t = time.perf_counter()
    solution = routing.SolveWithParameters(search)
    seconds = time.perf_counter() - t
    index, tour = routing.Start(0), []
    while not routing.IsEnd(index):
        tour.append(manager.IndexToNode(index))
        index = solution.Value(routing.NextVar(index))
    return tour, seconds


def run_ortools(matrix: np.ndarray, optimum: float, repeats: int, limit_s: float,
                pool) -> dict | None:
    """OR-Tools in a separate process: it and highspy (our MILP) each bundle HiGHS, and
    the two builds cannot be loaded into one process."""
    if pool is None:
        return None
    scaled = np.rint(matrix / matrix[matrix > 0].min() * 1000).astype(int)
    hits, times = 0, []
    for _ in range(repeats):
        tour, seconds = pool.submit(_ortools_tour, scaled, limit_s).result()
        times.append(seconds)
        hits += tour_length(matrix, np.array(tour)) <= optimum * (1 + 1e-6)
    return {"success": hits, "runs": repeats, "times_s": times}


def _ortools_pool():
    import importlib.util
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    if importlib.util.find_spec("ortools") is None:
        return None
    return ProcessPoolExecutor(max_workers=1, mp_context=get_context("spawn"))


def _median_ms(values: list[float]) -> float:
    return statistics.median(values) * 1e3 if values else float("nan")


def _p90(values: list[int]) -> float:
    return float(np.percentile(values, 90)) if values else float("nan")


def _peer_cells(run: dict | None) -> tuple[str, float]:
    if run is None:
        return "  n/a ", float("nan")
    return f"{run['success']:>3}/{run['runs']:<2}", _median_ms(run["times_s"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--peer-repeats", type=int, default=10)
    ap.add_argument("--ortools-limit", type=float, default=1.0,
                    help="OR-Tools guided local search time limit per solve [s]")
    ap.add_argument("--robot", default="planar_2r")
    ap.add_argument("--time-model", default="trapezoid")
    ap.add_argument("--json", type=Path)
    add_workers(ap, what="our solves", serial_default=True)
    args = ap.parse_args()
    where = workers_options(args)

    cases = instances(args.robot, args.time_model)
    t = time.perf_counter()
    optima = [milp_optimum(m)[0] for _, _, m in cases]
    certify_s = time.perf_counter() - t

    compile_s = {}
    for preset in ("default", "paper"):  # first calls compile (or load the numba cache)
        t = time.perf_counter()
        solve(MatrixProblem(cases[0][2]), seed=0,
              params=SolverParams(preset=preset))
        compile_s[preset] = time.perf_counter() - t

    rows = []
    ours = {preset: run_ours([m for _, _, m in cases], optima, preset, args.seeds, where)
            for preset in ("default", "paper")}
    pool = _ortools_pool()
    with progress_bar(True, total=len(cases), desc="peers") as bar:
        for k, ((family, name, matrix), optimum) in enumerate(zip(cases, optima, strict=True)):
            row = {"instance": name, "family": family, "n": len(matrix), "optimum": optimum}
            for preset in ("default", "paper"):
                row[preset] = ours[preset][k]
            row["elkai"] = run_elkai(matrix, optimum, args.peer_repeats)
            row["ortools"] = run_ortools(matrix, optimum, args.peer_repeats, args.ortools_limit,
                                         pool)
            rows.append(row)
            bar.update()

    if pool is not None:
        pool.shutdown()
    print(f"\nsequencing benchmark: robot {args.robot}, time model {args.time_model}, "
          f"{args.seeds} seeds per preset on {where_text(where)}; "
          f"optima certified by MILP in {certify_s:.2f} s")
    print("compile / cache load of the first call: "
          + ", ".join(f"{k} {v:.2f} s" for k, v in compile_s.items()))
    head = (f"{'instance':<12} {'optimum':>9} | {'default':>8} {'med ms':>7} {'gens':>5} | "
            f"{'paper':>7} {'med gen':>7} {'p90 gen':>7} {'paper*':>6} {'med ms':>7} | "
            f"{'elkai':>6} {'med ms':>7} | {'ortools':>7} {'med ms':>7}")
    print(head)
    print("-" * len(head))
    for r in rows:
        d, p, e, o = r["default"], r["paper"], r["elkai"], r["ortools"]
        (es, et), (os_, ot) = _peer_cells(e), _peer_cells(o)
        print(f"{r['instance']:<12} {r['optimum']:>9.4f} | "
              f"{d['success']:>4}/{d['runs']:<3} {_median_ms(d['times_s']):>7.3f} "
              f"{statistics.median(d['generations_to_optimum'] or [float('nan')]):>5.0f} | "
              f"{p['success']:>3}/{p['runs']:<3} "
              f"{statistics.median(p['generations_to_optimum'] or [float('nan')]):>7.0f} "
              f"{_p90(p['generations_to_optimum']):>7.0f} {PAPER_GENERATIONS[r['family']]:>6} "
              f"{_median_ms(p['times_s']):>7.2f} | {es:>6} {et:>7.2f} | {os_:>7} {ot:>7.1f}")
    all_default = [t for r in rows for t in r["default"]["times_s"]]
    all_elkai = [t for r in rows if r["elkai"] for t in r["elkai"]["times_s"]]
    print(f"\ndefault preset: {sum(r['default']['success'] for r in rows)}/"
          f"{sum(r['default']['runs'] for r in rows)} runs at the certified optimum, "
          f"median {_median_ms(all_default):.3f} ms per solve")
    if all_elkai:
        print(f"elkai (LKH-3): median {_median_ms(all_elkai):.2f} ms per solve "
              f"({_median_ms(all_elkai) / _median_ms(all_default):.1f}x the default preset)")
    print("paper*: generation at which the paper reports reaching the optimum")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({
            "robot": args.robot, "time_model": args.time_model, "seeds": args.seeds,
            "compile_s": compile_s, "certify_s": certify_s, "rows": rows}, indent=1))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()

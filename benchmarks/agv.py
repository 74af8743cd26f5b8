"""AGV benchmarks (seed 004): quadtree vs grid planning, the paper scenarios,
and the 200-run random suite (odometry drift on; with and without corner
check points) with and without the t-second collision check.

    .venv/bin/python benchmarks/agv.py [--n 200] [--seed 0] [--json OUT] [--out DIR]
        [--workers N | --scheduler tcp://host:8786]

The suites run here by default; ``--workers N`` / ``--scheduler`` spread their
runs as ``subtask-opt batch`` does (same report).

``--out DIR`` also writes a GIF and a route figure of each paper scenario and
a quadtree figure of experiment 1's map. Timings exclude JIT compilation (one
warm-up run first).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from subtask_opt.batch import suite_mapper, warm_agv
from subtask_opt.cli._common import add_workers, where_text, workers_options
from subtask_opt.planners.agv.quadtree import compare_with_grid, decompose
from subtask_opt.planners.agv.scenarios import (
    PAPER_SCENARIOS,
    random_agv_scenario,
    run_agv_suite,
    suite_params,
)
from subtask_opt.planners.agv.simulation import simulate


def quadtree_vs_grid(seed: int, n_maps: int = 20) -> list[dict]:
    rows = []
    sc = PAPER_SCENARIOS["1"]()
    rows.append({"map": "experiment 1", **_flat(compare_with_grid(sc.world, sc.start, sc.goal))})
    for i in range(n_maps):
        rs = random_agv_scenario(seed + i, n_obstacles=0)
        rows.append({"map": f"random {seed + i}",
                     **_flat(compare_with_grid(rs.world, rs.start, rs.goal))})
    return rows


def _flat(cmp: dict) -> dict:
    return {f"{k}_{f}": v for k, row in cmp.items() for f, v in row.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json")
    ap.add_argument("--out")
    add_workers(ap, what="the suite runs", serial_default=True)
    args = ap.parse_args()
    where = workers_options(args)

    simulate(random_agv_scenario(10_000), seed=0)  # warm-up: JIT compile outside the timings

    print("== quadtree vs 8-connected grid (octile distance transform), same map ==")
    rows = quadtree_vs_grid(args.seed)
    print(f"{'map':<14} {'qt nodes':>8} {'grid nodes':>10} {'qt ms':>7} {'grid ms':>8} "
          f"{'qt len':>7} {'grid len':>8}")
    for r in rows:
        print(f"{r['map']:<14} {r['quadtree_nodes']:>8} {r['grid_nodes']:>10} "
              f"{1e3 * r['quadtree_time_s']:>7.2f} {1e3 * r['grid_time_s']:>8.2f} "
              f"{r['quadtree_length']:>7.2f} {r['grid_length']:>8.2f}")
    q = np.array([r["quadtree_length"] / r["grid_length"] for r in rows])
    nodes = np.array([r["quadtree_nodes"] / r["grid_nodes"] for r in rows])
    print(f"mean quadtree/grid: length {q.mean():.3f}, graph nodes {nodes.mean():.3f}")

    print("\n== paper scenarios ==")
    paper = {}
    for name, make in PAPER_SCENARIOS.items():
        run = simulate(make())
        paper[name] = run.to_dict(trajectory=False)
        print(run.summary())
        if args.out:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            from subtask_opt.plotting import agv as plots

            out = Path(args.out)
            out.mkdir(parents=True, exist_ok=True)
            plots.animate_run(run, out / f"agv_{name}.gif")
            plots.save_run_figure(run, out / f"agv_{name}.png")
            if name == "1":
                tree = decompose(run.world.occupancy)
                fig = plots.plot_quadtree(tree, run.world.occupancy)
                fig.savefig(out / "agv_quadtree.png", dpi=120, bbox_inches="tight")
                plt.close(fig)

    print(f"\n== random suite: {args.n} runs from seed {args.seed} on {where_text(where)} ==")
    t0 = time.perf_counter()
    mapper = suite_mapper(**where, progress=True, desc="agv suite", warm_up=warm_agv)
    on = run_agv_suite(args.n, args.seed, map_runs=mapper)
    print(on.summary())
    off = run_agv_suite(args.n, args.seed, map_runs=mapper,
                        params=replace(suite_params(), collision_check=False))
    print(off.summary())
    if args.out:
        from subtask_opt.plotting import agv as plots

        plots.save_suite_figure(on, Path(args.out) / "agv_suite.png")
    print(f"both suites: {time.perf_counter() - t0:.1f} s wall")

    if args.json:
        payload = {"quadtree_vs_grid": rows, "paper": paper, "suite": on.to_dict(),
                   "suite_no_check": off.to_dict()}
        Path(args.json).write_text(json.dumps(payload, indent=2, default=_safe) + "\n")


def _safe(v):
    if isinstance(v, (np.floating, float)):
        return None if not math.isfinite(float(v)) else float(v)
    if isinstance(v, np.integer):
        return int(v)
    return str(v)


if __name__ == "__main__":
    main()

"""MAKLINK + Dijkstra + improved Dijkstra + PSO vs the exact visibility-graph optimum.

Prints (1) the paper's Table 1 for this project's start/goal pairs on seed003
(the paper states none) with the exact optimum as the last column, and (2)
timings after JIT warm-up: the whole pipeline (graph built from scratch,
Dijkstra, improvement, PSO) and the visibility graph (built from scratch, and
the cached ``shortest_path_length`` query). The JIT compile time of the first
call is reported separately.

Run: ``.venv/bin/python benchmarks/maklink.py [--runs 20] [--repeat 30] [--json OUT]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from subtask_opt.planners.polygon import maklink, pso, visibility
from subtask_opt.planners.polygon.maklink_table import SEED003_PAIRS, format_table, table_rows
from subtask_opt.planners.polygon.world import PolygonWorld


def fresh(world: PolygonWorld) -> PolygonWorld:
    """An equal world with empty caches (so graphs are built inside the timing)."""
    return PolygonWorld.from_dict(world.to_dict())


def median_ms(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def timings(world: PolygonWorld, start, goal, repeat: int) -> dict[str, float]:
    s, g = np.asarray(start, float), np.asarray(goal, float)
    worlds = [fresh(world) for _ in range(repeat)]
    it = iter(worlds)
    pipeline = median_ms(lambda: pso.plan(next(it), s, g, seed=0), repeat)
    graph_ms = median_ms(lambda: maklink.build_graph(world), repeat)
    graph = maklink.graph_for(world)
    route_ms = median_ms(lambda: graph.route(s, g), repeat)
    _, ids = graph.route(s, g)
    path = np.vstack([s, graph.midpoints[ids], g])
    improve_ms = median_ms(lambda: maklink.crossed_links(graph, maklink.shortcut(world, path)),
                           repeat)
    crossed, t0 = maklink.crossed_links(graph, maklink.shortcut(world, path))
    links = graph.links[crossed]
    pso_ms = median_ms(lambda: pso.optimize_crossings(links, s, g, t0, seed=0), repeat)
    worlds = [fresh(world) for _ in range(repeat)]
    it = iter(worlds)
    vis_cold = median_ms(lambda: visibility.plan(next(it), s, g), repeat)
    vis_query = median_ms(lambda: visibility.shortest_path_length(world, s, g), repeat)
    return {"pipeline_ms": pipeline, "graph_ms": graph_ms, "dijkstra_ms": route_ms,
            "improve_ms": improve_ms, "pso_ms": pso_ms,
            "visibility_ms": vis_cold, "visibility_query_ms": vis_query}


def _pt(p) -> str:
    return f"({p[0]:g}, {p[1]:g})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20, help="PSO seeds per pair in the table")
    ap.add_argument("--repeat", type=int, default=50, help="repetitions per timing (median)")
    ap.add_argument("--json", type=Path, help="write all figures as JSON")
    args = ap.parse_args()

    world = PolygonWorld.builtin("seed003")
    t0 = time.perf_counter()
    pso.plan(fresh(world), *SEED003_PAIRS[0], seed=0)
    visibility.plan(world, *SEED003_PAIRS[0])
    print(f"JIT warm-up (first calls, compile or cache load): {time.perf_counter() - t0:.2f} s\n")

    rows = table_rows(world, SEED003_PAIRS, runs=args.runs)
    print(format_table(rows, title="Table 1 on seed003: path lengths"))

    print("\nTimings after warm-up (median ms of each stage, measured separately; 'pipeline' "
          "and 'visibility' build their graph from scratch):")
    head = (f"{'start':>12} {'goal':>12} {'pipeline':>9} {'graph':>7} {'Dijkstra':>9} "
            f"{'improve':>8} {'PSO':>7} {'visibility':>11} {'vis query':>10}")
    print(head)
    print("-" * len(head))
    timing_rows = []
    for start, goal in SEED003_PAIRS:
        t = timings(world, start, goal, args.repeat)
        timing_rows.append({"start": start, "goal": goal, **t})
        pair = f"{_pt(start):>12} {_pt(goal):>12}"
        print(f"{pair} {t['pipeline_ms']:9.2f} {t['graph_ms']:7.2f} "
              f"{t['dijkstra_ms']:9.3f} {t['improve_ms']:8.3f} {t['pso_ms']:7.2f} "
              f"{t['visibility_ms']:11.3f} {t['visibility_query_ms']:10.3f}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"table": rows, "timings": timing_rows}, indent=1))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()

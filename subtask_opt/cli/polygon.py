"""CLI commands for the polygon planners (registered by :func:`register`).

``subtask-opt plan polygon``   one path in a polygon world with any registered
                               polygon planner (``planners("polygon")``)
``subtask-opt bench maklink``  the seed paper's Table 1 for chosen start/goal pairs

Exit codes: 0 a path was found (every pair, for the bench), 1 the planner ran
and found none, 2 bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from subtask_opt.cli._common import (
    EXIT_FAILED,
    EXIT_OK,
    MAX_RUNTIME_S,
    add_no_progress,
    add_outputs,
    float_in,
    int_in,
    output_file,
    point,
    refuse_overwriting_inputs,
    seed,
    write_json,
)

_WORLD_HELP = "a built-in world name (seed003) or a JSON world file (default seed003)"


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan polygon`` and ``bench maklink``."""
    from subtask_opt.planners.base import planners

    found = planners("polygon")
    listing = "; ".join(f"{name}: {info.description}" for name, info in found.items())
    stochastic = [name for name, info in found.items() if info.stochastic]
    p = plan.add_parser(
        "polygon", help="plan in a polygon world (MAKLINK + Dijkstra / PSO, visibility graph)",
        description="Plan a path among polygon obstacles and compare it with the exact "
                    f"optimum (visibility graph). Planners: {listing}.")
    p.add_argument("--world", default="seed003", metavar="NAME|PATH.json", help=_WORLD_HELP)
    p.add_argument("--start", type=point, required=True, metavar="X,Y")
    p.add_argument("--goal", type=point, required=True, metavar="X,Y")
    p.add_argument("--planner", choices=list(found), default="pso",
                   help=f"one of {', '.join(found)} (default pso)")
    p.add_argument("--seed", type=seed, default=0,
                   help=f"random seed of the stochastic planners ({', '.join(stochastic)}); "
                        "deterministic ones ignore it (default 0)")
    _add_pso_options(p)
    add_outputs(p, what="the result (path, length, history, optimum)",
                plot="a figure of the world, the free links and the path")
    add_no_progress(p)
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "maklink", help="seed paper 003's Table 1: Dijkstra, improved, PSO vs the exact optimum",
        description="Path lengths of Dijkstra, improved Dijkstra and improved Dijkstra + PSO over "
                    "the MAKLINK graph, with the exact optimum (visibility graph) as the last "
                    "column. The paper does not state its start and goal; the default pairs on "
                    "seed003 are this project's choice.")
    b.add_argument("--world", default="seed003", metavar="NAME|PATH.json", help=_WORLD_HELP)
    b.add_argument("--pair", nargs=2, type=point, action="append", metavar=("START", "GOAL"),
                   help="a start/goal pair X,Y X,Y (repeatable; default: the built-in pairs "
                        "for seed003)")
    b.add_argument("--runs", type=int_in(1, 10_000), default=10, metavar="N",
                   help="PSO seeds per pair, N in [1, 10000] (default 10)")
    b.add_argument("--seed", type=seed, default=0,
                   help="first PSO seed; run k uses seed + k (default 0)")
    _add_pso_options(b)
    add_outputs(b, what="the table rows", plot="a figure of the first pair's paths")
    add_no_progress(b)
    b.set_defaults(handler=_run_bench)


def _add_pso_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("PSO", "swarm and stopping criteria (first met stops)")
    g.add_argument("--swarm", type=int_in(1, 10_000), default=None, metavar="N",
                   help="particles, N in [1, 10000] (default 40)")
    g.add_argument("--iterations", type=int_in(1, 1_000_000), default=200, metavar="N",
                   help="at most N iterations, N in [1, 1000000] (default 200)")
    g.add_argument("--stall", type=int_in(1, 1_000_000), default=50, metavar="N",
                   help="stop after N iterations without improvement, N in [1, 1000000] "
                        "(default 50)")
    g.add_argument("--time-limit", type=float_in(0.0, MAX_RUNTIME_S, open_low=True),
                   default=None, metavar="S",
                   help=f"stop after S seconds, S in (0, {MAX_RUNTIME_S:g}]")


def _pso_setup(args: argparse.Namespace) -> tuple[Any, list[Any]]:
    from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement
    from subtask_opt.planners.polygon.pso import PSOParams

    params = PSOParams() if args.swarm is None else PSOParams(swarm=args.swarm)
    stop: list[Any] = [MaxGenerations(args.iterations), NoImprovement(args.stall)]
    if args.time_limit is not None:
        stop.append(MaxRuntime(args.time_limit))
    return params, stop


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.polygon.compare import plan_against_optimum
    from subtask_opt.planners.polygon.world import load_world

    refuse_overwriting_inputs([args.world], [args.json, args.plot])
    world = load_world(args.world)
    params, stop = _pso_setup(args)
    with progress_bar(not args.no_progress, total=args.iterations, desc=args.planner,
                      unit="it") as bar:
        done = [0]

        def tick(progress: Any) -> None:
            bar.update(progress.generation - done[0])
            done[0] = progress.generation

        run = plan_against_optimum(world, args.planner, args.start, args.goal, params=params,
                                   seed=args.seed, stop=stop, on_chunk=tick)
    result = run.result
    print(f"world {world.name or args.world}: {len(world.obstacles)} obstacles, "
          f"start ({args.start[0]:g}, {args.start[1]:g}) -> goal "
          f"({args.goal[0]:g}, {args.goal[1]:g})")
    print(result.summary())
    for line in run.report_lines():
        print(f"  {line}")
    if args.json:
        write_json(args.json, run.to_dict())
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting import polygon as plot

        fig = plot.planner_figure(world, {args.planner: result}, optimum=run.optimum,
                                  graph=run.graph,
                                  title=f"{world.name or args.world}: {args.planner}")
        with output_file(args.plot) as tmp:
            plot.save(fig, tmp)
        print(f"wrote {args.plot}")
    if not result.success:
        print(f"subtask-opt: failed: {result.planner}: {result.message}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def _run_bench(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.polygon.maklink_table import (
        default_pairs,
        first_pair_results,
        format_table,
        table_rows,
    )
    from subtask_opt.planners.polygon.world import load_world

    refuse_overwriting_inputs([args.world], [args.json, args.plot])
    world = load_world(args.world)
    pairs = ([(tuple(s), tuple(g)) for s, g in args.pair] if args.pair
             else default_pairs(world))
    params, stop = _pso_setup(args)
    with progress_bar(not args.no_progress, total=len(pairs) * args.runs, desc="PSO runs",
                      unit="run") as bar:
        rows = table_rows(world, pairs, runs=args.runs, seed=args.seed, params=params,
                          stop=stop, on_run=lambda: bar.update(1))
    print(format_table(rows, title=f"Table 1 on {world.name or args.world}: path lengths"))
    if args.json:
        write_json(args.json, {"world": world.name or args.world, "rows": rows})
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting import polygon as plot

        results, graph, optimum = first_pair_results(world, pairs[0], params=params,
                                                     seed=args.seed, stop=stop)
        (sx, sy), (gx, gy) = pairs[0]
        fig = plot.planner_figure(
            world, results, optimum=optimum, graph=graph,
            title=f"{world.name or args.world}: Dijkstra, improved, PSO, optimum\n"
                  f"({sx:g}, {sy:g}) -> ({gx:g}, {gy:g})")
        with output_file(args.plot) as tmp:
            plot.save(fig, tmp)
        print(f"wrote {args.plot}")
    failed = [k + 1 for k, r in enumerate(rows) if not r["found"]]
    if failed:
        print(f"subtask-opt: failed: no collision-free path for pair(s) "
              f"{', '.join(map(str, failed))}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK

"""CLI commands for the polygon planners (registered by :func:`register`).

``subtask-opt plan polygon``   one path in a polygon world (MAKLINK Dijkstra,
                               improved Dijkstra, PSO, or the exact visibility path)
``subtask-opt bench maklink``  the seed paper's Table 1 for chosen start/goal pairs
"""

from __future__ import annotations

import argparse
from typing import Any

from subtask_opt.cli._common import point, positive_float, positive_int, write_json

PLANNERS = ("dijkstra", "improved", "pso", "visibility")


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan polygon`` and ``bench maklink``."""
    p = plan.add_parser(
        "polygon", help="plan in a polygon world (MAKLINK + Dijkstra / PSO, visibility graph)",
        description="Plan a path among polygon obstacles: Dijkstra over the MAKLINK free-link "
                    "graph, improved Dijkstra, improved Dijkstra + PSO (seed paper 003), or the "
                    "exact shortest path over the visibility graph.")
    p.add_argument("--world", default="seed003", metavar="NAME|PATH.json",
                   help="built-in world name (seed003) or a JSON world file (default seed003)")
    p.add_argument("--start", type=point, required=True, metavar="X,Y")
    p.add_argument("--goal", type=point, required=True, metavar="X,Y")
    p.add_argument("--planner", choices=PLANNERS, default="pso")
    p.add_argument("--seed", type=int, default=0, help="PSO random seed (default 0)")
    _add_pso_options(p)
    p.add_argument("--json", metavar="OUT", help="write the result as JSON")
    p.add_argument("--plot", metavar="OUT.png", help="write a figure of the world, links and path")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "maklink", help="seed paper 003's Table 1: Dijkstra, improved, PSO vs the exact optimum",
        description="Path lengths of Dijkstra, improved Dijkstra and improved Dijkstra + PSO over "
                    "the MAKLINK graph, with the exact optimum (visibility graph) as the last "
                    "column. The paper does not state its start and goal; the default pairs on "
                    "seed003 are this project's choice.")
    b.add_argument("--world", default="seed003", metavar="NAME|PATH.json")
    b.add_argument("--pair", nargs=2, type=point, action="append", metavar=("START", "GOAL"),
                   help="a start/goal pair X,Y X,Y (repeatable; default: the built-in pairs "
                        "for seed003)")
    b.add_argument("--runs", type=positive_int, default=10, help="PSO seeds per pair (default 10)")
    b.add_argument("--seed", type=int, default=0, help="first PSO seed (default 0)")
    _add_pso_options(b)
    b.add_argument("--json", metavar="OUT", help="write the table rows as JSON")
    b.add_argument("--plot", metavar="OUT.png", help="figure of the first pair's paths")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")
    b.set_defaults(handler=_run_bench)


def _add_pso_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("PSO", "swarm and stopping criteria (first met stops)")
    g.add_argument("--swarm", type=positive_int, default=None, help="particles (default 40)")
    g.add_argument("--iterations", type=positive_int, default=200,
                   help="at most this many iterations (default 200)")
    g.add_argument("--stall", type=positive_int, default=50,
                   help="stop after this many iterations without improvement (default 50)")
    g.add_argument("--time-limit", type=positive_float, default=None, metavar="S",
                   help="stop after S seconds")


def _load_world(spec: str) -> Any:
    from subtask_opt.planners.polygon.world import PolygonWorld

    if spec in PolygonWorld.builtin_names():
        return PolygonWorld.builtin(spec)
    if not spec.lower().endswith(".json"):
        from subtask_opt.base.errors import InputDataError

        raise InputDataError(f"--world must be one of {PolygonWorld.builtin_names()} or a "
                             f".json file, got {spec!r}")
    return PolygonWorld.from_json(spec)


def _pso_setup(args: argparse.Namespace) -> tuple[Any, list[Any]]:
    from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement
    from subtask_opt.planners.polygon.pso import PSOParams

    params = PSOParams() if args.swarm is None else PSOParams(swarm=args.swarm)
    stop: list[Any] = [MaxGenerations(args.iterations), NoImprovement(args.stall)]
    if args.time_limit is not None:
        stop.append(MaxRuntime(args.time_limit))
    return params, stop


def _check_seed(seed: int) -> None:
    if seed < 0:
        from subtask_opt.base.errors import ParameterError

        raise ParameterError(f"--seed must be >= 0, got {seed}")


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.polygon import maklink, pso, visibility

    _check_seed(args.seed)
    world = _load_world(args.world)
    start = world.check_point("start", args.start)
    goal = world.check_point("goal", args.goal)
    if args.planner == "visibility":
        result = visibility.plan(world, start, goal)
    elif args.planner in ("dijkstra", "improved"):
        params = maklink.MaklinkParams(improve=args.planner == "improved")
        result = maklink.plan(world, start, goal, params=params)
    else:
        pso_params, stop = _pso_setup(args)
        with progress_bar(not args.no_progress, total=args.iterations, desc="PSO",
                          unit="it") as bar:
            done = [0]

            def tick(progress: Any) -> None:
                bar.update(progress.generation - done[0])
                done[0] = progress.generation

            result = pso.plan(world, start, goal, params=pso_params, seed=args.seed, stop=stop,
                              on_chunk=tick)
    optimum = (result.length if args.planner == "visibility"
               else visibility.shortest_path_length(world, start, goal))
    print(f"world {world.name or args.world}: {len(world.obstacles)} obstacles, "
          f"start ({start[0]:g}, {start[1]:g}) -> goal ({goal[0]:g}, {goal[1]:g})")
    print(result.summary())
    if result.success:
        if "dijkstra_length" in result.info:
            print(f"  Dijkstra {result.info['dijkstra_length']:.4f}"
                  + (f", improved {result.info['improved_length']:.4f}"
                     if "improved_length" in result.info else ""))
        gap = 100.0 * (result.length / optimum - 1.0)
        print(f"  exact optimum {optimum:.4f} (gap {gap:.3f} %)")
    if args.json:
        payload = result.to_dict()
        payload.update(world=world.name or args.world, optimum=optimum,
                       start=start.tolist(), goal=goal.tolist())
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.planners.polygon.maklink import graph_for
        from subtask_opt.plotting import polygon as plot

        graph = graph_for(world) if args.planner != "visibility" else None
        fig = plot.figure(world, graph=graph, results={args.planner: result},
                          title=f"{world.name or args.world}: {args.planner}")
        plot.save(fig, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _run_bench(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.polygon import maklink, pso, visibility
    from subtask_opt.planners.polygon.maklink_table import SEED003_PAIRS, format_table, table_rows

    _check_seed(args.seed)
    world = _load_world(args.world)
    if args.pair:
        pairs = [(tuple(s), tuple(g)) for s, g in args.pair]
    elif world.name == "seed003":
        pairs = list(SEED003_PAIRS)
    else:
        raise InputDataError(f"world {world.name!r} has no built-in start/goal pairs; "
                             "give them with --pair X,Y X,Y")
    for k, (s, g) in enumerate(pairs):
        world.check_point(f"pair {k + 1} start", s)
        world.check_point(f"pair {k + 1} goal", g)
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

        s, g = pairs[0]
        results = {
            "Dijkstra": maklink.plan(world, s, g),
            "improved": maklink.plan(world, s, g, params=maklink.MaklinkParams(improve=True)),
            "PSO": pso.plan(world, s, g, params=params, seed=args.seed, stop=stop),
            "optimum": visibility.plan(world, s, g),
        }
        fig = plot.figure(world, graph=maklink.graph_for(world), results=results,
                          title=f"{world.name or args.world}: Table 1, first pair")
        plot.save(fig, args.plot)
        print(f"wrote {args.plot}")
    return 0

"""CLI commands for the grid planners (registered by :func:`register`).

``subtask-opt plan grid``       one path on a built-in 14x9 map or a map file
``subtask-opt bench grid``      the six-map comparison table (thesis Tables 4.2-4.7)
``subtask-opt bench movingai``  every row of a MovingAI scenario file, octile DT vs optimum
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from subtask_opt.cli._common import point, positive_int, write_json

PLANNER_NAMES = ("dt", "dt-octile", "mdt", "ga", "ga-paper", "vff", "vfh")


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan grid``, ``bench grid`` and ``bench movingai``."""
    p = plan.add_parser(
        "grid", help="plan on an occupancy grid (DT, any-angle MDT, GA, VFF, VFH)",
        description="Plan a path on an occupancy grid. Cells are (x, y) = (column, row) from "
                    "the top-left. Built-in maps carry their own start and goal.")
    p.add_argument("--map", required=True, metavar="NAME|PATH",
                   help="built-in map (open, walls, blocks, rooms, spiral, cluttered, trap) or "
                        "a .map (MovingAI), .png or ASCII text file")
    p.add_argument("--start", type=point, metavar="X,Y",
                   help="start cell (default: the built-in map's)")
    p.add_argument("--goal", type=point, metavar="X,Y",
                   help="goal cell (default: the built-in map's)")
    p.add_argument("--planner", default="mdt", metavar="NAME",
                   help=f"one of {', '.join(PLANNER_NAMES)} (default mdt)")
    p.add_argument("--seed", type=int, default=0, help="GA random seed (default 0)")
    p.add_argument("--json", metavar="OUT", help="write the result as JSON")
    p.add_argument("--plot", metavar="OUT.png", help="write a figure of the map and path")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "grid", help="six 14x9 maps: time, length and turns of DT, MDT, GA, VFF, VFH",
        description="The comparison of the thesis' Tables 4.2-4.7 on six built-in maps. "
                    "Times are after a JIT warm-up, best of --repeats runs.")
    b.add_argument("--seed", type=int, default=0, help="GA seed (default 0)")
    b.add_argument("--repeats", type=positive_int, default=3, help="timed runs (default 3)")
    b.add_argument("--json", metavar="OUT", help="write the table rows as JSON")
    b.add_argument("--plot", metavar="OUT.png", help="figure of the six maps with their paths")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")
    b.set_defaults(handler=_run_bench_grid)

    m = bench.add_parser(
        "movingai", help="octile distance transform vs a MovingAI scenario file",
        description="Answer every row of a MovingAI .scen file with the goal-rooted octile "
                    "distance transform and count rows whose length differs from the file's "
                    "optimum by more than 1e-3.")
    m.add_argument("--map", required=True, metavar="PATH", help="MovingAI .map file")
    m.add_argument("--scen", required=True, metavar="PATH", help="MovingAI .scen file")
    m.add_argument("--focused", action="store_true",
                   help="order each row's transform towards its start (A*): same values, faster")
    m.add_argument("--json", metavar="OUT", help="write rows, mismatches, max_abs_error, seconds")
    m.add_argument("--no-progress", action="store_true", help="no progress bar")
    m.set_defaults(handler=_run_bench_movingai)


def load_grid(spec: str) -> tuple[Any, tuple[int, int] | None, tuple[int, int] | None]:
    """A built-in map name or a map file -> (world, default start, default goal)."""
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.planners.grid.maps import MAP_NAMES, thesis_case
    from subtask_opt.planners.grid.world import GridWorld

    if spec in MAP_NAMES:
        case = thesis_case(spec)
        return case.world, case.start, case.goal
    path = Path(spec)
    if not path.is_file():
        raise InputDataError(
            f"--map {spec!r} is neither a built-in map ({', '.join(MAP_NAMES)}) nor a file")
    suffix = path.suffix.lower()
    if suffix == ".map":
        return GridWorld.from_movingai(path), None, None
    if suffix == ".png":
        return GridWorld.from_png(path), None, None
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputDataError(f"cannot read map {spec!r}: {exc}") from None
    return GridWorld.from_ascii(text, name=path.stem), None, None


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.planners.grid.compare import PLANNERS, plan_grid

    if args.planner not in PLANNERS:
        raise ParameterError(
            f"--planner must be one of {', '.join(PLANNER_NAMES)}, got {args.planner!r}")
    world, start, goal = load_grid(args.map)
    start = args.start if args.start is not None else start
    goal = args.goal if args.goal is not None else goal
    if start is None or goal is None:
        raise ParameterError(f"--start and --goal are required for the map file {args.map!r}")
    plan_grid(world, start, goal, args.planner, seed=args.seed)  # warm-up: JIT out of the time
    result = plan_grid(world, start, goal, args.planner, seed=args.seed)
    print(f"map {world.name or args.map} ({world.width}x{world.height}), "
          f"start {tuple(int(v) for v in start)}, goal {tuple(int(v) for v in goal)}")
    print(result.summary())
    if args.json:
        payload = result.to_dict()
        payload.pop("trajectory", None)
        payload.update({"map": world.name or args.map, "seed": args.seed})
        write_json(args.json, payload)
    if args.plot:
        from subtask_opt.plotting.grid import save_grid_plot

        save_grid_plot(args.plot, world, [result], start=start, goal=goal)
    return 0


def _run_bench_grid(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.grid.compare import TABLE_PLANNERS, compare, format_table
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    rows = []
    cases = [thesis_case(name) for name in THESIS_MAPS]
    with progress_bar(not args.no_progress, total=len(cases), desc="maps", unit="map") as bar:
        for case in cases:
            rows.extend(compare(case.world, case.start, case.goal, seed=args.seed,
                                repeats=args.repeats))
            bar.update()
    print(format_table(rows))
    if args.json:
        write_json(args.json, {"seed": args.seed, "planners": list(TABLE_PLANNERS),
                               "rows": [r.to_dict() for r in rows]})
    if args.plot:
        from subtask_opt.plotting.grid import save_comparison_figure

        save_comparison_figure(args.plot, cases, rows)
    return 0


def _run_bench_movingai(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.grid.movingai import bench, read_scenarios
    from subtask_opt.planners.grid.world import GridWorld

    world = GridWorld.from_movingai(args.map)
    scen = read_scenarios(args.scen)
    with progress_bar(not args.no_progress, total=len(scen), desc="rows", unit="row") as bar:
        state = {"done": 0}

        def advance(done: int) -> None:
            bar.update(done - state["done"])
            state["done"] = done

        report = bench(world, scen, focused=args.focused, on_field=advance)
    print(report.summary())
    if args.json:
        write_json(args.json, report.to_dict())
    return 0

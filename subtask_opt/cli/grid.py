"""CLI commands for the grid planners (registered by :func:`register`).

``subtask-opt plan grid``       one path on a built-in map or a map file
``subtask-opt bench grid``      the six-map comparison table (thesis Tables 4.2-4.7)
``subtask-opt bench movingai``  every row of a MovingAI scenario file, octile DT vs optimum

Planner names, their help and which of them take ``--seed`` / stopping
options come from the registry (``planners("grid")``). Map files are read by
:func:`subtask_opt.planners.grid.world.read_grid`, which decides the format by
content (PNG, MovingAI ``.map`` or ASCII text).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from subtask_opt.cli._common import (
    EXIT_OK,
    MAX_GENERATIONS,
    MAX_RUNTIME_S,
    MAX_STALL,
    add_no_progress,
    add_outputs,
    failed,
    float_in,
    int_in,
    output_file,
    point,
    refuse_overwriting_inputs,
    seed,
    stop_criteria,
    write_json,
)


def _planner_help() -> tuple[list[str], str]:
    from subtask_opt.planners.base import planners

    found = planners("grid")
    text = "; ".join(f"{name}: {info.description}" for name, info in found.items())
    return list(found), text


def _stochastic_names() -> str:
    from subtask_opt.planners.base import planners

    return ", ".join(n for n, i in planners("grid").items() if i.stochastic) or "none"


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan grid``, ``bench grid`` and ``bench movingai``."""
    from subtask_opt.planners.grid.maps import MAP_NAMES
    from subtask_opt.planners.grid.world import MAX_FILE_BYTES, MAX_SIDE

    names, planner_text = _planner_help()
    stochastic = _stochastic_names()
    limits = f"files up to {MAX_FILE_BYTES // 2**20} MiB and {MAX_SIDE}x{MAX_SIDE} cells"
    p = plan.add_parser(
        "grid", help="plan on an occupancy grid (distance transforms, MDT, GA, VFF, VFH)",
        description="Plan a path on an occupancy grid. Cells are (x, y) = (column, row) from "
                    "the top-left. Built-in maps carry their own start and goal. Exit 1 when "
                    "the planner ran and found no path (no path, stall, collision, timeout).")
    p.add_argument("--map", required=True, metavar="NAME|PATH",
                   help=f"built-in map ({', '.join(MAP_NAMES)}) or a map file: PNG, MovingAI "
                        f".map or ASCII text, told apart by content ({limits})")
    p.add_argument("--start", type=point, metavar="X,Y",
                   help="start cell (default: the built-in map's)")
    p.add_argument("--goal", type=point, metavar="X,Y",
                   help="goal cell (default: the built-in map's)")
    p.add_argument("--planner", default="mdt", choices=names, metavar="NAME",
                   help=f"{planner_text} (default mdt)")
    p.add_argument("--seed", type=seed, default=None,
                   help=f"random seed of the stochastic planners ({stochastic}; default 0); "
                        "the others are deterministic and ignore it")
    _add_stop_options(p)
    add_outputs(p, what="the result (with the distance field for the transforms)",
                plot="a figure of the map and the path")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "grid", help="six 14x9 maps: time, length and turns of every grid planner",
        description="The comparison of the thesis' Tables 4.2-4.7 on six built-in maps. "
                    "Times are after a JIT warm-up, best of --repeats runs.")
    b.add_argument("--seed", type=seed, default=0,
                   help=f"seed of the stochastic planners ({stochastic}; default 0)")
    b.add_argument("--repeats", type=int_in(1, 1000), default=3, metavar="N",
                   help="timed runs, N in [1, 1000] (default 3)")
    add_outputs(b, what="the table rows", plot="a figure of the six maps with their paths")
    add_no_progress(b)
    b.set_defaults(handler=_run_bench_grid)

    m = bench.add_parser(
        "movingai", help="octile distance transform vs a MovingAI scenario file",
        description="Answer every row of a MovingAI .scen file with the goal-rooted octile "
                    "distance transform and count rows whose length differs from the file's "
                    "optimum by more than 1e-3. Exit 1 when any row mismatches.")
    m.add_argument("--map", required=True, metavar="PATH",
                   help=f"MovingAI map file (or any grid file read_grid reads; {limits})")
    m.add_argument("--scen", required=True, metavar="PATH", help="MovingAI .scen file")
    m.add_argument("--focused", action="store_true",
                   help="order each row's transform towards its start (A*): same values, faster")
    add_outputs(m, what="rows, mismatches, max_abs_error, seconds",
                plot="a figure: the map with the longest queries, and ours vs optimal")
    add_no_progress(m)
    m.set_defaults(handler=_run_bench_movingai)


def _add_stop_options(p: argparse.ArgumentParser) -> None:
    from subtask_opt.planners.base import planners

    iterative = ", ".join(n for n, i in planners("grid").items() if i.iterative) or "none"
    g = p.add_argument_group(
        "stopping", f"for the iterative planners ({iterative}); the first criterion met stops "
                    "the run; none given: the planner's default")
    # the shared criteria (stop_criteria) under this command's option names
    g.add_argument("--generations", dest="max_generations", type=int_in(1, MAX_GENERATIONS),
                   default=None, help=f"at most this many generations (<= {MAX_GENERATIONS})")
    g.add_argument("--stall", dest="no_improvement", type=int_in(1, MAX_STALL), default=None,
                   help=f"stop after this many generations without improvement (<= {MAX_STALL})")
    g.add_argument("--time-limit", dest="max_runtime",
                   type=float_in(0.0, MAX_RUNTIME_S, open_low=True), default=None, metavar="S",
                   help="stop after S seconds")


def load_grid(spec: str) -> tuple[Any, tuple[int, int] | None, tuple[int, int] | None, int]:
    """A built-in map name or a map file -> (world, default start, default goal, border)."""
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.planners.grid.maps import MAP_NAMES, thesis_case
    from subtask_opt.planners.grid.world import read_grid

    if spec in MAP_NAMES:
        case = thesis_case(spec)
        return case.world, case.start, case.goal, case.border
    path = Path(spec)
    if not path.is_file():
        raise InputDataError(
            f"--map {spec!r} is neither a built-in map ({', '.join(MAP_NAMES)}) nor a file")
    return read_grid(path), None, None, 0


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.planners.grid.compare import plan_report

    refuse_overwriting_inputs([args.map], [args.json, args.plot])
    world, start, goal, border = load_grid(args.map)
    start = args.start if args.start is not None else start
    goal = args.goal if args.goal is not None else goal
    if start is None or goal is None:
        raise ParameterError(f"--start and --goal are required for the map file {args.map!r}")
    report = plan_report(world, start, goal, args.planner, seed=args.seed, stop=stop_criteria(args),
                         border=border)
    print(f"map {world.name or args.map} ({world.width}x{world.height}), "
          f"start {report.start}, goal {report.goal}")
    print(report.result.summary())
    if args.json:
        write_json(args.json, report.to_dict())
    if args.plot:
        from subtask_opt.plotting.grid import save_grid_plot

        with output_file(args.plot) as tmp:
            save_grid_plot(tmp, world, [report.result], start=report.start,
                           goal=report.goal,
                           title=f"{world.name or Path(args.map).name}: {args.planner}")
    if not report.result.success:
        return failed(f"{report.result.outcome}: {report.result.message}")
    return EXIT_OK


def _run_bench_grid(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.grid.compare import compare, format_table, planner_names
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    refuse_overwriting_inputs([], [args.json, args.plot])
    rows = []
    cases = [thesis_case(name) for name in THESIS_MAPS]
    with progress_bar(not args.no_progress, total=len(cases), desc="maps", unit="map") as bar:
        for case in cases:
            rows.extend(compare(case.world, case.start, case.goal, seed=args.seed,
                                repeats=args.repeats))
            bar.update()
    print(format_table(rows))
    if args.json:
        write_json(args.json, {"seed": args.seed, "planners": list(planner_names()),
                               "rows": [r.to_dict() for r in rows]})
    if args.plot:
        from subtask_opt.plotting.grid import save_comparison_figure

        with output_file(args.plot) as tmp:
            save_comparison_figure(tmp, cases, rows)
    return EXIT_OK


def _run_bench_movingai(args: argparse.Namespace) -> int:
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.planners.grid.movingai import bench, read_scenarios
    from subtask_opt.planners.grid.world import read_grid

    refuse_overwriting_inputs([args.map, args.scen], [args.json, args.plot])
    world = read_grid(args.map)
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
    if args.plot:
        from subtask_opt.plotting.grid import save_movingai_figure

        with output_file(args.plot) as tmp:
            save_movingai_figure(tmp, world, scen, report)
    if report.mismatches:
        return failed(f"{report.mismatches} rows differ from the scenario file's optimum")
    return EXIT_OK
